"""The direct motion: the straight segment from start to goal, tested exactly before any
C-space is built.

For large problems (many triangle pairs) a C-space over the whole bounds is the expensive
part of planning: the reduced convolution of IndustReal's gear base (5k triangles) with a
gear (20k–51k) passes four million facets, past the default memory budget, while the gear
comes off its shaft along a straight line. A serious planner tries the direct connection
first; here it is tested exactly on the meshes as given, by the C-obstacles' triangle-pair
pieces (:class:`PieceObstacles`, no reduced convolution, no octree), so the test is cheap
and proves what it says:

* an end inside a C-obstacle but valid for FCL (a tolerated contact: a part resting in its
  seat) is stepped out by the same short escape the planner uses
  (:func:`.endpoints.escape`); an end FCL calls in collision is the answer already
  (no path: the planner reports it without a C-space, as it would with one);
* the segment between the (escaped) ends must miss every C-obstacle grown by the
  clearance, exactly.

The motion found is then validated by FCL and OMPL like every path (a motion that fails is
not reported, and the planner builds its C-space as before). Nothing is claimed when the
segment is blocked: a no-path still needs the planner's certificate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.problem import Scenario
from planner.sources import Source
from planner.validation import FclChecker

from .endpoints import escape

__all__ = ["Direct", "PieceObstacles", "direct_motion", "triangle_pairs"]


def triangle_pairs(scenario: Scenario) -> int:
    """Triangle pairs of the robot against every obstacle (the size of the problem)."""
    robot = len(scenario.robot.mesh.faces)
    return sum(len(o.mesh.faces) * robot for o in scenario.obstacles)


class PieceObstacles:
    """The C-obstacles ``O_k ⊕ (−R)`` of a scenario for point and segment queries only:
    one exact pair sum per obstacle built with ``pieces=True`` (every triangle-pair piece
    a boundary candidate, found per query by a traversal of the two meshes' BVHs;
    containment counts for solids), so building them costs nothing beyond the meshes.

    Args:
        scenario: the problem.
        source: its C-obstacle source (for the checked native meshes it holds).
    """

    is_exact = True
    """Escapes try the exact source's fan of directions (:func:`.endpoints.escape`)."""

    def __init__(self, scenario: Scenario, source: Source) -> None:
        from planner import _minkowski_core as core  # noqa: PLC0415

        native = source.parts.native
        robot = native(scenario.robot).negated()
        self.sums = [core.ExactSum(native(o), robot, o.solid, scenario.robot.solid,
                                   pieces=True) for o in scenario.obstacles]

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Whether each of ``points`` ``(n, 3)`` lies in a (closed) C-obstacle."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        inside = np.zeros(len(points), dtype=bool)
        for pair in self.sums:
            inside |= pair.contains(points)
        return inside

    def segment_is_free(self, a: np.ndarray, b: np.ndarray, margin: float = 0.0) -> bool:
        """Whether the closed segment ``a → b`` misses every C-obstacle grown by the cube
        of half-width ``margin``."""
        a_list, b_list = np.asarray(a, float).tolist(), np.asarray(b, float).tolist()
        return all(pair.segment_is_free(a_list, b_list, margin) for pair in self.sums)


@dataclass(frozen=True)
class Direct:
    """What the direct test found.

    Attributes:
        motion: ``(k, 3)`` waypoints of the straight motion (the ends, with the escapes
            out of tolerated contacts between them) when it is free, else ``None``.
        in_collision: ``"start"`` or ``"goal"`` when that end collides for FCL beyond the
            contact tolerance (inside a C-obstacle too), else ``None``.
    """

    motion: np.ndarray | None = None
    in_collision: str | None = None


def direct_motion(scenario: Scenario, source: Source, checker: FclChecker, *,
                  reach: float, margin: float) -> Direct:
    """The straight motion from start to goal when its middle segment misses every
    C-obstacle grown by ``margin`` exactly (see the module documentation).

    Args:
        scenario: the problem.
        source: its C-obstacle source.
        checker: the FCL checker of the validation (decides tolerated contacts).
        reach: longest escape out of a tolerated contact.
        margin: the clearance asked for.
    """
    obstacles = PieceObstacles(scenario, source)
    same = np.array_equal(np.asarray(scenario.start), np.asarray(scenario.goal))
    ends = []
    for which in ("start",) if same else ("start", "goal"):
        p = np.asarray(getattr(scenario, which), dtype=np.float64)
        out: np.ndarray | None = p
        if obstacles.contains(p[None, :])[0]:
            if not checker.is_valid(p):
                return Direct(in_collision=which)
            out = p if same else escape(obstacles, checker, p, reach)
        if same:  # valid and already there: no motion, no escape
            return Direct(motion=np.array([p, p], dtype=np.float64))
        if out is None:
            return Direct()
        ends.append((p, out))
    (start, start_out), (goal, goal_out) = ends
    if not obstacles.segment_is_free(start_out, goal_out, margin):
        return Direct()
    waypoints = [start, start_out, goal_out, goal]
    kept = [waypoints[0]] + [w for prev, w in zip(waypoints, waypoints[1:])
                             if not np.array_equal(prev, w)]
    return Direct(motion=np.array(kept, dtype=np.float64))
