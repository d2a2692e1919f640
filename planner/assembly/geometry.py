"""Where a part has left an assembly: the exit box of the remaining parts and the points
and directions of removals."""

from __future__ import annotations

import math

import numpy as np
import trimesh

from planner.errors import InvalidParameterError
from planner.problem import Part

__all__ = ["DIRECTIONS", "ESCAPE_MARGIN_REL", "direction_vector", "exit_box", "exit_point",
           "parts_box", "vector_name"]

ESCAPE_MARGIN_REL = 0.1
"""A part has left when its box is outside the remaining parts' box grown by this
fraction of the assembly's diagonal."""

DIRECTIONS = {name: vec for name, vec in zip(
    ("+z", "-z", "+x", "-x", "+y", "-y"),
    np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], float),
    strict=True)}
"""The six axis directions of straight removals and goal sides, by name."""


def parts_box(meshes: list[trimesh.Trimesh]) -> tuple[np.ndarray, np.ndarray]:
    bounds = np.array([m.bounds for m in meshes])
    return bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)


def exit_box(part: Part, others: list[Part], margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Translations at which the part's box meets the box of the remaining parts (the
    part itself included, at its assembled pose) grown by ``margin``: outside this box,
    the part has left. It always contains ``0``."""
    o_lo, o_hi = parts_box([p.mesh for p in [part, *others]])
    p_lo, p_hi = part.mesh.bounds
    return o_lo - margin - p_hi, o_hi + margin - p_lo


def exit_point(direction: np.ndarray, box: tuple[np.ndarray, np.ndarray],
                margin: float) -> np.ndarray:
    """Where the ray from ``0`` along the unit ``direction`` leaves the exit box, plus
    half the margin."""
    lo, hi = box
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(direction > 0, hi / direction,
                         np.where(direction < 0, lo / direction, np.inf))
    return direction * (float(np.min(reach)) + margin / 2)


def direction_vector(direction: str | np.ndarray) -> tuple[str, np.ndarray]:
    """``(name, unit vector)`` of an axis name (``"+z"``) or a vector."""
    if isinstance(direction, str):
        if direction not in DIRECTIONS:
            raise InvalidParameterError(f"direction {direction!r}: use one of "
                                        f"{', '.join(DIRECTIONS)} or a 3-vector")
        return direction, DIRECTIONS[direction]
    vec = np.asarray(direction, dtype=np.float64).reshape(-1)
    norm = float(np.linalg.norm(vec)) if vec.shape == (3,) else 0.0
    if not (norm > 0 and math.isfinite(norm)):
        raise InvalidParameterError(f"direction {direction!r}: expected a non-zero finite "
                                    f"3-vector")
    vec = vec / norm
    for name, axis in DIRECTIONS.items():
        if float(np.dot(vec, axis)) > 1.0 - 1e-12:
            return name, axis
    return vector_name(vec), vec


def vector_name(vec: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in vec) + "]"
