"""No-path proofs near one end: the free component of the start (or goal) walled off by
verified FULL cells inside a box around it, for problems whose C-space over the whole
bounds is out of reach.

Large triangle soups (OMPL.app's spirelli held at one orientation: 3.8k × 11.4k triangles
of surfaces) take minutes for the octree over the bounds, and its channel refinement does
not converge; but a robot in a pocket is walled off by the C-obstacle cells near it.
:func:`prove_end_enclosed`:

1. a coarse FCL flood fill from the end (grid step the bounds' diagonal over
   :data:`FLOOD_DIVISIONS`, at most :data:`FLOOD_MAX_NODES` free nodes, stopped at the
   deadline) — a heuristic that only chooses the box: it must close without reaching the
   other end;
2. the box is the flood's extent grown by :data:`MARGIN_STEPS` grid steps (clipped to the
   bounds), and the C-space is built over it alone — for slabs of the robot first
   (:mod:`.slabs`: walled off for a slab is walled off for the robot, at a fraction of the
   triangle pairs), then for the whole robot;
3. :func:`wall_off`: the end's component of EMPTY and MIXED leaves is refined, level by
   level, where its MIXED leaves lie inside the C-obstacle (their centres), until every
   FULL leaf around it is verified by the core and none is a wall of the box that is not a
   face of the bounds. Then no path leaves the component, whatever lies outside the box:
   no path (exact on the exact source). Otherwise nothing is claimed and the planner
   searches the whole bounds as before — unless the time limit went on the proofs (the
   native builds and refinements stop at it, :mod:`planner.deadline`), or a step of them
   was not started because it would have ended after it (then the answer is
   ``not_found``, ``time_limit``) or the proof ran out of memory
   (:class:`~planner.errors.ResourceLimitError`, raised). Then the pocket's walls need
   finer cells than the limit allows; a path out of the pocket would pass a gap narrower
   than the flood's step, which the C-space over the whole bounds would have to resolve
   with cells as fine, so it is not tried.

What each end's proof tried (the flood, each robot subset, and how it ended) goes into
``report.json`` (``local_proof.attempts``). The assembly planner's enclosures
(:mod:`planner.assembly.enclosure`) use :func:`wall_off` too.
"""

from __future__ import annotations

import collections
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.deadline import Deadline
from planner.errors import ResourceLimitError, TimeLimitError
from planner.problem import Scenario
from planner.sources import Source
from planner.validation import FclChecker

from .slabs import subsets

__all__ = ["FLOOD_DIVISIONS", "FLOOD_MAX_NODES", "MARGIN_STEPS",
           "LocalProof", "leaf_boxes", "prove_end_enclosed", "surface_pairs",
           "wall_off"]

log = logging.getLogger(__name__)

FLOOD_DIVISIONS = 128
"""The flood's grid step is the bounds' diagonal over this."""

FLOOD_MAX_NODES = 20_000
"""A flood that finds more free nodes than this is taken as not closed."""

FLOOD_CHECK_EVERY = 16
"""The flood asks the deadline once per this many nodes tested."""

MARGIN_STEPS = 4
"""The box is the flood's extent grown by this many grid steps on every side (the walls
around a pocket need room inside the box)."""

COARSE_DIVISIONS = 16
"""The box's first cells are its largest side over this."""

FLOOR_DIVISIONS = 1024
"""The finest cells are the box's largest side over this."""

MAX_ROUNDS = 8
"""Refinement rounds at most (each splits the selected MIXED leaves once)."""

_MIXED = 2
_STEPS = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))


@dataclass
class LocalProof:
    """A proved enclosure of one end: its C-space (over the box ``summary["box"]``), the
    core's certificate (``raw``, as :meth:`CSpace.enclosure` gives it) and a summary for
    ``report.json``."""

    which: str
    cspace: Any
    raw: dict[str, Any]
    summary: dict[str, Any]


def surface_pairs(scenario: Scenario) -> int:
    """Triangle pairs of the robot against obstacles where one of the two is a surface
    (every pair is a boundary candidate: the expensive kind)."""
    robot = scenario.robot
    return sum(len(o.mesh.faces) * len(robot.mesh.faces) for o in scenario.obstacles
               if not (o.solid and robot.solid))


def prove_end_enclosed(scenario: Scenario, source: Source, checker: FclChecker,
                       which: str, *, deadline: Deadline,
                       attempts: list[dict[str, Any]] | None = None) -> LocalProof | None:
    """A proof that the ``which`` end (``"start"`` or ``"goal"``) is walled off near it,
    or ``None`` (see the module documentation); ``deadline.reached`` tells whether the
    time limit stopped it. What was tried, and how it ended, is appended to ``attempts``
    (for ``report.json``): one entry per robot subset, or one for the flood.

    Raises:
        ResourceLimitError: the box's C-space or its refinement would pass the memory
            limit.
    """
    t0 = time.perf_counter()
    tried = attempts if attempts is not None else []
    lo, hi = (np.asarray(b, dtype=np.float64) for b in scenario.bounds)
    ends = {"start": np.asarray(scenario.start, float), "goal": np.asarray(scenario.goal, float)}
    point, other = ends[which], ends[_other(which)]
    step = float(np.linalg.norm(hi - lo)) / FLOOD_DIVISIONS
    extent = _flood(checker, point, other, lo, hi, step, deadline)
    if extent is None:
        why = "stopped by the time limit" if deadline.reached else "did not close"
        tried.append(_attempt(which, None, None, f"the flood fill {why}", t0))
        return None
    box = np.stack([np.maximum(point + (extent[0] - MARGIN_STEPS) * step, lo),
                    np.minimum(point + (extent[1] + MARGIN_STEPS) * step, hi)])
    if np.all((box[0] <= other) & (other <= box[1])):
        # not a pocket of one end
        tried.append(_attempt(which, box, None, f"the {_other(which)} lies in the box", t0))
        return None
    bounds_faces = [bool(box[0][s // 2] <= lo[s // 2]) if s % 2 == 0 else
                    bool(box[1][s // 2] >= hi[s // 2]) for s in range(6)]
    side = float(np.max(box[1] - box[0]))
    order = list(subsets(scenario.robot))
    for label, robot in order:
        t_subset = time.perf_counter()
        subset = {"subset": label, "triangles": len(robot.mesh.faces)}
        if deadline.would_pass(deadline.cspace_pace * len(robot.mesh.faces)):
            tried.append(_attempt(which, box, subset, "not started: its C-space would end "
                                                      "after the time limit", t_subset))
            break
        whole = robot is scenario.robot
        reached_before, deadline.reached = deadline.reached, False
        try:
            with deadline.native():
                cs = source.cspace(scenario.obstacles, robot, box, side / FLOOR_DIVISIONS,
                                   side / COARSE_DIVISIONS)
                deadline.cspace_pace = ((time.perf_counter() - t_subset)
                                        / max(len(robot.mesh.faces), 1))
                raw, rounds = wall_off(cs, point, bounds_faces=bounds_faces,
                                       deadline=deadline, select=inside_obstacles)
        except ResourceLimitError:
            deadline.reached |= reached_before
            tried.append(_attempt(which, box, subset, "over the memory limit", t_subset))
            if whole and label == order[-1][0]:
                raise  # nothing smaller is left to try
            continue
        except TimeLimitError:
            deadline.reached = True
            tried.append(_attempt(which, box, subset, "stopped by the time limit", t_subset))
            break
        outcome = _outcome(raw is not None, rounds, deadline.reached)
        deadline.reached |= reached_before
        tried.append(_attempt(which, box, subset, outcome, t_subset, rounds=rounds))
        if raw is not None:
            summary = {"end": which, "box": box.tolist(), "flood_step": step,
                       "bounds_faces": [f"{'-+'[side % 2]}{'xyz'[side // 2]}"
                                        for side in range(6) if bounds_faces[side]],
                       "rounds": rounds, "robot": subset,
                       "seconds": time.perf_counter() - t0}
            return LocalProof(which, cs, raw, summary)
    return None


def _outcome(proved: bool, rounds: int, out_of_time: bool) -> str:
    """How one robot subset's proof ended, in words (for ``report.json``)."""
    if proved:
        return "proved"
    if out_of_time:
        return "not walled off: its next refinement round would end after the time limit"
    if rounds >= MAX_ROUNDS:
        return f"not walled off within {MAX_ROUNDS} refinement rounds"
    return "not walled off: nothing left to refine"


def _other(which: str) -> str:
    return "goal" if which == "start" else "start"


def _attempt(which: str, box: np.ndarray | None, subset: dict[str, Any] | None,
             outcome: str, t0: float, *, rounds: int | None = None) -> dict[str, Any]:
    """One entry of a local proof's attempts (logged as it is made)."""
    seconds = time.perf_counter() - t0
    entry: dict[str, Any] = {"end": which, "outcome": outcome, "seconds": seconds}
    if box is not None:
        entry["box"] = box.tolist()
    if subset is not None:
        entry["robot"] = subset
    if rounds is not None:
        entry["rounds"] = rounds
    log.info("local proof at the %s%s%s: %s%s in %.2f s", which,
             "" if box is None else f" (box {np.round(box, 4).tolist()})",
             "" if subset is None else f", {subset['subset']} ({subset['triangles']} "
                                       "triangles)",
             outcome, "" if rounds is None else f" after {rounds} rounds", seconds)
    return entry


def _flood(checker: FclChecker, point: np.ndarray, other: np.ndarray, lo: np.ndarray,
           hi: np.ndarray, step: float, deadline: Deadline) -> np.ndarray | None:
    """The grid extent ``[min, max]`` (in steps from ``point``) of the free nodes a flood
    fill from ``point`` reaches, or ``None`` when it does not close within
    :data:`FLOOD_MAX_NODES`, reaches the node next to ``other``, ``point`` is not free, or
    the deadline passes (asked every :data:`FLOOD_CHECK_EVERY` nodes: an FCL test of a
    large soup can take tens of milliseconds)."""
    target = tuple(int(v) for v in np.round((other - point) / step))
    seen = {(0, 0, 0)}
    queue = collections.deque([(0, 0, 0)])
    low, high = np.zeros(3), np.zeros(3)
    free = 0
    tested = 0
    while queue:
        tested += 1
        if tested % FLOOD_CHECK_EVERY == 0 and deadline.would_pass():
            return None
        node = queue.popleft()
        p = point + step * np.asarray(node, dtype=np.float64)
        if np.any(p < lo) or np.any(p > hi) or checker.collides(p):
            if node == (0, 0, 0):
                return None
            continue
        free += 1
        near_other = max(abs(a - b) for a, b in zip(node, target, strict=True)) <= 1
        if free > FLOOD_MAX_NODES or near_other:
            return None
        low, high = np.minimum(low, node), np.maximum(high, node)
        for d in _STEPS:
            n = (node[0] + d[0], node[1] + d[1], node[2] + d[2])
            if n not in seen:
                seen.add(n)
                queue.append(n)
    return np.stack([low, high])


def inside_obstacles(cs, leaves: dict[str, np.ndarray], members: np.ndarray) -> list[int]:
    """The component's MIXED leaves whose centres lie in the C-obstacle (where the walls
    leak: refining the free side's boundary leaves would only multiply them)."""
    mixed = members[leaves["label"][members] == _MIXED]
    if not len(mixed):
        return []
    lo, hi = leaf_boxes(cs, leaves, mixed)
    return [int(i) for i in mixed[np.asarray(cs.contains((lo + hi) / 2), dtype=bool)]]


def leaf_boxes(cs, leaves: dict[str, np.ndarray], ids: np.ndarray) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """The boxes ``(lo, hi)`` of the leaves ``ids`` (rows of ``cs.leaves()``)."""
    lo = np.asarray(cs.origin) + leaves["ijk"][ids] * cs.floor
    return lo, lo + (cs.floor * 2.0 ** leaves["level"][ids].astype(np.float64))[:, None]


def wall_off(cs, point: np.ndarray, *, bounds_faces: list[bool], deadline: float | Deadline,
             select: Callable[[Any, dict[str, np.ndarray], np.ndarray], list[int]],
             max_rounds: int = MAX_ROUNDS) -> tuple[dict[str, Any] | None, int]:
    """Refine the component of ``point`` (the leaves ``select`` picks, once per round)
    until it is walled off by verified FULL leaves, none a wall of the C-space's box
    except on a side in ``bounds_faces`` (``2 · axis + upper``: a face of the problem's
    own bounds). ``(certificate, rounds)``; the certificate is ``None`` when that did not
    happen within ``max_rounds`` or the deadline (a round is not started when the last
    one's seconds per refined leaf say it would end after the deadline).

    Raises:
        ResourceLimitError: a refinement would pass the memory limit.
    """
    clock = deadline if isinstance(deadline, Deadline) else Deadline(deadline)
    rounds = 0
    per_leaf = 0.0  # seconds per refined leaf in the last round
    while True:
        raw = cs.enclosure(point.tolist())
        if raw is None:  # the point's leaf is FULL: not free after all
            return None, rounds
        prims = np.asarray(raw["wall_prims"], dtype=np.int64)
        sides = prims[prims >= cs.n_obstacle_prims] - cs.n_obstacle_prims
        artificial = sum(not bounds_faces[int(s)] for s in sides)
        if raw["verified"] and artificial == 0 and len(prims):
            return raw, rounds
        log.debug("wall_off round %d: %d walls on the box's own sides, verified %s", rounds,
                  artificial, raw["verified"])
        members = np.asarray(raw["component_leaves"], dtype=np.int64)
        chosen = select(cs, cs.leaves(), members)
        if not chosen or rounds >= max_rounds:
            return None, rounds
        if clock.would_pass(per_leaf * len(chosen)):
            log.debug("wall_off round %d: refining %d leaves would pass the deadline",
                      rounds, len(chosen))
            return None, rounds
        t_round = time.perf_counter()
        stats = cs.refine(chosen, ring=False, levels=1)
        if stats["refined"] == 0:
            return None, rounds
        per_leaf = (time.perf_counter() - t_round) / len(chosen)
        rounds += 1
