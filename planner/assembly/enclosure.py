"""A local proof that a part cannot leave: the free component of its start, walled off
by verified FULL cells of the C-obstacles inside a small box around the start.

Entry point: :func:`prove_enclosed`. The planner (:func:`planner.planning.plan`) proves a
part stuck by walling off its start from a goal outside the exit box, which means
resolving the C-obstacles over the whole exit box; a nut on a bolt moves within a
fraction of a millimetre, and that octree does not finish. Here the octree covers only
``start ± r`` (``r`` from :data:`HALF_SIZES_REL`, smallest first): the start's component
of EMPTY and MIXED cells is refined (its MIXED cells split, level by level) until every
FULL cell around it is verified inside an obstacle's C-obstacle and none is a wall
outside the box (:meth:`CSpace.enclosure`). Then no path leaves the component, whatever
lies beyond the box: the part cannot leave. When the component reaches the box, a larger
box is tried; after the largest, nothing is claimed (the planner decides).

Slabs of the part first (:mod:`planner.planning.slabs`): a component walled off for a
slab of the part's triangles is walled off for the part, and a slab makes far fewer
triangle pairs (a nut's thread turn against the bolt, not all of them); the whole part is
tried last.

A start in tolerated contact (an assembled pose inside the contact or interference
tolerance) is first stepped out: the shortest straight step found to a free pose no
farther than the tolerance (every pose on that step is within the tolerance of a free
one, so the step is valid at it). The proof then speaks of that free pose's component.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from planner.deadline import native_deadline
from planner.errors import ResourceLimitError, TimeLimitError
from planner.planning.local_proof import leaf_boxes, wall_off
from planner.planning.slabs import subsets
from planner.problem import Part
from planner.sources import ExactSource, Source
from planner.validation import FclChecker

__all__ = ["HALF_SIZES_REL", "prove_enclosed"]

log = logging.getLogger(__name__)

HALF_SIZES_REL = (1.0 / 128.0, 1.0 / 32.0)
"""Half-sizes of the boxes tried, as fractions of the assembly's diagonal."""

COARSE_DIVISIONS = 16
"""The box's first cells are its side over this."""

FLOOR_DIVISIONS = 1024
"""The finest cells are the box's side over this."""

ESCAPE_STEPS = 32
"""A start in tolerated contact looks for a free pose at this many lengths up to the
tolerance."""

MAX_ROUNDS = 2
"""Refinement rounds per box (each splits the component's MIXED cells once)."""

_MIXED = 2


def prove_enclosed(source: Source, part: Part, obstacles: list[Part], *, delta: float,
                   diagonal: float, deadline: float,
                   min_half: float = 0.0) -> dict[str, Any] | None:
    """A proof that ``part`` (at translation ``0``) cannot leave ``obstacles``, or
    ``None``: ``{"start", "half_size", "component_cells", "wall_cells",
    "wall_cells_by_obstacle", "floor", "rounds", "exact", "seconds", "claim"}`` (``claim``:
    what is proved, in words: motions that meet no obstacle, from a free start).

    Args:
        source: the C-obstacle source (the proof speaks of its C-obstacles: exact for the
            exact source).
        delta: the contact (plus interference) tolerance of a start in contact.
        diagonal: the assembly's diagonal (box sizes are fractions of it).
        deadline: ``time.perf_counter()`` value after which no box is started or
            refined further.
        min_half: boxes of this half-size or less are not tried (the part is known to
            move that far, e.g. along a free straight line).
    """
    t0 = time.perf_counter()
    checker = FclChecker.for_parts(part, obstacles, contact_tolerance=delta)
    start = _free_start(checker, delta)
    if start is None:
        return None
    for rel in HALF_SIZES_REL:
        half = rel * diagonal
        if half <= min_half:
            continue
        for subset, robot in subsets(part):
            if time.perf_counter() > deadline:
                return None
            t_subset = time.perf_counter()
            on = source if robot is part else _exact(source)
            proof = _enclosed_in_box(on, robot, obstacles, start, half, deadline)
            log.info("enclosure box %.3g, %s (%d triangles): %s in %.2f s", half, subset,
                     len(robot.mesh.faces),
                     "proved" if proof else "not proved", time.perf_counter() - t_subset)
            if proof is not None:
                proof.update(start=start.tolist(), half_size=half, subset=subset,
                             exact=on.exact, seconds=time.perf_counter() - t0,
                             claim=_claim(start, delta))
                return proof
    return None


def _claim(start: np.ndarray, delta: float) -> str:
    """What the proof proves, in words (for the answer's JSON)."""
    moved = float(np.linalg.norm(start))
    origin = ("the assembled pose" if moved == 0.0 else
              f"a free pose {moved:.3g} from the assembled one (within the tolerance "
              f"{delta:.3g})")
    return (f"no translation from {origin} leaves the proof's box without its part "
            "meeting an obstacle (exact C-obstacles: no penetration on the way); motions "
            "that penetrate by up to the tolerance while moving are not covered")


def _exact(source: Source) -> Source:
    """The source a slab (a surface) is proved on: ``source`` when it is the exact
    source, else an exact source beside it (a decomposition cannot take a surface)."""
    if source.kind == ExactSource.kind:
        return source
    return ExactSource(source.settings, "enclosure of a slab (a surface)")


def _free_start(checker: FclChecker, delta: float) -> np.ndarray | None:
    """``0`` when free, else the nearest free pose found within ``delta`` of it (lengths
    ``delta * k / ESCAPE_STEPS``, shortest first, along the axes, then cube-edge and
    -corner directions). Every pose on the straight step to a free ``q`` with
    ``|q| <= delta`` is within ``delta`` of ``q``, so its penetration depth is at most
    ``delta``: the step is valid at the tolerance."""
    origin = np.zeros(3)
    if not checker.collides(origin):
        return origin
    axes = [s * e for e in np.eye(3) for s in (1.0, -1.0)]
    fan = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)
                    if abs(x) + abs(y) + abs(z) > 1], dtype=np.float64)
    directions = axes + list(fan / np.linalg.norm(fan, axis=1)[:, None])
    for k in range(1, ESCAPE_STEPS + 1):
        for d in directions:
            q = (delta * k / ESCAPE_STEPS) * d
            if not checker.collides(q):
                return q
    return None


def _enclosed_in_box(source: Source, part: Part, obstacles: list[Part], start: np.ndarray,
                     half: float, deadline: float) -> dict[str, Any] | None:
    """Refine the start's component in the box ``start ± half`` until it is walled off
    inside the box (the proof) or cannot be (``None``)."""
    bounds = np.stack([start - half, start + half])
    side = 2.0 * half
    def mixed_inside_box(cs, leaves, members):
        inside = _inside_box(cs, leaves, members, bounds)
        return [int(i) for i in members[inside & (leaves["label"][members] == _MIXED)]]

    try:
        with native_deadline(deadline):  # the core's builds stop at it too
            cs = source.cspace(obstacles, part, bounds, side / FLOOR_DIVISIONS,
                               side / COARSE_DIVISIONS)
            enclosure, rounds = wall_off(cs, start, bounds_faces=[False] * 6,
                                         deadline=deadline, select=mixed_inside_box,
                                         max_rounds=MAX_ROUNDS)
    except (ResourceLimitError, TimeLimitError) as error:
        log.info("enclosure box %.3g: %s", half, error)
        return None
    if enclosure is None:
        log.info("enclosure box %.3g: the start's component is not walled off in it after "
                 "%d rounds", half, rounds)
        return None
    prims = np.asarray(enclosure["wall_prims"], dtype=np.int64)
    owners = [obstacles[int(k)].name for k in source.owners(obstacles, part)]
    return _proof(cs, enclosure, prims, owners, rounds)


def _inside_box(cs, leaves: dict[str, np.ndarray], members: np.ndarray,
                bounds: np.ndarray) -> np.ndarray:
    """Which of the leaves ``members`` lie inside the box (the others straddle it: MIXED
    for the walls outside it, which no refinement removes)."""
    lo, hi = leaf_boxes(cs, leaves, members)
    return np.all(lo >= bounds[0], axis=1) & np.all(hi <= bounds[1], axis=1)


def _proof(cs, enclosure: dict[str, Any], prims: np.ndarray, owners: list[str],
           rounds: int) -> dict[str, Any]:
    """The proof's summary: the component and its wall cells, by obstacle."""
    by_obstacle: dict[str, int] = {}
    for prim in prims:
        by_obstacle[owners[int(prim)]] = by_obstacle.get(owners[int(prim)], 0) + 1
    return {"component_cells": len(enclosure["component_leaves"]),
            "wall_cells": int(len(prims)), "wall_cells_by_obstacle": by_obstacle,
            "floor": cs.floor, "rounds": rounds}
