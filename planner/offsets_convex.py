"""Offsets of one convex solid, without a grid: grown, the hull of its vertices' balls
(tessellated within the error asked for); eroded, its face planes moved inward (exact).

For a convex ``P`` with face planes ``n_k · x <= d_k``:

* the erosion by ``r`` is ``{x : n_k · x <= d_k - r}`` (inside a convex solid the distance
  to the boundary is the least distance to a face plane), a convex polytope with flat
  faces only, exact up to the hull's rounding; empty when ``r`` reaches the inradius;
* the growth by ``r`` is ``P ⊕ ball(r)``. A convex polytope ``B`` inside the ball with a
  vertex ``r n_k`` for every face normal gives ``P ⊕ B``, the hull of the points
  ``v + u`` (vertices ``v`` of ``P``, ``u`` of ``B``): its flat faces are ``P``'s moved out
  by exactly ``r``, its round parts chords of the true cylinders and spheres. Minkowski sums
  are 1-Lipschitz in the Hausdorff distance, so the result lies inside the true offset and
  within ``r - c`` of it, ``c`` the least distance from the origin to a facet plane of
  ``B``. ``B`` is an icosphere of radius ``r`` at the coarsest subdivision whose bound is
  within ``eps``, plus those face-normal points.

:func:`convex_offset` returns ``None`` for a solid that is not one convex body (by every
face lying on its hull) or when the hull would take too many points; the caller then uses
the cell source, as it does when qhull cannot build a hull (a result too thin).
"""

from __future__ import annotations

import functools
import time
from typing import Any

import numpy as np
import trimesh

__all__ = ["MAX_FACES", "MAX_POINTS", "convex_offset"]

MAX_FACES = 5000
"""Solids with more triangles are not tested for convexity (the test is faces × hull
facets); the cell source takes them."""

MAX_POINTS = 2_000_000
"""Most points ``v + u`` one grown hull may take (vertices of ``P`` times those of ``B``)."""

PLANE_TOL_REL = 1e-9
"""On a plane, relative to the solid's diagonal: the convexity test's tolerance and the
rounding allowance of the hulls' bound."""

MAX_SUBDIVISIONS = 7


def convex_offset(solid: trimesh.Trimesh, radius: float, eps: float
                  ) -> tuple[trimesh.Trimesh, float, dict[str, Any]] | None:
    """``(mesh, error_bound, stats)`` of the closed solid's offset by ``radius`` when it is
    one convex body (see the module documentation), else ``None``. An erosion that leaves
    nothing gives an empty mesh."""
    t0 = time.perf_counter()
    planes = _convex_planes(solid)
    if planes is None:
        return None
    normals, offsets = planes
    diag = float(np.linalg.norm(np.ptp(np.asarray(solid.bounds), axis=0))) + 2 * abs(radius)
    rounding = PLANE_TOL_REL * diag
    from scipy.spatial import QhullError  # noqa: PLC0415

    try:
        if radius < 0:
            eroded = _eroded(normals, offsets, -radius, rounding)
            if eroded is None:
                return None
            mesh, bound, method, subdivisions = (eroded, rounding, "face planes moved inward",
                                                 None)
        else:
            grown = _grown(np.asarray(solid.vertices), normals, radius, eps)
            if grown is None:
                return None
            mesh, chord, subdivisions = grown
            bound, method = chord + rounding, "hull of the vertices' tessellated balls"
    except QhullError:  # a hull too thin for qhull: the cell source decides
        return None
    stats = {"triangles": len(mesh.faces), "band_cells": 0, "h": 0.0, "refinements": 0,
             "planar_cells": 0, "planar_pieces": 0, "planes_fallback_edges": 0,
             "bound_by_region": {"planes": rounding, "sampled": 0.0, "missed": 0.0,
                                 "round": bound - rounding if radius > 0 else 0.0},
             "holes_closed": 0, "sheets_unzipped": 0, "convex": method,
             "ball_subdivisions": subdivisions, "seconds": time.perf_counter() - t0}
    return mesh, bound, stats


def _convex_planes(solid: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray] | None:
    """The facet planes ``(unit normals, offsets)`` of the solid when it is one convex body
    (every face's centroid on its hull's boundary, its volume the hull's, within
    :data:`PLANE_TOL_REL`), else ``None``. The planes are the hull's facets (not the
    triangles': a zero-area or tilted sliver has no reliable normal), each offset the
    largest ``n · v`` over the body's vertices, so every plane bounds the body."""
    if len(solid.faces) > MAX_FACES or len(solid.faces) < 4:
        return None
    vertices = np.asarray(solid.vertices, dtype=np.float64)
    hull = _hull(vertices)
    scale = float(np.linalg.norm(np.ptp(vertices, axis=0)))
    tol = PLANE_TOL_REL * scale
    centroids = np.asarray(solid.triangles_center)
    # the largest plane value over the hull's facets: 0 on its boundary, negative inside
    height = (centroids @ hull.equations[:, :3].T + hull.equations[None, :, 3]).max(axis=1)
    if np.any(height < -tol) or abs(float(solid.volume) - hull.volume) > tol * hull.area:
        return None
    normals = hull.equations[:, :3] / np.linalg.norm(hull.equations[:, :3], axis=1)[:, None]
    normals = np.unique(np.round(normals, 12), axis=0)  # the triangulated facets' repeats
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    return normals, (vertices @ normals.T).max(axis=0)


def _eroded(normals: np.ndarray, offsets: np.ndarray, depth: float,
            rounding: float) -> trimesh.Trimesh | None:
    """``{x : n · x <= d - depth}``: the hull of its vertices, found by intersecting the
    moved half-spaces about their Chebyshev centre; empty when that centre is not deeper
    than ``depth`` (plus rounding) or none exists; ``None`` when the solver fails
    otherwise."""
    from scipy.optimize import linprog  # noqa: PLC0415
    from scipy.spatial import HalfspaceIntersection  # noqa: PLC0415

    moved = offsets - depth
    # the deepest point x and its depth t: maximise t with n · x + t <= d - depth
    res = linprog(c=[0.0, 0.0, 0.0, -1.0], A_ub=np.column_stack([normals, np.ones(len(normals))]),
                  b_ub=moved, bounds=[(None, None)] * 3 + [(0.0, None)], method="highs")
    if res.status == 2 or (res.status == 0 and res.x[3] <= rounding):  # 2: infeasible
        return trimesh.Trimesh()
    if res.status != 0:
        return None
    halfspaces = np.column_stack([normals, -moved])  # n · x - (d - depth) <= 0
    corners = HalfspaceIntersection(halfspaces, np.asarray(res.x[:3])).intersections
    return _mesh(_hull(corners))


def _grown(vertices: np.ndarray, normals: np.ndarray, radius: float,
           eps: float) -> tuple[trimesh.Trimesh, float, int] | None:
    """``(P ⊕ B, bound, subdivisions)`` for the coarsest icosphere whose chord bound
    ``r (1 - c)`` is within ``eps`` (``c``: its least facet distance on the unit sphere; the
    face-normal points added to it only make ``B`` larger, so the bound holds for ``B``);
    ``None`` when that needs more than :data:`MAX_POINTS` points or
    :data:`MAX_SUBDIVISIONS` subdivisions."""
    corners = np.unique(vertices, axis=0)  # a convex solid's vertices: its hull's, or on it
    for subdivisions in range(MAX_SUBDIVISIONS + 1):
        unit, inner = _unit_ball(subdivisions)
        chord = radius * (1.0 - inner)
        if chord > eps:
            continue
        ball = np.vstack([unit, normals]) * radius
        if len(ball) * len(corners) > MAX_POINTS:
            return None
        points = (corners[:, None, :] + ball[None, :, :]).reshape(-1, 3)
        return _mesh(_hull(points)), chord, subdivisions
    return None


@functools.lru_cache(maxsize=None)
def _unit_ball(subdivisions: int) -> tuple[np.ndarray, float]:
    """The unit icosphere's vertices and the least distance from its centre to a facet
    plane."""
    sphere = _hull(trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0).vertices)
    return np.asarray(sphere.points[sphere.vertices]), float(-sphere.equations[:, 3].max())


def _hull(points: np.ndarray):
    """Qhull's convex hull of ``points`` (triangulated facets, outward ``equations``)."""
    from scipy.spatial import ConvexHull  # noqa: PLC0415

    return ConvexHull(points, qhull_options="Qt")


def _mesh(hull) -> trimesh.Trimesh:
    """A hull's triangles as a closed, outward mesh on the vertices they use."""
    faces = np.asarray(hull.simplices, dtype=np.int64)
    points = np.asarray(hull.points)
    a, b, c = (points[faces[:, k]] for k in range(3))
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    faces[inward] = faces[inward][:, ::-1]
    used, faces = np.unique(faces, return_inverse=True)
    return trimesh.Trimesh(points[used], faces.reshape(-1, 3), process=False)
