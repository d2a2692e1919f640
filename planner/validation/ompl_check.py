"""OMPL's independent check of a translation path.

Entry point: :func:`ompl_check_path`, returning :class:`OmplPathCheck`.

The path is loaded into OMPL as an ``og.PathGeometric`` over a
``RealVectorStateSpace(3)`` with the scenario bounds, whose ``SpaceInformation`` uses a
validity checker backed by any :class:`~planner.roles.StateValidityChecker`
(normally the :class:`~planner.validation.fcl_checker.FclChecker`), and checked with
``PathGeometric.check()``, i.e. every state plus OMPL's discrete motion validator between
consecutive states. Optionally OMPL's ``PathSimplifier`` shortens it (re-checked after).

OMPL checks a motion at discrete states, spaced by its *state validity checking
resolution*, a fraction of the space's maximum extent (its diagonal). The default, 1%,
steps right over the corner of a hole that a peg path cuts; here the resolution is set
so that the step is at most half the path's clearance, clamped to
``[MIN_RESOLUTION, DEFAULT_RESOLUTION]``.

ompl 2.0.1 (nanobind bindings) facts this module relies on:

- a plain Python callable ``f(state) -> bool`` is accepted by
  ``SpaceInformation.setStateValidityChecker``; states index like ``state[0]``;
- states come from ``si.allocState()`` and are owned by Python: never pass them to
  ``si.freeState`` (double free, segfault); ``PathGeometric.append`` copies the state;
- nanobind prints "leaked instances" warnings at interpreter exit for OMPL objects still
  alive then (typically module globals). ompl does not expose nanobind's
  ``set_leak_warnings``; keep OMPL objects local to a call (as here) or release them
  before exit (see :mod:`planner.validation.ompl_planners`), and never build a reference
  cycle between a Python callback and the OMPL object holding it (the cycle passes
  through C++, so the garbage collector cannot break it).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from planner.errors import InvalidParameterError


def ompl_missing() -> str | None:
    """Why OMPL cannot be used here (its Python package does not import: it has wheels
    for CPython 3.10-3.13 on Linux x86_64 / aarch64 and macOS 15 or later only, and
    minkplan asks for it only there), or ``None`` when it can. One line."""
    try:
        import ompl  # noqa: F401
    except ImportError as exc:
        return (f"OMPL is not installed ({exc}; it has wheels for CPython 3.10-3.13 on Linux "
                f"and macOS 15+ only): the OMPL path check and planners are unavailable, "
                f"FCL validation runs")
    return None

__all__ = [
    "ompl_missing",
    "DEFAULT_RESOLUTION",
    "MIN_RESOLUTION",
    "OmplPathCheck",
    "ompl_check_path",
    "resolution_for_clearance",
]

DEFAULT_RESOLUTION = 0.01
"""OMPL's default state validity checking resolution (fraction of the space's extent)."""

MIN_RESOLUTION = 1e-4
"""Finest resolution chosen automatically (fraction of the space's extent)."""


@dataclass(frozen=True)
class OmplPathCheck:
    """Result of :func:`ompl_check_path`.

    Attributes:
        valid: OMPL's ``PathGeometric.check()`` accepted the path.
        length: the path's length as OMPL measures it.
        simplified: ``(m, 3)`` waypoints after ``PathSimplifier``, or ``None``.
        resolution_used: state validity checking resolution given to OMPL (fraction of
            the space's maximum extent).
        step: the corresponding longest unchecked step, in scene units.
        simplified_valid: the simplified path passed OMPL's check and, when the
            checker has ``check_path``, the checker's own path check; ``None`` when not
            simplified.
        simplified_length: length of the simplified path (``nan`` if not simplified).
        n_valid_checks: state validity checks OMPL made that answered "valid".
        n_invalid_checks: state validity checks OMPL made that answered "invalid".
    """

    valid: bool
    length: float
    simplified: np.ndarray | None
    resolution_used: float
    step: float = float("nan")
    simplified_valid: bool | None = None
    simplified_length: float = float("nan")
    n_valid_checks: int = 0
    n_invalid_checks: int = 0


def as_bounds(bounds: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high)`` as two ``(3,)`` arrays from a ``(2, 3)`` array-like."""
    arr = np.asarray(bounds, dtype=np.float64)
    if arr.shape != (2, 3) or not np.all(np.isfinite(arr)):
        raise InvalidParameterError(
            f"bounds: expected finite [[xmin, ymin, zmin], [xmax, ymax, zmax]], got {bounds!r}"
        )
    if not np.all(arr[1] > arr[0]):
        raise InvalidParameterError(f"bounds: need min < max on every axis, got {arr.tolist()}")
    return arr[0].copy(), arr[1].copy()


def extent_of(bounds: ArrayLike) -> float:
    """OMPL's maximum extent of the box ``bounds``: its diagonal."""
    lo, hi = as_bounds(bounds)
    return float(np.linalg.norm(hi - lo))


def resolution_for_clearance(
    clearance: float,
    bounds: ArrayLike,
    *,
    floor: float = MIN_RESOLUTION,
    ceiling: float = DEFAULT_RESOLUTION,
) -> float:
    """Resolution (fraction of the extent) whose step is at most ``clearance / 2``,
    clamped to ``[floor, ceiling]``; a non-positive or unknown clearance gives ``floor``."""
    extent = extent_of(bounds)
    if not (clearance > 0 and math.isfinite(clearance)):
        return floor
    return float(min(max(0.5 * clearance / extent, floor), ceiling))


@contextlib.contextmanager
def quiet_ompl(level_name: str = "LOG_WARN") -> Iterator[None]:
    """Temporarily set OMPL's console log level (``LOG_DEBUG`` .. ``LOG_NONE``)."""
    from ompl import util as ou

    previous = ou.getLogLevel()
    ou.setLogLevel(getattr(ou.LogLevel, level_name))
    try:
        yield
    finally:
        ou.setLogLevel(previous)


class CheckCounter:
    """Valid/invalid tallies of an OMPL validity callback (no reference to OMPL)."""

    __slots__ = ("valid", "invalid")

    def __init__(self) -> None:
        self.valid = 0
        self.invalid = 0


def make_validity_fn(checker, lo: np.ndarray, hi: np.ndarray, counter: CheckCounter):
    """A plain ``f(state) -> bool`` for ``si.setStateValidityChecker``: in bounds and
    ``checker.is_valid``. It closes over the checker and counter only, never over OMPL
    objects (no reference cycle through C++)."""
    lo_t, hi_t = tuple(lo), tuple(hi)

    def is_valid(state) -> bool:
        t = (state[0], state[1], state[2])
        ok = all(lo_t[i] <= t[i] <= hi_t[i] for i in range(3)) and bool(checker.is_valid(t))
        if ok:
            counter.valid += 1
        else:
            counter.invalid += 1
        return ok

    return is_valid


def make_space_information(checker, bounds: ArrayLike, resolution: float, counter: CheckCounter):
    """``(space, si)``: ``RealVectorStateSpace(3)`` with ``bounds`` and a set-up
    ``SpaceInformation`` using ``checker`` at ``resolution``."""
    from ompl import base as ob

    lo, hi = as_bounds(bounds)
    if not (0 < resolution <= 1 and math.isfinite(resolution)):
        raise InvalidParameterError(f"resolution = {resolution!r}: must be in (0, 1]")
    space = ob.RealVectorStateSpace(3)
    rv_bounds = ob.RealVectorBounds(3)
    for i in range(3):
        rv_bounds.setLow(i, float(lo[i]))
        rv_bounds.setHigh(i, float(hi[i]))
    space.setBounds(rv_bounds)
    si = ob.SpaceInformation(space)
    si.setStateValidityChecker(make_validity_fn(checker, lo, hi, counter))
    si.setStateValidityCheckingResolution(float(resolution))
    si.setup()
    return space, si


def states_to_array(path) -> np.ndarray:
    """``(n, 3)`` waypoints of an ``og.PathGeometric``."""
    return np.array([[s[0], s[1], s[2]] for s in path.getStates()], dtype=np.float64).reshape(
        -1, 3
    )


def array_to_path(si, waypoints: np.ndarray):
    """An ``og.PathGeometric`` through ``waypoints`` (``(n, 3)``)."""
    from ompl import geometric as og

    path = og.PathGeometric(si)
    state = si.allocState()
    for p in waypoints:
        state[0], state[1], state[2] = float(p[0]), float(p[1]), float(p[2])
        path.append(state)  # copies the state
    return path


def ompl_check_path(
    waypoints: ArrayLike,
    checker,
    bounds: ArrayLike,
    *,
    resolution: float | None = None,
    simplify: bool = False,
    clearance: float | None = None,
    simplify_time: float = 1.0,
) -> OmplPathCheck:
    """Check a path with OMPL (``PathGeometric.check()``), optionally simplify it.

    Args:
        waypoints: ``(n, 3)`` translations, ``n >= 1``.
        checker: a :class:`~planner.roles.StateValidityChecker`
            (``is_valid``); if it also has ``check_path`` (the FCL checker) it provides
            the clearance and re-checks the simplified path.
        bounds: ``(2, 3)`` ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``; states outside
            are invalid.
        resolution: OMPL's state validity checking resolution, a fraction of the
            bounds' diagonal. ``None``: chosen by :func:`resolution_for_clearance` from
            ``clearance``.
        simplify: also run OMPL's ``PathSimplifier.simplify`` for up to
            ``simplify_time`` seconds on a copy, and re-check the result.
        clearance: the path's minimum clearance, if known; ``None``: measured with
            ``checker.check_path`` when available (an invalid path has clearance 0, so
            it gets the finest resolution), else taken as unknown.
        simplify_time: time budget of the simplifier, seconds.

    Returns:
        :class:`OmplPathCheck`.
    """
    pts = np.asarray(waypoints, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0 or not np.all(np.isfinite(pts)):
        raise InvalidParameterError(
            f"waypoints: expected a finite (n, 3) array with n >= 1, got shape {pts.shape}"
        )
    extent = extent_of(bounds)
    if resolution is None:
        if clearance is None and hasattr(checker, "check_path"):
            fcl_result = checker.check_path(pts)
            clearance = fcl_result.min_clearance if fcl_result.valid else 0.0
        resolution = resolution_for_clearance(
            clearance if clearance is not None else math.nan, bounds
        )
    counter = CheckCounter()
    with quiet_ompl():
        from ompl import geometric as og

        _space, si = make_space_information(checker, bounds, float(resolution), counter)
        path = array_to_path(si, pts)
        valid = bool(path.check())
        length = float(path.length())
        simplified = None
        simplified_valid = None
        simplified_length = math.nan
        if simplify:
            copy = og.PathGeometric(path)
            og.PathSimplifier(si).simplify(copy, float(simplify_time))
            simplified = states_to_array(copy)
            simplified_length = float(copy.length())
            simplified_valid = bool(copy.check())
            if simplified_valid and hasattr(checker, "check_path"):
                simplified_valid = bool(checker.check_path(simplified).valid)
    return OmplPathCheck(
        valid=valid,
        length=length,
        simplified=simplified,
        resolution_used=float(resolution),
        step=float(resolution) * extent,
        simplified_valid=simplified_valid,
        simplified_length=simplified_length,
        n_valid_checks=counter.valid,
        n_invalid_checks=counter.invalid,
    )
