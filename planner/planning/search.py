"""The search of the octree planner: refinement rounds until a free path, a certificate,
the floor or a limit.

Each round: A* through EMPTY leaves (face-adjacent leaves joined through the centre of
their shared face: every segment lies in one closed EMPTY leaf, so the path is exactly
free). If there is none, A* finds the cheapest channel of EMPTY and MIXED leaves (MIXED
ones cost more) and its MIXED leaves (and their MIXED neighbours) are split. When no
channel avoids MIXED leaves at the floor: if start and goal lie in different components of
the EMPTY ∪ MIXED leaves, the core's certificate proves that no path exists, once each of
its FULL wall leaves has been re-verified; otherwise "not found down to the floor".
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner import budget
from planner.errors import ResourceLimitError, TimeLimitError
from planner.progress import StatusLine
from planner.roles import FOUND, NO_PATH, NOT_FOUND, PlanStatus

from .report import Clock

__all__ = ["SearchResult", "SearchRun", "search", "search_without_margin"]

log = logging.getLogger(__name__)


@dataclass
class SearchResult:
    """What the rounds ended with.

    Attributes:
        status, reason, message: as in :class:`~planner.planning.outcome.PlanOutcome`.
        waypoints: ``(n, 3)`` roadmap path when found.
        min_leaf_size: smallest leaf the path crosses (``inf`` for the straight segment).
        certificate: the core's certificate dict for a no-path.
    """

    status: PlanStatus
    reason: str
    message: str
    waypoints: np.ndarray | None = None
    min_leaf_size: float = float("nan")
    certificate: dict[str, Any] | None = None


@dataclass
class SearchRun:
    """What the rounds of one plan share.

    Attributes:
        params: the :class:`~planner.planning.octree_planner.OctreeParams`.
        clock: seconds per stage.
        rounds: each refinement is recorded here.
        deadline: ``time.perf_counter()`` value at which the rounds stop.
        progress: the status line.
    """

    params: Any
    clock: Clock
    rounds: list[dict]
    deadline: float
    progress: StatusLine


def search(cs, start: np.ndarray, goal: np.ndarray, run: SearchRun) -> SearchResult:
    """Refinement rounds on the native C-space ``cs``."""
    params, clock = run.params, run.clock
    s, g = start.tolist(), goal.tolist()
    if cs.segment_is_free(s, g):
        return SearchResult(FOUND, "path", "the straight segment is free",
                            waypoints=np.array([s, g]), min_leaf_size=float("inf"))
    for index in range(params.max_rounds + 1):
        with clock.stage("search"):
            path = cs.free_path(s, g, rings=params.attach_rings)
        if path is not None:
            return SearchResult(FOUND, "path", f"roadmap path after {index} refinement rounds",
                                waypoints=np.asarray(path["waypoints"]),
                                min_leaf_size=float(path["min_leaf_size"]))
        with clock.stage("search"):
            channel = cs.channel(s, g, penalty=params.mixed_penalty, refinable_only=True)
        if channel is None:
            return _at_the_floor(cs, s, g, clock)
        if index == params.max_rounds:
            break
        if time.perf_counter() > run.deadline:
            return SearchResult(NOT_FOUND, "time_limit",
                                f"time limit reached after {index} refinement rounds")
        stopped = _refine(cs, channel, run, index)
        if stopped is not None:
            return stopped
    return SearchResult(NOT_FOUND, "rounds", f"{params.max_rounds} refinement rounds used up")


def _refine(cs, channel: dict, run: SearchRun, index: int) -> SearchResult | None:
    """Split the channel's MIXED leaves; a result when that cannot go on."""
    try:
        with run.clock.stage("refine"):
            stats = cs.refine(channel["leaves"], ring=run.params.ring,
                              levels=run.params.refine_levels)
    except ResourceLimitError as exc:
        refused = budget.explain(exc, cell_bytes=budget.LEAF_BYTES,
                                 cells_given=run.params.leaves_setting)
        return SearchResult(NOT_FOUND, "budget", f"octree budget exhausted: {refused}")
    if stats["refined"] == 0:
        return SearchResult(
            NOT_FOUND, "floor",
            f"no path found down to the floor cell size {cs.floor:.3g}: the start or goal "
            f"cannot be attached to the roadmap")
    run.rounds.append({
        "round": index + 1,
        "channel_leaves": len(channel["leaves"]),
        "channel_min_cell": channel["min_leaf_size"],
        "refined": stats["refined"],
        "created": stats["created"],
        "leaves": len(cs),
    })
    run.progress.show(f"minkplan: round {index + 1}: {len(cs)} cells, channel of "
                  f"{len(channel['leaves'])} cells down to {channel['min_leaf_size']:.3g}")
    return None


def _at_the_floor(cs, s: list[float], g: list[float], clock: Clock) -> SearchResult:
    """No channel avoids MIXED leaves at the floor: a verified certificate, or nothing."""
    with clock.stage("certificate"):
        certificate = cs.certificate(s, g)
    if certificate is None:
        return SearchResult(
            NOT_FOUND, "floor",
            f"no path found down to the floor cell size {cs.floor:.3g}: every channel from "
            f"start to goal crosses MIXED cells at the floor")
    if not certificate["verified"]:
        walls = np.asarray(certificate["wall_prims"])
        unverified = int((walls < 0).sum())
        log.warning("a no-path certificate did not pass re-verification: %d of %d wall cells "
                    "could not be shown blocked", unverified, len(walls))
        return SearchResult(
            NOT_FOUND, "certificate_unverified",
            f"start and goal lie in different components of the EMPTY and MIXED cells, but "
            f"{unverified} of the {len(walls)} FULL cells walling them apart could not be "
            f"re-verified as blocked; no proof is claimed")
    return SearchResult(NO_PATH, "certificate", "start and goal lie in different components "
                        "of the EMPTY and MIXED cells", certificate=certificate)


def search_without_margin(build: Callable[[float], Any], first: SearchResult, margin: float,
                          ends: dict[str, np.ndarray], run: SearchRun
                          ) -> tuple[SearchResult, Any]:
    """A no-path found with the clearance margin must speak of the obstacles themselves:
    search again on the C-space without it (``build(0.0)``). Returns the result and the
    C-space it is about (``None``: the first one)."""
    if first.status != NO_PATH or margin <= 0:
        return first, None
    if time.perf_counter() > run.deadline:  # the second C-space would run past the limit
        return SearchResult(
            NOT_FOUND, "time_limit",
            f"time limit reached: no path keeps the clearance margin {margin:.4g}, and "
            f"there was no time left to search without it"), None
    log.info("no path with margin %.3g; checking without the margin", margin)
    try:
        space = build(0.0)
        second = search(space, ends["start"], ends["goal"], run)
    except TimeLimitError:
        return SearchResult(
            NOT_FOUND, "time_limit",
            f"time limit reached: no path keeps the clearance margin {margin:.4g}, and "
            f"the search without it did not end in time"), None
    if second.status == FOUND:
        return SearchResult(
            NOT_FOUND, "clearance",
            f"no path keeps the clearance margin {margin:.4g}; paths with less exist"), space
    return second, space
