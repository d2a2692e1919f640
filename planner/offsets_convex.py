"""Offsets of a convex solid (or one convex up to its file's rounding), without a grid:
grown, its hull's facets, edges and corners moved out and tessellated within the error
asked for (else the hull of its vertices' tessellated balls); eroded, its hull's facet
planes moved inward.

For the hull ``H = {x : n_k · x <= d_k}`` of the solid ``P``'s vertices:

* ``H`` eroded by ``r`` is ``{x : n_k · x <= d_k - r}`` (inside a convex solid the
  distance to the boundary is the least distance to a facet plane), flat faces only;
  empty when ``r`` reaches the inradius;
* ``H`` grown by ``r`` is ``H ⊕ ball(r)``: its boundary is ``H``'s facets moved out by
  ``r``, cylinders over its edges and spheres at its corners. The core
  (``rounded_polytope``) tessellates them along ``H``'s own structure, no hull computed:
  the facets exactly flat, each edge's cylinder a strip over its dihedral arc, each
  corner's sphere patch graded rows over its normal cone, the round points a hair outside
  ``r`` so the chords' sag is split between the two sides (the bound is measured on the
  triangles: see ``minkowski_core/src/polytope/rounded.rs``), points closer than
  :data:`MERGE_REL` of the size welded (the bound adds the move). A hull with more
  corners than the tolerance needs (a CAD cylinder's many sides) is also grown from the
  hull of fewer of them, its measured gap taken from the tolerance and added to the bound
  (growing is 1-Lipschitz), and the one with fewer triangles kept. When that is not
  possible (too many triangles, a weld that would open the surface), the hull of the
  points ``v + u`` (vertices ``v`` of ``H``, ``u`` of an icosphere of radius ``r``) and of
  every facet's corners moved ``r`` along its normal holds ``H ⊕ icosphere`` and lies
  inside the true offset: its flat faces are ``H``'s moved out by exactly ``r``, its round
  parts chords of the true cylinders and spheres. Minkowski sums are 1-Lipschitz in the
  Hausdorff distance, so it lies within the chord ``r (1 - c)`` of the true offset, ``c``
  the least distance from the centre to a facet plane of the unit icosphere, the coarsest
  subdivision whose chord is within ``eps``. A point ``v + u`` is a vertex only where
  some direction finds both ``v`` and ``u`` extreme: pairs whose normal cones lie apart
  are left out beforehand.

``P`` need not be ``H`` exactly (CAD exports round their coordinates): with ``t`` a
depth such that every triangle of ``P`` has all its corners within ``t`` of one facet
plane of ``H`` (about the least), ``P``'s boundary misses the inside of
``H_t = {x : n_k · x <= d_k - t}``, so one winding number at a point inside ``H_t``
shows ``H_t ⊂ P ⊂ H``. Offsets are monotone, so ``P``'s lies between ``H_t``'s and
``H``'s, and the bound adds their distance: at most ``t R / ρ`` (``ρ`` the depth of
``H``'s deepest point, ``R`` the farthest corner from it: ``H_t`` holds ``H`` shrunk about
that point by ``1 - t/ρ``), else measured: the largest distance from a vertex of the
larger to the smaller (a convex function of the point, so its maximum over a polytope is
at a vertex). The path is taken only when the bound is within ``eps``.

:func:`convex_offset` returns ``None`` otherwise (not convex enough, too many faces or
points, qhull unable to build a hull); the caller then uses the cell source.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh

from .errors import InvalidMeshError, InvalidParameterError
from .meshes.closest import closest_points_on_triangles

__all__ = ["BALL_CONE_ANGLE", "BALL_INNER", "CLOSED", "MAX_FACES", "MAX_POINTS", "ROUNDED",
           "Declined", "convex_closing", "convex_hull", "convex_offset", "hull_mesh",
           "measured_ball", "merge_distance", "representatives", "rounding_allowance", "unit_ball"]

log = logging.getLogger(__name__)

MAX_FACES = 200_000
"""Solids with more triangles are left to the cell source (qhull and the tessellation
grow with them; an icosphere of 5 subdivisions has 20,480)."""

MAX_POINTS = 2_000_000
"""Most points ``v + u`` one grown hull may take (vertices of ``H`` times those of ``B``)."""

PLANE_TOL_REL = 1e-9
"""Relative to the solid's diagonal: the rounding allowance added to every bound."""

MAX_SUBDIVISIONS = 7

MAX_ROUNDED_TRIANGLES = 4_000_000
"""Most triangles the rounded hull (:func:`_rounded`) may make: the core keeps about 120
bytes per triangle while it builds them, so about 0.5 GB."""

ROUNDED = "facets moved out, edges' cylinders and corners' spheres tessellated"
"""``stats["convex"]`` of a grown convex solid tessellated along its own structure."""

CLOSED = "a convex solid is its own closing"
"""``stats["convex"]`` of a closing the solid itself gives (:func:`convex_closing`)."""

MERGE_REL = 1e-6
"""Grown hulls' points closer than this, relative to their size and distance from the
origin, are one (a float32 file keeps about 7 digits), unless that is more than
:data:`MERGE_EPS_SHARE` of the tolerance (:func:`merge_distance`)."""

MERGE_EPS_SHARE = 1.0 / 16.0
"""The most of the tolerance a merge of close points may take: far from the origin (a
0.2 sphere at x = 1000) 1e-6 of the distance would be more than the whole tolerance."""


def convex_offset(solid: trimesh.Trimesh, radius: float, eps: float,
                  why: list[str] | None = None
                  ) -> tuple[trimesh.Trimesh, float, dict[str, Any]] | None:
    """``(mesh, error_bound, stats)`` of the closed solid's offset by ``radius`` by its
    hull (see the module documentation), or ``None``, with the reason appended to ``why``
    (a phrase about the solid). An erosion that leaves nothing gives an empty mesh."""
    from scipy.spatial import QhullError  # noqa: PLC0415

    t0 = time.perf_counter()
    rounding = rounding_allowance(solid, radius)
    try:
        hull, deepest = _between_hulls(solid, eps)
        extra: dict[str, Any] = {}
        if radius < 0:
            mesh, between, sheet = _eroded(hull, -radius, rounding, eps)
            method, subdivisions, chord = "hull's facet planes moved inward", None, 0.0
            extra = {"sheet_left": sheet} if sheet else {}
        else:
            # growing is 1-Lipschitz: the grown H and H_t are no farther apart than H, H_t
            between, measured = _hull_gap(hull, deepest, eps)
            # (less a few ulps of eps: the sums below must not round past it)
            left = eps - between - rounding - 8 * math.ulp(eps)
            rounded = _rounded_from_fewest(hull, radius, left)
            if rounded is not None:
                mesh, chord, extra = rounded
                subdivisions, method = None, ROUNDED
            else:
                grown = _grown(hull, radius, eps)
                if grown is None:
                    _declined(why, "is convex, but its grown hull would need more than "
                                   f"{MAX_POINTS:,} points or a finer ball than "
                                   f"{MAX_SUBDIVISIONS} subdivisions")
                    return None
                mesh, chord, subdivisions = grown
                if chord + between + rounding > eps and not measured:
                    between = min(between, _gap_exact(hull, eps))
                method = "hull of the vertices' tessellated balls"
    except QhullError:  # a hull too thin for qhull: the cell source decides
        _declined(why, "has a hull too thin or flat for qhull")
        return None
    except Declined as declined:
        _declined(why, str(declined))
        return None
    bound = chord + between + rounding
    if len(mesh.faces) and bound > eps:
        _declined(why, f"is convex, but its hull's offset has a bound of {bound:.3g}, "
                       f"above eps")
        return None
    stats = {"triangles": len(mesh.faces), "band_cells": 0, "h": 0.0, "refinements": 0,
             "planar_cells": 0, "planar_pieces": 0, "planar_regions": 0,
             "planar_fanned": 0, "planar_straight_dropped": 0, "planar_unfolded": 0,
             "planes_fallback_edges": 0,
             "bound_by_region": {"planes": between + rounding, "sampled": 0.0, "missed": 0.0,
                                 "round": chord},
             "holes_closed": 0, "sheets_unzipped": 0, "sheets_apart": 0.0, "convex": method,
             "hull_depth": hull.depth, "ball_subdivisions": subdivisions, **extra,
             "seconds": time.perf_counter() - t0}
    return mesh, bound, stats


def convex_closing(solid: trimesh.Trimesh, eps: float) -> tuple[float, dict[str, Any]] | None:
    """``(bound, stats)`` when the closed solid is convex up to ``eps``: it is then its own
    closing by any radius, within ``bound`` (Hausdorff); ``None`` otherwise. A closing
    holds its input and lies inside every half-space that does (a half-space grown and
    eroded by as much is itself, and both are monotone), so ``P ⊆ closing(P) ⊆ H``; with
    ``H_t ⊂ P`` (the module documentation) every point of the closing lies within the
    distance from ``H`` to ``H_t`` of ``P``."""
    from scipy.spatial import QhullError  # noqa: PLC0415

    t0 = time.perf_counter()
    try:
        hull, deepest = _between_hulls(solid, eps)
        between, _ = _hull_gap(hull, deepest, eps)
    except (QhullError, Declined):
        return None
    bound = between + rounding_allowance(solid, 0.0)
    if bound > eps:
        return None
    return bound, {"triangles": len(solid.faces), "convex": CLOSED,
                   "hull_depth": hull.depth, "seconds": time.perf_counter() - t0}


class Declined(Exception):
    """Why a solid is not offset by its hull (a phrase about it: "has ...", "is ...")."""


def _declined(why: list[str] | None, reason: str) -> None:
    """The reason appended to ``why`` (when given) and logged."""
    log.debug("the hull method declines: the solid %s", reason)
    if why is not None:
        why.append(reason)


def _between_hulls(solid: trimesh.Trimesh, eps: float
                   ) -> tuple[_Hull, tuple[np.ndarray, float]]:
    """The solid's hull ``H`` and a point inside ``H_t`` with its depth, when ``H_t ⊂ P ⊂
    H`` with the depth ``t`` within ``eps`` (see the module documentation): the point is
    inside the solid by one winding number exactly when ``H_t`` is. :class:`Declined`
    otherwise."""
    hull = _hull_planes(solid, eps)
    deepest = _inner_point(hull, eps)
    if deepest is None:
        raise Declined("has a hull whose deepest point the solver did not find")
    if deepest[1] <= hull.depth:
        raise Declined(f"is convex only to {hull.depth:.3g}, as deep as its hull's inside")
    if not _inside_at(solid, deepest[0]):
        raise Declined("does not hold the inside of its hull (its winding number there is "
                       "not 1)")
    return hull, deepest


def rounding_allowance(solid: trimesh.Trimesh, radius: float) -> float:
    """:data:`PLANE_TOL_REL` of the diagonal of the solid's box grown by ``|radius|``: the
    rounding every offset's bound adds."""
    extent = np.ptp(np.asarray(solid.bounds), axis=0)
    return PLANE_TOL_REL * (float(np.linalg.norm(extent)) + 2 * abs(radius))


@dataclass(frozen=True)
class _Hull:
    """The hull ``H`` of a solid's vertices: its distinct facet planes (unit ``normals``,
    ``offsets`` each the largest ``n · v`` over the vertices, so every plane bounds them:
    :func:`_plane_offsets`), the ``depth`` ``t`` within which every triangle of the solid
    has its corners on one of them, its ``corners`` (vertices), and its triangles' corners
    (``triangles``, (k, 3, 3)) with their unit normals (``triangle_normals``); per
    corner, a circular cone holding its normal cone (the directions in which it is
    extreme): unit ``cone_axes`` and half-angles ``cone_angles``."""

    normals: np.ndarray
    offsets: np.ndarray
    depth: float
    corners: np.ndarray
    triangles: np.ndarray
    triangle_normals: np.ndarray
    cone_axes: np.ndarray
    cone_angles: np.ndarray


def _hull_planes(solid: trimesh.Trimesh, eps: float) -> _Hull:
    """The solid's :class:`_Hull`; :class:`Declined` when its depth exceeds ``eps`` or it
    has too many triangles."""
    if len(solid.faces) > MAX_FACES:
        raise Declined(f"has {len(solid.faces):,} triangles, more than the hull method takes "
                       f"({MAX_FACES:,})")
    if len(solid.faces) < 4:
        raise Declined(f"has {len(solid.faces)} triangles")
    vertices = np.asarray(solid.vertices, dtype=np.float64)
    hull = convex_hull(vertices, keep_coplanar=True)
    triangle_normals = hull.equations[:, :3] / np.linalg.norm(hull.equations[:, :3],
                                                              axis=1)[:, None]
    # coplanar triangles' repeats are one plane
    normals, plane_of = np.unique(np.round(triangle_normals, 12), axis=0, return_inverse=True)
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = _plane_offsets(vertices, hull, normals, plane_of.ravel())
    depth = _depth(vertices, np.asarray(solid.faces), normals, offsets, eps)
    if depth > eps:
        raise Declined(f"is not convex within eps {eps:.3g}: some triangle lies deeper than "
                       f"that inside its hull")
    used = np.sort(hull.vertices)
    axes, angles = _normal_cones(np.searchsorted(used, hull.simplices), triangle_normals,
                                 len(used))
    return _Hull(normals, offsets, depth, vertices[used], vertices[hull.simplices],
                 triangle_normals, axes, angles)


def _plane_offsets(vertices: np.ndarray, hull, normals: np.ndarray, plane_of: np.ndarray
                   ) -> np.ndarray:
    """Per plane, the largest ``n · v`` over the corners of the ``hull``'s triangles on it
    (``plane_of``) and the vertices qhull left out as on one of them (``coplanar``: it
    keeps no point that lies above a facet by more than its precision, but keeps within it
    some that do): the largest over every vertex. Linear in the triangles: every vertex
    against every plane was quadratic (an icosphere of 20k triangles: 1.7 GB and 5 s)."""
    heights = np.einsum("tkj,tj->tk", vertices[hull.simplices], normals[plane_of]).max(axis=1)
    offsets = np.full(len(normals), -np.inf)
    np.maximum.at(offsets, plane_of, heights)
    if len(hull.coplanar):
        point, planes = hull.coplanar[:, 0], plane_of[hull.coplanar[:, 1]]
        np.maximum.at(offsets, planes, np.einsum("pj,pj->p", vertices[point], normals[planes]))
    return offsets


def _depth(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray,
           offsets: np.ndarray, eps: float) -> float:
    """A ``t`` such that every triangle has its corners within ``t`` below one of the
    planes (any plane gives such a ``t``; the least is sought): each triangle's depth below
    the plane nearest its own normal (a k-d tree over the unit normals), and where that is
    farther than ``eps``, the least over every plane, or over the :data:`NEAR_PLANES`
    nearest its normal when every plane would be too many (:data:`FULL_SEARCH`); the
    search stops at the first piece of triangles with one deeper than ``eps`` below all
    it tries (the ``t`` returned then exceeds ``eps``, by an amount that means nothing).
    In pieces of at most :data:`DEPTH_ENTRIES` triangle corners times planes."""
    from scipy.spatial import cKDTree  # noqa: PLC0415

    corners = vertices[faces]                                       # (faces, 3, 3)
    own = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(own, axis=1)
    flat = length == 0  # no normal: its nearest plane is the first, as any would do
    own = np.where(flat[:, None], normals[0], own / np.where(flat, 1.0, length)[:, None])
    tree = cKDTree(normals)
    nearest = tree.query(own)[1]
    depths = (offsets[nearest][:, None]
              - np.einsum("fkj,fj->fk", corners, normals[nearest])).max(axis=1)
    far = np.flatnonzero(depths > eps)
    near = len(far) * len(normals) > FULL_SEARCH
    tried = min(NEAR_PLANES, len(normals)) if near else len(normals)
    step = _rows_at_once(3 * tried)
    for k in range(0, len(far), step):
        # per far triangle and plane tried, the deepest corner's depth; per triangle, its
        # best
        rows = far[k:k + step]
        if near:
            planes = tree.query(own[rows], k=tried)[1].reshape(len(rows), -1)
            below = offsets[planes][:, None, :] - np.einsum("fkj,fpj->fkp", corners[rows],
                                                            normals[planes])
        else:
            below = offsets[None, None, :] - corners[rows] @ normals.T  # (rows, 3, planes)
        depths[rows] = np.minimum(depths[rows], below.max(axis=1).min(axis=1))
        if depths[rows].max() > eps:
            break
    return float(depths.max())


DEPTH_ENTRIES = 9_000_000
"""Most entries (points times planes or directions) one product holds at once in
:func:`_depth`, :func:`_gap` and :func:`_fewer_corners` (72 MB of floats, a few times
that with the arrays made from it)."""


def _rows_at_once(columns: int) -> int:
    """Rows of a product with ``columns`` columns that keep it within
    :data:`DEPTH_ENTRIES`."""
    return max(1, DEPTH_ENTRIES // max(columns, 1))


def _extreme(points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The distinct indices of the points extreme in each direction (sorted), the
    directions taken a piece at a time."""
    step = _rows_at_once(len(points))
    return np.unique(np.concatenate([np.argmax(points @ directions[k:k + step].T, axis=0)
                                     for k in range(0, len(directions), step)]))

FULL_SEARCH = 50_000_000
"""Most far triangles times planes :func:`_depth` searches in full; beyond it each far
triangle tries the :data:`NEAR_PLANES` planes nearest its normal (a larger ``t``, at worst:
the hull path is then declined, never wrong)."""

NEAR_PLANES = 32
"""Planes a far triangle of a large solid tries (:data:`FULL_SEARCH`)."""


def _normal_cones(corners_of: np.ndarray, triangle_normals: np.ndarray, count: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Per corner of a convex polytope (``count`` of them; ``corners_of``: each triangle's
    three), the axis (its triangles' mean normal) and the half-angle of a circular cone
    around it that holds every normal of its triangles, so their conic hull when the
    half-angle is below 90°."""
    sums = np.zeros((count, 3))
    for k in range(3):
        np.add.at(sums, corners_of[:, k], triangle_normals)
    axes = sums / np.linalg.norm(sums, axis=1)[:, None]
    cosines = np.ones(count)
    for k in range(3):
        at = corners_of[:, k]
        np.minimum.at(cosines, at, np.einsum("ij,ij->i", axes[at], triangle_normals))
    return axes, np.arccos(np.clip(cosines, -1.0, 1.0))


def _inside_at(solid: trimesh.Trimesh, point: np.ndarray) -> bool:
    """Whether ``point`` lies inside the closed solid (the core's exact winding number)."""
    from ._minkowski_core import winding_numbers  # noqa: PLC0415

    return int(winding_numbers(np.asarray(solid.vertices, dtype=np.float64),
                               np.asarray(solid.faces, dtype=np.int64),
                               point.reshape(1, 3))[0]) == 1


def _hull_gap(hull: _Hull, deepest: tuple[np.ndarray, float], eps: float
              ) -> tuple[float, bool]:
    """``(a bound on the distance from H to H_t, whether it was measured)``: the cheap
    bound of :func:`_gap_bound` about the inner point ``deepest``, measured
    (:func:`_gap_exact`) only when that is over a quarter of ``eps``."""
    between = _gap_bound(hull, *deepest)
    if between <= eps / 4:
        return between, False
    return min(between, _gap_exact(hull, eps)), True


def _gap_bound(hull: _Hull, centre: np.ndarray, inradius: float) -> float:
    """An upper bound on the distance from ``H`` to ``H_t``: ``H_t`` holds ``H`` scaled
    about its deepest point ``c`` (depth ``ρ``) by ``1 - t/ρ`` (a plane ``ρ`` or more from
    ``c`` moves in by at least ``t``), so no point of ``H`` is farther from ``H_t`` than
    ``t/ρ`` times its distance from ``c``."""
    if hull.depth == 0:
        return 0.0
    return hull.depth / inradius * float(np.linalg.norm(hull.corners - centre, axis=1).max())


def _gap_exact(hull: _Hull, eps: float) -> float:
    """The distance from ``H`` to ``H_t`` (their Hausdorff distance) measured to ``H_t``'s
    mesh: at least that distance (the mesh's merged corners keep it inside ``H_t``)."""
    inner = _planes_hull(hull.normals, hull.offsets - hull.depth, eps)
    return math.inf if inner is None else _gap(hull.corners, inner[0])


def _gap(points: np.ndarray, smaller: trimesh.Trimesh) -> float:
    """The largest distance from the ``points`` (a convex polytope's corners) to the
    convex mesh ``smaller`` inside it (their Hausdorff distance), exact to rounding: a
    point outside a convex polytope is nearest a facet whose plane it lies in front of
    (``p - q`` is a positive mix of the normals at ``q``, so it makes a positive dot
    product with one of them), so only those facets are measured."""
    normals = np.asarray(smaller.face_normals)
    heights = np.einsum("fj,fj->f", normals, smaller.triangles[:, 0])
    step = _rows_at_once(len(normals))
    gap = 0.0
    for start in range(0, len(points), step):
        chunk = points[start:start + step]
        point, facet = np.nonzero(chunk @ normals.T - heights > 0)
        if len(point) == 0:
            continue
        nearest = closest_points_on_triangles(smaller.triangles[facet], chunk[point])
        distance = np.full(len(chunk), np.inf)
        np.minimum.at(distance, point, np.linalg.norm(chunk[point] - nearest, axis=1))
        gap = max(gap, float(np.max(distance[np.isfinite(distance)])))
    return gap


def _eroded(hull: _Hull, r: float, rounding: float, eps: float
            ) -> tuple[trimesh.Trimesh, float, float]:
    """``(H eroded by r, a bound on its distance to H_t eroded by r, the thickness of what
    is left when that is too thin to mesh)``. Nothing is left when ``H`` eroded has no
    point deeper than the rounding allowance; what is left is a sheet no thicker than twice
    its deepest point's depth, too thin to mesh when that depth is within the distance
    corners are merged by (:func:`merge_distance`: its two sides would be one): both give
    an empty mesh (``P`` eroded lies inside ``H`` eroded). With the mesh's corners merged
    by ``m``: first the bound of :func:`_gap_bound` about the eroded ``H``'s deepest point
    (``H_t`` eroded is the eroded ``H``'s planes moved in by ``t``), its corners taken ``m``
    farther, plus ``2 m``; when that exceeds a quarter of ``eps``, the gap measured from
    the mesh's corners (inside ``H_t`` eroded: at least the true one) plus ``m`` for the
    corners merged away, plus ``m`` for the mesh's own distance to ``H`` eroded."""
    deepest = _deepest_point(hull.normals, hull.offsets - r)
    if deepest is None or deepest[1] <= rounding:
        return trimesh.Trimesh(), 0.0, 0.0
    if deepest[1] <= merge_distance(hull.corners, 0.0, eps):
        return trimesh.Trimesh(), deepest[1], 2.0 * deepest[1]
    centre = deepest[0]
    mesh, merged = _hull_about(hull.normals, hull.offsets - r, centre, eps)
    if hull.depth == 0:
        return mesh, merged, 0.0
    depth = float(np.min(hull.offsets - r - hull.normals @ centre))
    if depth > hull.depth:
        farthest = float(np.linalg.norm(mesh.vertices - centre, axis=1).max()) + merged
        cheap = hull.depth / depth * farthest + 2.0 * merged
        if cheap <= eps / 4:
            return mesh, cheap, 0.0
    inner = _planes_hull(hull.normals, hull.offsets - r - hull.depth, eps, rounding)
    if inner is None:  # H_t eroded is empty, H eroded is not: the whole of it is between
        return mesh, float(np.ptp(mesh.vertices, axis=0).max()), 0.0
    return mesh, _gap(np.asarray(mesh.vertices), inner[0]) + 2.0 * merged, 0.0


def _planes_hull(normals: np.ndarray, offsets: np.ndarray, eps: float, thinnest: float = 0.0
                 ) -> tuple[trimesh.Trimesh, np.ndarray, float] | None:
    """``({x : n · x <= d}, its deepest point, how far its corners were merged)``: the
    hull of the half-spaces' corners (:func:`_merged_hull`), found about the deepest point;
    ``None`` when that point is no deeper than ``thinnest`` (nothing, or a sheet, is left)
    or the solver fails."""
    deepest = _deepest_point(normals, offsets)
    if deepest is None or deepest[1] <= thinnest:
        return None
    mesh, merged = _hull_about(normals, offsets, deepest[0], eps)
    return mesh, deepest[0], merged


def _hull_about(normals: np.ndarray, offsets: np.ndarray, inside: np.ndarray, eps: float
                ) -> tuple[trimesh.Trimesh, float]:
    """``({x : n · x <= d}, how far its corners were merged)``: the hull of the
    half-spaces' corners (:func:`_merged_hull`), found about a point ``inside`` it."""
    from scipy.spatial import HalfspaceIntersection  # noqa: PLC0415

    corners = HalfspaceIntersection(np.column_stack([normals, -offsets]), inside).intersections
    return _merged_hull(corners, eps)


def _merged_hull(points: np.ndarray, eps: float) -> tuple[trimesh.Trimesh, float]:
    """``(the hull of the points, how far they moved)``: points closer than
    :func:`merge_distance` are one first (a float32 file's nearly coplanar triangles give
    corners or planes a few 1e-10 apart, which a reader's weld would join into edges of
    four triangles); that moves the hull by at most that distance (none when none were
    merged)."""
    merge = merge_distance(points, 0.0, eps)
    kept = representatives(points, merge)
    return hull_mesh(convex_hull(points[kept])), merge if len(kept) < len(points) else 0.0


def _inner_point(hull: _Hull, eps: float) -> tuple[np.ndarray, float] | None:
    """``(x, t)``: a point inside ``H`` and its depth, for the winding test and the gap
    bound: the mean of ``H``'s corners when it lies deeper than ``H``'s depth and its gap
    bound is within a quarter of ``eps`` (always for a solid that is its own hull), else
    ``H``'s deepest point (a linear program)."""
    centre = hull.corners.mean(axis=0)
    depth = float(np.min(hull.offsets - hull.normals @ centre))
    if depth > hull.depth and _gap_bound(hull, centre, depth) <= eps / 4:
        return centre, depth
    return _deepest_point(hull.normals, hull.offsets)


def _deepest_point(normals: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, float] | None:
    """``(x, t)`` maximising ``t`` with ``n · x + t <= d`` for the unit normals (the
    Chebyshev centre of ``{x : n · x <= d}`` and its depth), ``t >= 0``; ``None`` when
    the half-spaces leave nothing or the solver fails."""
    from scipy.optimize import linprog  # noqa: PLC0415

    res = linprog(c=[0.0, 0.0, 0.0, -1.0], A_ub=np.column_stack([normals, np.ones(len(normals))]),
                  b_ub=offsets, bounds=[(None, None)] * 3 + [(0.0, None)], method="highs")
    if res.status != 0:
        return None
    # the depth the point really has (the solver's is within its tolerance of it)
    centre = np.asarray(res.x[:3])
    return centre, float(np.min(offsets - normals @ centre))


def _grown(hull: _Hull, radius: float, eps: float
           ) -> tuple[trimesh.Trimesh, float, int] | None:
    """``(mesh, chord, subdivisions)``: the hull of ``H``'s corners each grown by the
    coarsest icosphere whose chord ``r (1 - c)`` is within ``eps`` (``c``: its least facet
    distance on the unit sphere), and of each triangle's corners moved ``r`` along its
    normal. It holds ``H ⊕ icosphere`` (within the chord of the true offset) and lies
    inside the true offset, so the chord bounds it; the moved corners make the flat faces
    exactly ``r`` out. ``None`` when that needs more than :data:`MAX_POINTS` points or
    :data:`MAX_SUBDIVISIONS` subdivisions."""
    moved = (hull.triangles + radius * hull.triangle_normals[:, None, :]).reshape(-1, 3)
    for subdivisions in range(MAX_SUBDIVISIONS + 1):
        if radius * (1.0 - BALL_INNER[subdivisions]) > eps:
            continue
        unit, inner = unit_ball(subdivisions)
        chord = radius * (1.0 - inner)
        if len(unit) * len(hull.corners) > MAX_POINTS:
            return None
        corner, direction = _extreme_pairs(hull, unit, ball_cone_angle(subdivisions))
        mesh, merged = _merged_hull(np.vstack([hull.corners[corner] + radius * unit[direction],
                                               moved]), eps)
        return mesh, chord + merged, subdivisions
    return None


def _rounded_from_fewest(hull: _Hull, radius: float, tol: float
                         ) -> tuple[trimesh.Trimesh, float, dict[str, Any]] | None:
    """:func:`_rounded` of ``H``, or of the hull of fewer of its corners
    (:func:`_fewer_corners`, its gap taken from the tolerance and added to the bound),
    whichever has fewer triangles: the thinning saves the many sides' strips and corners
    but leaves the round parts less tolerance (the Factory peg at eps 4e-4: 692 triangles
    thinned, 4,092 not; at 2e-5 thinned to 392 corners, 12,844 against 7,260). ``H``
    itself is not tessellated when the thinned one has no more triangles than ``H``'s
    would at least (its facets' triangles, moved out, twice over for the edges' strips,
    and about one per corner)."""
    corners = hull.corners
    fewer, gap = _fewer_corners(corners, THIN_SHARE * tol)
    thinned = _rounded(fewer, radius, tol - gap) if gap > 0 else None
    if thinned is not None:
        mesh, bound, stats = thinned
        thinned = mesh, bound + gap, {**stats, "round_corners": len(fewer), "round_thinned": gap}
        if len(mesh.faces) <= 2 * len(hull.triangles) + len(corners):
            return thinned
    every = _rounded(corners, radius, tol)
    if every is not None:
        every = every[0], every[1], {**every[2], "round_corners": len(corners),
                                     "round_thinned": 0.0}
    if thinned is None or (every is not None and len(every[0].faces) <= len(thinned[0].faces)):
        return every
    return thinned


def _fewer_corners(corners: np.ndarray, budget: float) -> tuple[np.ndarray, float]:
    """``(kept, gap)``: corners of ``H`` whose hull ``K`` lies within ``gap <= budget`` of
    ``H`` (Hausdorff: :func:`_gap`), or all of them (gap 0) when no such thinning keeps
    markedly fewer. ``K ⊂ H``, and growing is 1-Lipschitz, so ``K``'s offset is within
    ``gap`` of ``H``'s: a faceted cylinder's many sides, each with its edge strip and
    corner patches, take far fewer triangles at a tolerance its facets are finer than.
    Kept: the extreme corner in each of ``n`` directions spread over the sphere
    (:func:`_directions`), from :data:`THIN_START` on. The gap goes as ``1 / n`` on round
    surfaces (a sphere's corners) and as ``1 / n²`` along round edges (a cylinder's rims),
    so a try over the budget is followed by one with ``n`` scaled by the square root of
    their ratio (and a margin), and later ones by the power the last two tries measured."""
    from scipy.spatial import QhullError  # noqa: PLC0415

    if budget <= 0 or len(corners) <= 8:
        return corners, 0.0
    count, power, last = THIN_START, 0.5, None
    for _ in range(THIN_TRIES):
        if count > THIN_ENOUGH * len(corners):
            break
        kept = _extreme(corners, _directions(count))
        if len(kept) > THIN_ENOUGH * len(corners):
            break
        try:  # the kept corners are on their hull
            gap = _gap(np.delete(corners, kept, axis=0), hull_mesh(convex_hull(corners[kept])))
        except QhullError:
            break
        if gap <= budget:
            return corners[kept], gap
        if last is not None and 0 < gap < last[1]:
            # the gap went as count^-1/power between the last two tries
            power = min(max(math.log(count / last[0]) / math.log(last[1] / gap), 0.5), 1.0)
        last = count, gap
        count = math.ceil(count * max(THIN_AIM * (gap / budget) ** power, 1.5))
    return corners, 0.0


THIN_SHARE = 0.5
"""Of the tolerance a grown hull's tessellation has, the share its corners may be thinned
by (:func:`_fewer_corners`)."""

THIN_START = 64
"""Directions :func:`_fewer_corners` tries first."""

THIN_TRIES = 5
"""Direction spreads :func:`_fewer_corners` tries at most."""

THIN_AIM = 1.2
"""A try whose gap is over the budget is followed by one with this much more than the
gap's ratio to it, raised to the power measured (at first one half), times its
directions."""

THIN_ENOUGH = 0.7
"""A thinning that keeps (or tries directions for) more than this share of the corners is
not worth its gap."""


def _directions(count: int) -> np.ndarray:
    """``count`` unit vectors spread about evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    ring = np.sqrt(1.0 - z * z)
    return np.column_stack([ring * np.cos(phi), ring * np.sin(phi), z])


def _rounded(corners: np.ndarray, radius: float, tol: float
             ) -> tuple[trimesh.Trimesh, float, dict[str, Any]] | None:
    """``(mesh, bound, stats)``: the hull ``H`` of the ``corners`` grown by ``radius`` and
    tessellated along its own facets, edges and corners by the core (:data:`ROUNDED`), its
    two-sided ``bound`` within ``tol``. Points closer than :data:`MERGE_REL` of the size are welded
    (a float32 file's nearly coplanar facets meet at angles of 1e-6, their moved corners
    that times ``r`` apart, which a reader would weld into edges of four triangles); the
    bound adds how far that moved them. ``None`` when the core refuses (more than
    :data:`MAX_ROUNDED_TRIANGLES`, or a weld that would open the surface or turn a
    triangle over): the hull of the tessellated balls takes those."""
    from ._minkowski_core import rounded_polytope  # noqa: PLC0415

    if tol <= 0:
        return None
    corners = np.ascontiguousarray(corners, dtype=np.float64)
    merge = merge_distance(corners, radius, tol)
    try:
        out = rounded_polytope(corners, radius, tol, merge, MAX_ROUNDED_TRIANGLES)
    except (InvalidMeshError, InvalidParameterError) as error:
        log.debug("the rounded hull is not used: %s", error)
        return None
    mesh = trimesh.Trimesh(out["vertices"], out["faces"], process=False)
    return mesh, float(out["bound"]), {"round_step": float(out["step"]),
                                       "round_scale": float(out["scale"]),
                                       "round_welded": float(out["welded"])}


def _extreme_pairs(hull: _Hull, unit: np.ndarray, ball_angle: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (corner ``v`` of ``H``, vertex ``u`` of the unit icosphere) whose point
    ``v + r u`` can be a vertex of ``H ⊕ icosphere``: some direction must find both
    extreme, so their normal cones must meet. The icosphere's lie within ``ball_angle``
    of ``u``, ``H``'s within the corner's circular cone; pairs whose cones are farther
    apart than that are left out (a corner whose cone is 90° or wider keeps every ``u``).
    The hull of the points is the same."""
    margin = 1e-6
    reach = hull.cone_angles + ball_angle + margin
    cosines = hull.cone_axes @ unit.T                         # (corners, directions)
    keep = (cosines >= np.cos(np.minimum(reach, np.pi))[:, None]) \
        | (hull.cone_angles >= np.pi / 2)[:, None]
    corner, direction = np.nonzero(keep)
    return corner, direction


def merge_distance(points: np.ndarray, radius: float, eps: float) -> float:
    """How close points are merged: :data:`MERGE_REL` of the points' size plus their
    distance from the origin and ``radius``, at most :data:`MERGE_EPS_SHARE` of ``eps``."""
    size = float(np.max(np.abs(points)) + np.ptp(points, axis=0).max() + radius)
    return min(MERGE_REL * size, MERGE_EPS_SHARE * eps)


def representatives(points: np.ndarray, radius: float) -> np.ndarray:
    """Indices of one point per cluster: each point in order is kept unless a kept one
    lies within ``radius`` of it."""
    from scipy.spatial import cKDTree  # noqa: PLC0415

    if len(points) == 0 or radius <= 0:
        return np.arange(len(points))
    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return np.arange(len(points))
    # only points with a neighbour can be dropped: walk those in order
    both = np.vstack([pairs, pairs[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    starts = np.searchsorted(both[:, 0], np.arange(len(points) + 1))
    dropped = np.zeros(len(points), dtype=bool)
    for i in np.unique(both[:, 0]):
        if not dropped[i]:
            dropped[both[starts[i]:starts[i + 1], 1]] = True
    # a kept point's neighbours are dropped; itself only by an earlier kept one
    return np.flatnonzero(~dropped)


BALL_INNER = (0.7946544722917661, 0.9341723589627156, 0.982246946376846,
              0.9954716323905444, 0.9988621167296411, 0.9997151646458344,
              0.9999287683373553, 0.9999821906571972)
"""Per subdivision of the unit icosphere (``0 .. MAX_SUBDIVISIONS``), the least distance
from its centre to a facet plane (:func:`measured_ball`: a test checks them), so the
coarsest fine enough is chosen without building the finer ones: a first offset in a
process built and hulled every icosphere up to the one it took (27 ms of a box's 49)."""

BALL_CONE_ANGLE = (0.6523581397843682, 0.36486382811348356, 0.18871053078356245,
                   0.09520283008485891, 0.04770951964236602, 0.0238683420897177,
                   0.01193587100459241, 0.00596814806538639)
"""Per subdivision, the largest angle between a vertex of the unit icosphere and the
normal of a facet at it: each vertex's normal cone lies within that angle of the
vertex (:func:`measured_ball`)."""


@functools.lru_cache(maxsize=None)
def unit_ball(subdivisions: int) -> tuple[np.ndarray, float]:
    """The unit icosphere's vertices and the least distance from its centre to a facet
    plane, measured on its own triangles (what :data:`BALL_INNER` tables, so a bound
    stays its own whatever trimesh builds)."""
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    unit = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    corners = unit[sphere.faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    inner = float(np.min(np.abs(np.einsum("ij,ij->i", normals, corners[:, 0]))))
    return np.ascontiguousarray(unit), inner


def ball_cone_angle(subdivisions: int) -> float:
    """:data:`BALL_CONE_ANGLE` of the subdivision."""
    return BALL_CONE_ANGLE[subdivisions]


def measured_ball(subdivisions: int) -> tuple[float, float]:
    """``(inner distance, cone angle)`` of the unit icosphere measured on its qhull hull:
    what :data:`BALL_INNER` and :data:`BALL_CONE_ANGLE` hold."""
    sphere = convex_hull(trimesh.creation.icosphere(subdivisions=subdivisions,
                                                    radius=1.0).vertices)
    corners = sphere.points[sphere.simplices]                  # (facets, 3, 3), unit
    cosines = np.einsum("fkj,fj->fk", corners, sphere.equations[:, :3])
    return (float(-sphere.equations[:, 3].max()),
            float(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))


def convex_hull(points: np.ndarray, keep_coplanar: bool = False):
    """Qhull's convex hull of ``points`` (triangulated facets, outward ``equations``);
    with ``keep_coplanar``, the points it found on a facet to its precision but left out
    are listed with that facet (``coplanar``)."""
    from scipy.spatial import ConvexHull  # noqa: PLC0415

    return ConvexHull(points, qhull_options="Qt Qc" if keep_coplanar else "Qt")


def hull_mesh(hull) -> trimesh.Trimesh:
    """A hull's triangles as a closed, outward mesh on the vertices they use."""
    faces = np.asarray(hull.simplices, dtype=np.int64)
    points = np.asarray(hull.points)
    a, b, c = (points[faces[:, k]] for k in range(3))
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), hull.equations[:, :3]) < 0
    faces[inward] = faces[inward][:, ::-1]
    used, faces = np.unique(faces, return_inverse=True)
    return trimesh.Trimesh(points[used], faces.reshape(-1, 3), process=False)
