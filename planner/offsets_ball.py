"""Offsets of a solid by its exact Minkowski sum with a polytope inscribed in the ball.

``P`` grown by ``r`` is ``P ⊕ B_r``. Take ``K``, the hull of an icosphere's vertices on
the sphere of radius ``r`` and of ``r n`` for each distinct face normal ``n`` of ``P``
(when there are not more of them than the icosphere has vertices). Every point of ``K``'s
hull lies on the sphere, so ``B_{r - δ} ⊆ K ⊆ B_r`` with ``δ = r -`` (``K``'s least
distance from its centre to a facet plane), and ``P ⊕ B_{r - δ} ⊆ P ⊕ K ⊆ P ⊕ B_r``. With
``s`` the sum's own bound (:func:`planner.minkowski_sum`, exact source) and ``b = δ + s``:

* every point ``x`` of the output has ``r - b <= dist(x, P) <= r + b``;
* every point at distance ``r`` from ``P`` lies within ``b`` of the output (``δ`` towards
  its nearest point of ``P`` it is inside ``P ⊕ K``).

That is the offset's ``error_bound`` (:class:`planner.offsets.OffsetResult`). It is the
distance between the two surfaces except where ``dist(·, P)`` has a critical value within
``b`` of ``r``: a gap or neck between two parts whose width is within ``2 b`` of ``2 r``
may be bridged in one and open in the other (the output then lies within ``b`` of the
level ``r`` but farther from its surface). The prisms over ``P``'s faces come out exactly
``r`` out when ``r n`` is a vertex of ``K``.

Eroded by ``r`` it is the same on the complement: ``P ⊖ B_r`` is what
``(C ∖ P) ⊕ (−B_r)`` leaves of ``P``, for a box ``C`` holding ``P`` with room to spare;
the inner shells of ``(C ∖ P) ⊕ (−K)``, turned inside out, bound ``P ⊖ K``, and ``P ⊖
B_r ⊆ P ⊖ K ⊆ P ⊖ B_{r - δ}`` gives the same bound for the distance to ``P``'s boundary.

The icosphere is the coarsest whose ``δ`` is within half the ``eps`` asked for; the sum
takes the rest. Unlike sampling distances cell by cell (:mod:`planner.offsets`'s cell
source), cells the facets' planes resolve end above ``eps``: only the sum's vertices and
edges where many facets meet are refined.

Entry point: :func:`ball_offset`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh

from planner.errors import ResourceLimitError
from planner.problem import Part

from .offsets_convex import (
    BALL_INNER,
    convex_hull,
    hull_mesh,
    representatives,
    rounding_allowance,
    unit_ball,
)

__all__ = ["BALL_SHARE", "MAX_SUBDIVISIONS", "Ball", "ball_offset", "face_directions",
           "inscribed_ball"]

BALL_SHARE = 0.5
"""The share of ``eps`` the ball's ``δ`` may take (the sum's grid has the rest)."""

NORMAL_ANGLE = 1e-6
"""Face normals closer than this (radians, about) are one direction."""


@dataclass(frozen=True)
class Ball:
    """A polytope ``mesh`` inscribed in the ball of radius ``r`` about the origin, ``delta``
    = ``r`` minus its least facet distance, the icosphere's ``subdivisions`` and whether
    the solid's face normals are among its vertices (``with_normals``)."""

    mesh: trimesh.Trimesh
    delta: float
    subdivisions: int
    with_normals: bool


MAX_SUBDIVISIONS = 4
"""The finest icosphere taken (2,562 vertices): a finer one makes the sum's convolution
(the solid's triangles times the ball's) cost more than the cells at that eps (Factory's
hole at eps 1e-7 needs 40,962 vertices: past 300 s and 3.6 GB before the sum was refused;
the cells refuse that eps in 8 s)."""


def inscribed_ball(radius: float, delta_max: float, normals: np.ndarray) -> Ball | None:
    """The hull of the coarsest icosphere of radius ``radius`` whose ``δ`` is within
    ``delta_max``, and of ``radius n`` for the unit ``normals`` when there are not more of
    them than its vertices (every point on the sphere, so they only shrink ``δ``);
    ``None`` when even the finest (:data:`MAX_SUBDIVISIONS`) is coarser."""
    for subdivisions in range(MAX_SUBDIVISIONS + 1):
        if radius * (1.0 - BALL_INNER[subdivisions]) > delta_max:
            continue
        unit, _ = unit_ball(subdivisions)
        with_normals = 0 < len(normals) <= len(unit)
        hull = convex_hull(radius * (np.vstack([unit, normals]) if with_normals else unit))
        delta = radius + float(hull.equations[:, 3].max())  # r - least facet distance
        return Ball(hull_mesh(hull), max(delta, 0.0), subdivisions, with_normals)
    return None


def face_directions(solid: trimesh.Trimesh) -> np.ndarray:
    """The solid's distinct unit face normals: zero-area triangles' left out, normals
    within :data:`NORMAL_ANGLE` of one taken once (a float32 file's copies of one plane's
    normal differ in their last digits)."""
    normals = np.asarray(solid.face_normals, dtype=np.float64)
    normals = normals[np.linalg.norm(normals, axis=1) > 0.5]
    if len(normals) == 0:
        return normals
    normals = np.unique(np.round(normals, 12), axis=0)
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    return normals[representatives(normals, NORMAL_ANGLE)]


def ball_offset(solid: trimesh.Trimesh, radius: float, eps: float, *, name: str,
                max_cells: int | None, progress: bool | None
                ) -> tuple[trimesh.Trimesh, float, dict[str, Any]] | None:
    """``(mesh, error_bound, stats)`` of the checked solid grown (``radius > 0``) or eroded
    by ``radius`` through the sum with an inscribed ball (see the module documentation);
    an empty mesh when an erosion leaves nothing; ``None`` when no icosphere is fine enough.

    Raises:
        ResourceLimitError: the sum would pass the memory limit or ``max_cells``.
    """
    from .minkowski import SURFACE_STATS, minkowski_sum  # noqa: PLC0415

    t0 = time.perf_counter()
    r = abs(radius)
    ball = inscribed_ball(r, BALL_SHARE * eps, face_directions(solid))
    if ball is None:
        return None
    rounding = rounding_allowance(solid, r)
    # (the solid was checked by the caller; the box around it and the hull are closed
    # and outward as made, so nothing is checked again)
    if radius > 0:
        operand = Part(name, solid, "offset operand", checked=True)
        polytope = ball.mesh
    else:  # the complement's sum with -K
        operand = Part(f"{name} (complement)", _complement(solid, r), "offset operand",
                       checked=True)
        polytope = trimesh.Trimesh(-ball.mesh.vertices, ball.mesh.faces[:, ::-1],
                                   process=False)
    try:
        summed = minkowski_sum(operand, Part("ball", polytope, "inscribed ball", checked=True),
                               exact=True,
                               eps=max(eps - ball.delta, rounding), max_cells=max_cells,
                               progress=progress)
    except ResourceLimitError as exc:
        what = f"{name} {'grown' if radius > 0 else 'eroded'} by {r:g}"
        message = str(exc).removeprefix(f"{operand.name} ⊕ ball: ").replace(
            "or use the decomposition source (exact: false) or simpler meshes",
            "or use a larger eps or the cells (method 'cells', --method cells)")
        raise ResourceLimitError(f"{what} (its sum with a ball of {len(polytope.vertices)} "
                                 f"vertices): {message}") from exc
    mesh = summed.mesh if radius > 0 else _inner_shells(summed.mesh)
    stats = {"triangles": len(mesh.faces),
             **{key: summed.stats[key] for key in SURFACE_STATS},
             "bound_by_region": {**summed.stats["bound_by_region"], "round": ball.delta},
             "ball": {"subdivisions": ball.subdivisions, "vertices": len(ball.mesh.vertices),
                      "delta": ball.delta, "with_face_normals": ball.with_normals},
             "sum_seconds": summed.stats["seconds"],
             "seconds": time.perf_counter() - t0}
    return mesh, ball.delta + summed.error_bound + rounding, stats


def _complement(solid: trimesh.Trimesh, r: float) -> trimesh.Trimesh:
    """A box holding the solid grown by more than ``r``, with the solid as a cavity."""
    lo, hi = np.asarray(solid.bounds, dtype=np.float64)
    margin = 2.0 * r + 0.05 * float(np.max(hi - lo))
    box = trimesh.creation.box(bounds=[lo - margin, hi + margin])
    vertices = np.vstack([np.asarray(solid.vertices, dtype=np.float64), box.vertices])
    faces = np.vstack([np.asarray(solid.faces)[:, ::-1], box.faces + len(solid.vertices)])
    return trimesh.Trimesh(vertices, faces, process=False)


def _inner_shells(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The shells of ``mesh`` other than the one through its lowest vertex (the outer
    box's), turned inside out; empty when there are none."""
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, len(mesh.faces))
    outer = labels[np.flatnonzero(np.any(mesh.faces == int(np.argmin(mesh.vertices[:, 0])),
                                         axis=1))[0]]
    keep = labels != outer
    if not np.any(keep):
        return trimesh.Trimesh()
    inner = trimesh.Trimesh(mesh.vertices, mesh.faces[keep][:, ::-1], process=False)
    inner.remove_unreferenced_vertices()
    return inner
