"""What the FCL checker is set with and what it answers: its tolerances, and the results
of segment and path checks (also the form :class:`~planner.planning.CSpaceChecker`
answers in)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CheckerTolerances", "PathCheck", "SegmentCheck"]


@dataclass(frozen=True)
class CheckerTolerances:
    """Tolerances of the FCL checker; ``*_rel`` ones are fractions of the scene's scale
    (the diagonal of the bounding box of the robot and the obstacles).

    Attributes:
        contact_floor_rel: conservative advancement declares contact when the clearance
            falls to ``contact_floor_rel * scale`` or below (with ``delta = 0``), and
            gives up certifying a motion when its certified step falls below it.
        clearance_rtol: the minimum clearance along a valid segment is refined until
            the certified lower bound is within this fraction of the best sample.
        clearance_budget: at most this many extra distance queries per segment for that
            refinement.
        max_checks_per_segment: hard cap on queries per segment (a motion that needs more
            is reported invalid, "not certified").
        max_contacts: contacts requested from FCL per obstacle when looking for escape
            directions or depth estimates.
        witness_fractions: lengths, as fractions of ``delta``, of the witness
            translations tried to certify a configuration in tolerated contact.
        witness_ladder_steps: also tried, the lengths ``2**(k / steps)`` between the
            smallest fraction of ``delta`` and ``delta`` (a ladder fixed in length, so
            that a larger tolerance accepts what a smaller one did); 0: none.
    """

    contact_floor_rel: float = 1e-9
    clearance_rtol: float = 1e-3
    clearance_budget: int = 64
    max_checks_per_segment: int = 1_000_000
    max_contacts: int = 64
    witness_fractions: tuple[float, ...] = (0.25, 0.5, 1.0)
    witness_ladder_steps: int = 8


@dataclass(frozen=True)
class SegmentCheck:
    """Result of :meth:`FclChecker.check_segment`.

    Attributes:
        valid: every configuration of the segment is valid (certified).
        first_invalid: ``(3,)`` first configuration found invalid or that could not be
            certified; ``None`` when valid. With ``delta = 0`` this is where the
            clearance first falls to the contact floor, i.e. the entry point into the
            obstacle (to within ``contact_floor_rel * scale``), not a point inside it.
        min_distance: smallest clearance seen at the checked configurations (an upper
            bound of the segment's true minimum; ``0`` when in tolerated contact).
        n_checks: FCL configuration queries made.
        last_valid_fraction: fraction of the segment certified valid from ``a``
            (``1.0`` when valid, ``None`` when ``a`` itself is invalid).
        clearance_lower_bound: certified lower bound of the true minimum clearance along
            the segment (1-Lipschitz bound between samples; ``min_distance`` minus at most
            ``clearance_rtol`` relative when valid and free).
        obstacle: name of the obstacle hit at ``first_invalid`` (``None`` if none, or if
            the motion was only "not certified").
    """

    valid: bool
    first_invalid: np.ndarray | None
    min_distance: float
    n_checks: int
    last_valid_fraction: float | None = 1.0
    clearance_lower_bound: float = float("nan")
    obstacle: str | None = None


@dataclass(frozen=True)
class PathCheck:
    """Result of :meth:`FclChecker.check_path`.

    Attributes:
        valid: every segment is valid.
        first_bad_segment: index ``i`` of the first invalid segment
            ``waypoints[i] -> waypoints[i + 1]``; ``None`` when valid.
        min_clearance: minimum of the segments' ``min_distance`` (up to the first bad
            segment).
        n_checks: FCL configuration queries over all segments checked.
        first_invalid: ``(3,)`` first invalid configuration, or ``None``.
        clearance_lower_bound: minimum of the segments' certified lower bounds.
        obstacle: obstacle hit at ``first_invalid``, if known.
    """

    valid: bool
    first_bad_segment: int | None
    min_clearance: float
    n_checks: int
    first_invalid: np.ndarray | None = None
    clearance_lower_bound: float = float("nan")
    obstacle: str | None = None
