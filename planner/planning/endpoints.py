"""Start and goal: attached to the roadmap, stepped out of a tolerated contact, or
reported in collision (which obstacle, how deep) with no search."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.validation import FclChecker

__all__ = ["Ends", "attach_ends", "collision_report", "escape"]

ESCAPE_FRACTIONS = (0.05, 0.1, 0.25, 0.5, 1.0)
"""Lengths of the escapes tried, as fractions of the reach."""


@dataclass
class Ends:
    """Where the search starts and ends.

    Attributes:
        points: ``{"start": (3,), "goal": (3,)}``, moved out of a tolerated contact.
        escapes: ``{which: {"from", "to"}}`` for each point that was moved.
        blocked: ``(which, collision report, in_margin)`` when one cannot be used.
    """

    points: dict[str, np.ndarray]
    escapes: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    blocked: tuple[str, dict[str, Any], bool] | None = None


def attach_ends(cs, checker: FclChecker, start: np.ndarray, goal: np.ndarray, reach: float,
                obstacle_of: Callable[[int], str]) -> Ends:
    """Each end outside the C-obstacles as it is; inside one but valid for FCL (tolerated
    contact, or within the margin) moved out by a short escape FCL accepts; else
    blocked, with the collision report."""
    ends = Ends({"start": start, "goal": goal})
    for which, p in (("start", start), ("goal", goal)):
        if not cs.contains(p[None, :])[0]:
            continue
        valid = checker.is_valid(p)
        escaped = escape(cs, checker, p, reach) if valid else None
        if escaped is None:
            ends.blocked = (which, collision_report(cs, checker, p, which, obstacle_of), valid)
            return ends
        ends.points[which] = escaped
        ends.escapes[which] = {"from": p.tolist(), "to": escaped.tolist()}
    return ends


def collision_report(cs, checker: FclChecker, p: np.ndarray, which: str,
                     obstacle_of: Callable[[int], str]) -> dict[str, Any]:
    """Which obstacle a colliding start or goal is in, and how deep: FCL's estimate as an
    upper bound, the C-space's depth as a lower bound."""
    by_obstacle: dict[str, float] = {}
    for prim, depth in cs.containing(p.tolist()):
        name = obstacle_of(prim)
        by_obstacle[name] = max(by_obstacle.get(name, 0.0), depth)
    fcl_hit = checker.colliding_obstacle(p)
    report: dict[str, Any] = {"which": which, "position": p.tolist()}
    if fcl_hit is not None:
        report["obstacle"] = fcl_hit[0]
        report["depth_upper_bound"] = fcl_hit[1]
        report["depth_lower_bound"] = by_obstacle.get(fcl_hit[0], 0.0)
    elif by_obstacle:
        name = max(by_obstacle, key=lambda k: by_obstacle[k])
        report["obstacle"] = name
        report["depth_lower_bound"] = by_obstacle[name]
    report["depth_by_obstacle"] = by_obstacle
    return report


def _escape_directions(cs, p: np.ndarray) -> list[np.ndarray]:
    """The six axes, then the facet planes nearest ``p`` of the primitives containing it
    (decomposition), or a fan of cube-face, -edge and -corner directions (exact source:
    no facet planes to follow)."""
    directions = [s * e for e in np.eye(3) for s in (1.0, -1.0)]
    if cs.is_exact:
        fan = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)
                        if (x, y, z) != (0, 0, 0) and abs(x) + abs(y) + abs(z) > 1], float)
        directions += list(fan / np.linalg.norm(fan, axis=1)[:, None])
        return directions
    for prim, _depth in cs.containing(p.tolist()):
        normals, offsets = cs.primitive_planes(prim)
        slack = offsets - normals @ p
        for k in np.argsort(slack, kind="stable")[:3]:
            directions.append(normals[k])
    return directions


def escape(cs, checker: FclChecker, p: np.ndarray, reach: float) -> np.ndarray | None:
    """A point outside every C-obstacle within ``reach`` of ``p`` whose segment from
    ``p`` FCL accepts (for a ``p`` in tolerated contact), shortest first, or ``None``."""
    candidates = sorted((length, tuple(d)) for d in _escape_directions(cs, p)
                        for length in reach * np.array(ESCAPE_FRACTIONS))
    for length, d in candidates:
        q = p + length * np.asarray(d)
        if not cs.contains(q[None, :])[0] and checker.check_segment(p, q).valid:
            return q
    return None
