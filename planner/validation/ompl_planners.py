"""OMPL's geometric planners, driven by the same checker, as baselines.

Entry points: :class:`OmplPlanner` (a :class:`~planner.roles.Planner`) and
:func:`available_planners`.

Every query builds its own OMPL objects (state space, ``SpaceInformation``,
``ProblemDefinition``, planner) and drops them before returning, so nothing OMPL-owned
outlives a call: no nanobind leak warnings at exit, no reference cycles through C++.

Seeding (ompl 2.0.1, measured): ``ompl.util.RNG.setSeed(s)`` must run before the planner
and its samplers are created; every OMPL RNG created afterwards draws its seed from a
generator re-seeded with ``s``. Calling it again later in the same process logs "Random
number generation already started" but does re-seed, so each :meth:`OmplPlanner.solve`
re-seeds (with the log silenced) and the same seed gives the same path for single-threaded
planners (RRTConnect, RRT, BIT*, ...). PRM grows its roadmap while a second thread looks
for solutions, so its result also depends on timing. OMPL ignores seed 0; the seed given
here is mapped to ``seed + 1``.

Optimizing planners (BIT*, RRT*, PRM*, ...) get a path-length objective whose cost
threshold is infinite, so they stop at their first solution instead of spending the whole
budget (pass ``optimize=True`` to let them improve it until the time limit).

A returned path is reported as :attr:`PlanStatus.FOUND` only when OMPL says the solution
is exact *and* the path passes ``checker.check_path`` (FCL conservative advancement);
otherwise the status (``no_path`` for a start or goal in collision, else ``not_found``)
and its reason say why, and no waypoints are returned.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import ArrayLike

from planner.errors import InvalidParameterError
from planner.roles import PlanResult, PlanStatus

from .ompl_check import (
    DEFAULT_RESOLUTION,
    CheckCounter,
    as_bounds,
    make_space_information,
    ompl_missing,
    quiet_ompl,
    states_to_array,
)

__all__ = ["OmplPlanner", "available_planners"]

# lower-case key -> ompl.geometric class name
_PLANNER_NAMES = (
    "RRTConnect",
    "RRT",
    "RRTstar",
    "InformedRRTstar",
    "SORRTstar",
    "AORRTC",
    "PRM",
    "PRMstar",
    "BITstar",
    "FMT",
    "BFMT",
    "KPIECE1",
    "BKPIECE1",
    "LBKPIECE1",
)


def available_planners() -> tuple[str, ...]:
    """Names of the OMPL planners :class:`OmplPlanner` accepts (case-insensitive); none
    where OMPL is not installed."""
    if ompl_missing() is not None:
        return ()
    from ompl import geometric as og

    return tuple(n for n in _PLANNER_NAMES if hasattr(og, n))


def _resolve_name(name: str) -> str:
    missing = ompl_missing()
    if missing is not None:
        raise InvalidParameterError(f"planner {name!r}: {missing}")
    names = available_planners()
    by_key = {n.lower(): n for n in names}
    key = str(name).strip().lower()
    if key not in by_key:
        import difflib

        close = difflib.get_close_matches(key, list(by_key), n=1)
        hint = f"did you mean {by_key[close[0]]!r}? " if close else ""
        raise InvalidParameterError(
            f"planner {name!r}: unknown OMPL planner; {hint}available: {', '.join(names)}"
        )
    return by_key[key]


_VALIDATOR_CLASS = None


def _checker_motion_validator(si, checker):
    """An ``ob.MotionValidator`` whose ``checkMotion`` is ``checker.check_motion``.

    The class is built once (OMPL is imported lazily) and closes over nothing, so the
    validator references the checker only, never ``si`` (no cycle through C++)."""
    global _VALIDATOR_CLASS
    if _VALIDATOR_CLASS is None:
        from ompl import base as ob

        class CheckerMotionValidator(ob.MotionValidator):
            def __init__(self, space_information, motion_checker) -> None:
                super().__init__(space_information)
                self.checker = motion_checker

            def checkMotion(self, a, b) -> bool:  # noqa: N802 (OMPL's name)
                ok, _ = self.checker.check_motion((a[0], a[1], a[2]), (b[0], b[1], b[2]))
                return bool(ok)

        _VALIDATOR_CLASS = CheckerMotionValidator
    return _VALIDATOR_CLASS(si, checker)


def _path_length(waypoints: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(waypoints, axis=0), axis=1).sum())


_REASONS = {
    "TIMEOUT": "time_limit",
    "APPROXIMATE_SOLUTION": "approximate_solution",
    "INVALID_START": "start_invalid",
    "INVALID_GOAL": "goal_invalid",
}
"""OMPL's ``PlannerStatus`` names to the reasons of a ``not_found``; OMPL's own
``INFEASIBLE`` is not a proof, so it is ``not_found`` too (reason ``planner_status``)."""


class OmplPlanner:
    """An OMPL geometric planner over ``RealVectorStateSpace(3)`` with the scene bounds.

    Args:
        name: planner name, case-insensitive, one of :func:`available_planners`
            (``RRTConnect``, ``PRM``, ``BITstar``, ...).
        checker: the state validity checker (normally
            :class:`~planner.validation.fcl_checker.FclChecker`); it must also have
            ``check_path`` (used to re-validate every returned path) and, for
            ``motion_validator="checker"``, ``check_motion``.
        bounds: ``(2, 3)`` ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``.
        seed: random seed (``>= 0``); see the module docstring.
        resolution: OMPL's state validity checking resolution (fraction of the bounds'
            diagonal) for its discrete motion validator; ``None`` is OMPL's default,
            ``0.01``.
        motion_validator: ``"discrete"`` (OMPL's ``DiscreteMotionValidator`` at
            ``resolution``, what OMPL users get) or ``"checker"`` (every edge checked by
            ``checker.check_motion``: exact, slower).
        simplify: shorten an exact solution with OMPL's ``PathSimplifier`` (kept only
            if it still re-validates).
        optimize: let optimizing planners improve their solution until the time limit.

    ``PlanResult.n_valid_checks`` / ``n_invalid_checks`` count the state validity
    checks OMPL made through its validity callback; with ``motion_validator="checker"``
    edge checks go to ``checker.check_motion`` instead and are counted on the checker
    (``n_valid_motions`` / ``n_invalid_motions``).

    Thread safety: one :meth:`solve` at a time per instance (the checker is shared and
    OMPL's seed is process-global).
    """

    def __init__(
        self,
        name: str,
        checker,
        bounds: ArrayLike,
        *,
        seed: int = 0,
        resolution: float | None = None,
        motion_validator: str = "discrete",
        simplify: bool = True,
        optimize: bool = False,
    ) -> None:
        self.name = _resolve_name(name)
        if not hasattr(checker, "is_valid") or not hasattr(checker, "check_path"):
            raise InvalidParameterError(
                "checker: needs is_valid(t) and check_path(waypoints) (e.g. FclChecker)"
            )
        if motion_validator not in ("discrete", "checker"):
            raise InvalidParameterError(
                f"motion_validator = {motion_validator!r}: use 'discrete' or 'checker'"
            )
        if motion_validator == "checker" and not hasattr(checker, "check_motion"):
            raise InvalidParameterError("motion_validator='checker' needs checker.check_motion")
        if int(seed) != seed or seed < 0:
            raise InvalidParameterError(f"seed = {seed!r}: must be an integer >= 0")
        self.checker = checker
        self.bounds = np.stack(as_bounds(bounds))
        self.seed = int(seed)
        self.resolution = DEFAULT_RESOLUTION if resolution is None else float(resolution)
        if not (0 < self.resolution <= 1):
            raise InvalidParameterError(f"resolution = {resolution!r}: must be in (0, 1]")
        self.motion_validator = motion_validator
        self.simplify = bool(simplify)
        self.optimize = bool(optimize)

    def __repr__(self) -> str:
        return f"OmplPlanner({self.name!r}, seed={self.seed}, resolution={self.resolution})"

    def setup(self) -> None:
        """Nothing to prepare: every query builds its own OMPL objects (see the module
        documentation)."""

    def _in_bounds(self, t: np.ndarray) -> bool:
        return bool(np.all(t >= self.bounds[0]) and np.all(t <= self.bounds[1]))

    def solve(self, start: ArrayLike, goal: ArrayLike, time_limit: float) -> PlanResult:
        """Plan from ``start`` to ``goal`` within ``time_limit`` seconds.

        Returns:
            :class:`~planner.roles.PlanResult`; ``waypoints`` only when ``found``
            (re-validated by ``checker.check_path``). A start or goal in collision is
            ``no_path``; OMPL's own "infeasible" is not a proof and is ``not_found``.
        """
        t0 = time.perf_counter()
        s = np.asarray(start, dtype=np.float64).reshape(-1)
        g = np.asarray(goal, dtype=np.float64).reshape(-1)
        for what, p in (("start", s), ("goal", g)):
            if p.shape != (3,) or not np.all(np.isfinite(p)):
                raise InvalidParameterError(f"{what}: expected 3 finite numbers, got {p!r}")
        if not (time_limit > 0 and math.isfinite(time_limit)):
            raise InvalidParameterError(f"time_limit = {time_limit!r}: must be finite and > 0")

        def result(status: PlanStatus, reason: str, message: str = "", counter=None,
                   **kw) -> PlanResult:
            return PlanResult(
                status=status,
                reason=reason,
                seconds=time.perf_counter() - t0,
                n_valid_checks=counter.valid if counter else 0,
                n_invalid_checks=counter.invalid if counter else 0,
                message=message,
                planner=self.name,
                **kw,
            )

        for which, p in (("start", s), ("goal", g)):
            if not self._in_bounds(p):
                return result(PlanStatus.NOT_FOUND, f"{which}_out_of_bounds",
                              f"{which} is out of bounds")
            if not self.checker.is_valid(p):
                return result(PlanStatus.NO_PATH, f"{which}_in_collision",
                              f"{which} is in collision")

        counter = CheckCounter()
        raw, simplified, reason, message = self._plan(s, g, float(time_limit), counter)
        if reason != "path":
            return result(PlanStatus.NOT_FOUND, reason, message, counter)
        for candidate, label in ((simplified, "simplified"), (raw, "raw")):
            if candidate is None:
                continue
            check = self.checker.check_path(candidate)
            if check.valid:
                return result(
                    PlanStatus.FOUND,
                    "path",
                    message if label == "raw" else "",
                    counter,
                    waypoints=candidate,
                    length=_path_length(candidate),
                )
            message = (
                f"OMPL's {label} path failed re-validation at segment "
                f"{check.first_bad_segment} (obstacle {check.obstacle})"
            )
        return result(PlanStatus.NOT_FOUND, "validation_failed", message, counter)

    def _plan(self, s: np.ndarray, g: np.ndarray, time_limit: float, counter: CheckCounter):
        """Run OMPL; returns (raw waypoints, simplified waypoints, reason, message), the
        reason ``"path"`` for an exact solution."""
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        with quiet_ompl("LOG_NONE"):
            # Re-seeding after the first RNG exists logs an error but does take effect.
            ou.RNG.setSeed(self.seed % (2**32 - 1) + 1)
        with quiet_ompl("LOG_ERROR"):
            _space, si = make_space_information(self.checker, self.bounds, self.resolution, counter)
            validator = None  # keeps the Python validator alive while OMPL uses it
            if self.motion_validator == "checker":
                validator = _checker_motion_validator(si, self.checker)
                si.setMotionValidator(validator)
                si.setup()
            start, goal = si.allocState(), si.allocState()
            for i in range(3):
                start[i], goal[i] = float(s[i]), float(g[i])
            pdef = ob.ProblemDefinition(si)
            pdef.setStartAndGoalStates(start, goal)
            objective = ob.PathLengthOptimizationObjective(si)
            if not self.optimize:
                objective.setCostThreshold(objective.infiniteCost())
            pdef.setOptimizationObjective(objective)
            planner = getattr(og, self.name)(si)
            planner.setProblemDefinition(pdef)
            planner.setup()
            plan_t0 = time.perf_counter()
            status = planner.solve(time_limit)
            kind = status.getStatus().name
            if kind != "EXACT_SOLUTION" or not pdef.hasExactSolution() or (
                pdef.hasApproximateSolution()
            ):
                reason = _REASONS.get(kind, "planner_status")
                if kind == "EXACT_SOLUTION":  # inconsistent report: trust the pdef
                    reason = "approximate_solution"
                return None, None, reason, f"OMPL status {kind}"
            path = pdef.getSolutionPath()
            raw = states_to_array(path)
            simplified = None
            if self.simplify:
                remaining = time_limit - (time.perf_counter() - plan_t0)
                copy = og.PathGeometric(path)
                og.PathSimplifier(si).simplify(copy, max(0.05, min(1.0, remaining)))
                simplified = states_to_array(copy)
        return raw, simplified, "path", ""
