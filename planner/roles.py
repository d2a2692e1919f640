"""Planning roles as ``typing.Protocol``s, after OMPL's base classes, and the one status
vocabulary every planner answers in.

Three roles are kept apart, as in ``ompl::base``:

- :class:`StateValidityChecker` answers "is the robot free at translation ``t``?" and
  "how far from contact is it?" (OMPL's ``StateValidityChecker::isValid``/``clearance``).
- :class:`MotionValidator` answers "is the straight motion ``a -> b`` free?", with the
  last valid fraction of the motion when it is not (OMPL's ``MotionValidator::checkMotion``
  with ``lastValid``).
- :class:`Planner` turns a start and a goal into a :class:`PlanResult` whose
  :class:`PlanStatus` says what happened (OMPL's ``Planner::solve`` -> ``PlannerStatus``).
  Planning outcomes (time-out, no path, invalid start) are statuses, never exceptions;
  exceptions are for misuse (bad arguments).

:class:`PlanStatus` has three values, the strings of ``path.json``: ``found`` (a path,
validated independently), ``no_path`` (proved: a certificate, or a start or goal in
collision, as OMPL's ``INFEASIBLE`` and ``INVALID_START``/``INVALID_GOAL``) and
``not_found`` (nothing found and nothing proved: OMPL's ``TIMEOUT``,
``APPROXIMATE_SOLUTION``, ...); a ``reason`` string says which case it was.

Anything with the right methods is a checker: the FCL checker on the original meshes
(:class:`planner.validation.fcl_checker.FclChecker`) and the native C-space
(:class:`planner.planning.cspace_checker.CSpaceChecker`) are interchangeable.

Translations ``t`` are ``(3,)`` array-likes of floats in the scenario's units; the robot
``R`` (fixed orientation, in its own frame) occupies ``R + t``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "FOUND",
    "NOT_FOUND",
    "NO_PATH",
    "MotionValidator",
    "PlanResult",
    "PlanStatus",
    "Planner",
    "StateValidityChecker",
]


class PlanStatus(enum.StrEnum):
    """Outcome of a planning query; the values are ``path.json``'s ``status`` strings."""

    FOUND = "found"
    """A collision-free path from start to goal, validated independently."""
    NO_PATH = "no_path"
    """No collision-free path exists: proved by a certificate, or the start or goal is in
    collision."""
    NOT_FOUND = "not_found"
    """Nothing found and nothing proved (floor, budget or time limit reached, an
    approximate solution, a path that failed validation)."""


FOUND = PlanStatus.FOUND
NO_PATH = PlanStatus.NO_PATH
NOT_FOUND = PlanStatus.NOT_FOUND


@dataclass(frozen=True)
class PlanResult:
    """What a :class:`Planner` returns.

    Attributes:
        status: the outcome.
        reason: which case of it, machine-readable: ``"path"``, ``"certificate"``,
            ``"start_in_collision"``, ``"goal_in_collision"``, ``"start_out_of_bounds"``,
            ``"goal_out_of_bounds"``, ``"time_limit"``, ``"approximate_solution"``,
            ``"validation_failed"``, ``"planner_status"``, ...
        waypoints: ``(n, 3)`` translations from start to goal; ``(0, 3)`` unless
            ``status`` is :attr:`PlanStatus.FOUND`.
        length: Euclidean length of the path (``nan`` without a path).
        seconds: wall-clock time of the whole query (planning, simplification and
            re-validation).
        n_valid_checks: state validity checks that answered "valid" during planning.
        n_invalid_checks: state validity checks that answered "invalid" during planning.
        message: a one-line human-readable explanation (empty when nothing to add).
        planner: the planner's name.
    """

    status: PlanStatus
    reason: str = ""
    waypoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    length: float = float("nan")
    seconds: float = 0.0
    n_valid_checks: int = 0
    n_invalid_checks: int = 0
    message: str = ""
    planner: str = ""

    @property
    def solved(self) -> bool:
        """``True`` only for a found, re-validated path."""
        return self.status is PlanStatus.FOUND


@runtime_checkable
class StateValidityChecker(Protocol):
    """Is the robot free at a translation? (OMPL's ``StateValidityChecker``.)

    Thread safety: an implementation need not be thread-safe. Callers must not call one
    instance from several threads at once; give each thread its own instance (as OMPL
    requires of ``StateValidityChecker`` implementations that keep mutable state). The
    counters below are plain attributes, updated without locks.

    Attributes:
        n_valid: number of :meth:`is_valid` calls that answered ``True``.
        n_invalid: number of :meth:`is_valid` calls that answered ``False``.
    """

    n_valid: int
    n_invalid: int

    def is_valid(self, t: ArrayLike) -> bool:
        """``True`` when the robot at translation ``t`` (``(3,)``) is collision-free
        (within the checker's stated contact tolerance)."""
        ...

    def clearance(self, t: ArrayLike) -> float:
        """Distance from the robot at ``t`` to the nearest obstacle; ``<= 0`` in
        contact or collision."""
        ...


@runtime_checkable
class MotionValidator(Protocol):
    """Is a straight translation free? (OMPL's ``MotionValidator``.)

    Thread safety: as for :class:`StateValidityChecker`: one instance per thread.

    Attributes:
        n_valid_motions: motions found valid so far.
        n_invalid_motions: motions found invalid so far.
    """

    n_valid_motions: int
    n_invalid_motions: int

    def check_motion(self, a: ArrayLike, b: ArrayLike) -> tuple[bool, float | None]:
        """Check every configuration on the segment ``a -> b`` (``(3,)`` each).

        Returns:
            ``(True, None)`` when the whole segment is valid; otherwise ``(False, f)``
            where ``f`` in ``[0, 1)`` is the fraction of the segment known valid (the
            last valid state is ``a + f * (b - a)``, OMPL's ``lastValid``); ``f`` is
            ``None`` when even ``a`` is invalid.
        """
        ...


@runtime_checkable
class Planner(Protocol):
    """Plans a translation path (OMPL's ``Planner``): :meth:`setup` prepares what the
    queries share, :meth:`solve` answers one.

    Thread safety: one query at a time per instance; instances share no mutable state
    unless documented otherwise.
    """

    def setup(self) -> None:
        """Prepare (OMPL's ``Planner::setup``); :meth:`solve` calls it if needed."""
        ...

    def solve(self, start: ArrayLike, goal: ArrayLike, time_limit: float) -> PlanResult:
        """Plan from ``start`` to ``goal`` (``(3,)`` translations) within
        ``time_limit`` seconds. Outcomes are reported in :attr:`PlanResult.status`;
        raises only on misuse (bad arguments)."""
        ...
