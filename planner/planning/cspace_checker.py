"""The native C-space as OMPL's roles see a collision checker: a
:class:`~planner.roles.StateValidityChecker` and :class:`~planner.roles.MotionValidator`
answered exactly from the C-obstacles (no FCL), so OMPL's planners can run on minkplan's
C-space and the two checkers can be compared on the same queries."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from planner.validation import PathCheck

__all__ = ["CSpaceChecker"]

BISECTIONS = 40
"""Halvings that locate the last valid point of a blocked motion (to 1e-12 of it)."""


class CSpaceChecker:
    """Validity and motion checks on a native ``CSpace``: a translation is valid when it
    is inside the bounds and outside every C-obstacle (the C-space's closed obstacles:
    touching counts), a motion when the closed segment misses them.

    Args:
        cspace: a native :class:`planner._minkowski_core.CSpace`.

    Attributes:
        n_valid, n_invalid, n_valid_motions, n_invalid_motions: answers so far.

    Thread safety: not thread-safe (the counters); one instance per thread.
    """

    def __init__(self, cspace) -> None:
        self.cspace = cspace
        self.n_valid = self.n_invalid = 0
        self.n_valid_motions = self.n_invalid_motions = 0

    def _free(self, t: np.ndarray) -> bool:
        return not bool(self.cspace.contains(t[None, :])[0])

    def is_valid(self, t: ArrayLike) -> bool:
        p = np.asarray(t, dtype=np.float64).reshape(3)
        ok = self._free(p)
        if ok:
            self.n_valid += 1
        else:
            self.n_invalid += 1
        return ok

    def clearance(self, t: ArrayLike) -> float:
        """A lower bound of the distance to the C-obstacles (``<= 0`` inside)."""
        p = np.asarray(t, dtype=np.float64).reshape(1, 3)
        return float(self.cspace.signed_distance(p)[0])

    def check_motion(self, a: ArrayLike, b: ArrayLike) -> tuple[bool, float | None]:
        pa = np.asarray(a, dtype=np.float64).reshape(3)
        pb = np.asarray(b, dtype=np.float64).reshape(3)
        if self.cspace.segment_is_free(pa.tolist(), pb.tolist()):
            self.n_valid_motions += 1
            return True, None
        self.n_invalid_motions += 1
        if not self._free(pa):
            return False, None
        lo, hi = 0.0, 1.0  # the segment a -> a + lo (b - a) is free, to a + hi (b - a) not
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            if self.cspace.segment_is_free(pa.tolist(), (pa + mid * (pb - pa)).tolist()):
                lo = mid
            else:
                hi = mid
        return False, lo

    def check_path(self, waypoints: ArrayLike) -> PathCheck:
        """Every segment of a piecewise-linear path, exactly (as ``FclChecker.check_path``
        reports it; no clearance is measured)."""
        pts = np.asarray(waypoints, dtype=np.float64).reshape(-1, 3)
        for i in range(len(pts) - 1):
            ok, fraction = self.check_motion(pts[i], pts[i + 1])
            if not ok:
                hit = pts[i] if fraction is None else pts[i] + fraction * (pts[i + 1] - pts[i])
                return PathCheck(False, i, float("nan"), len(pts) - 1, first_invalid=hit)
        valid = len(pts) > 1 or self._free(pts[0])
        return PathCheck(valid, None if valid else 0, float("nan"), max(len(pts) - 1, 1))
