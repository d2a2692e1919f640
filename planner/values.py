"""Checks of single values shared by the typed problems, the readers and the API: numbers,
booleans and seeds, each with one rule and a message that describes the offending value.

Each check raises ``ValueError`` with the problem only (no field name); callers add the
field (the readers as a :class:`~planner.errors.ScenarioError`, the API as an
:class:`~planner.errors.InvalidParameterError`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["SEED_LIMIT", "check_bool", "check_optional", "check_real", "check_seed",
           "describe_value"]

SEED_LIMIT = 2**32 - 1
"""Seeds are integers in ``0 .. SEED_LIMIT - 1``: every random generator minkplan drives
takes them as they are (CoACD, numpy) or as ``seed + 1`` (OMPL, which ignores 0), all
32-bit."""


def describe_value(value: Any) -> str:
    """A value as an error message names it: ``string 'up'``, ``a list of 2``, ..."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"string {value!r}"
    if isinstance(value, (int, float)):
        return f"number {value!r}"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    return type(value).__name__


def check_real(value: Any, low: float, *, strict: bool, high: float | None = None) -> float:
    """A finite number ``> low`` (``strict``) or ``>= low``, and ``<= high`` if given."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"expected a number, got {describe_value(value)}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, got {value!r}")
    if (number <= low) if strict else (number < low):
        raise ValueError(f"must be {'>' if strict else '>='} {low:g}, got {value!r}")
    if high is not None and number > high:
        raise ValueError(f"must be <= {high:g}, got {value!r}")
    return number


def check_optional(value: Any, low: float, *, strict: bool) -> float | None:
    """``None``, or a number as :func:`check_real` wants it."""
    return None if value is None else check_real(value, low, strict=strict)


def check_seed(value: Any) -> int:
    """An integer seed in ``0 .. SEED_LIMIT - 1`` (see :data:`SEED_LIMIT`)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"expected an integer, got {describe_value(value)}")
    if not 0 <= int(value) < SEED_LIMIT:
        raise ValueError(f"must be in 0 .. {SEED_LIMIT - 1}, got {value!r}")
    return int(value)


def check_bool(value: Any) -> bool:
    """``True`` or ``False`` (not 0, 1 or a string)."""
    if isinstance(value, bool):
        return value
    raise ValueError(f"expected true or false, got {describe_value(value)}")
