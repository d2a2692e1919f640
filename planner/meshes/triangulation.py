"""Triangulation of polygons in their own plane: quads along the diagonal that keeps both
triangles facing the polygon's normal (all quads at once, vectorised), larger polygons by
ear clipping (mapbox-earcut: non-convex and "keyhole" polygons, collinear corners). Used
for OBJ n-gons and for filling holes.

Entry points: :func:`triangulate_polygons`, :func:`ear_clip`.
"""

from __future__ import annotations

import mapbox_earcut
import numpy as np

__all__ = ["ear_clip", "triangulate_polygons"]


def triangulate_polygons(points: np.ndarray, polygons: list[list[int]]):
    """Triangulate polygons (lists of vertex indices) in their planes.

    Returns ``(faces, problems)``: ``(m, 3)`` int64 faces, and the number of polygons
    that were degenerate or needed a forced (non-ear) cut.
    """
    triangles = [np.asarray([p for p in polygons if len(p) == 3], dtype=np.int64)]
    quads = np.asarray([p for p in polygons if len(p) == 4], dtype=np.int64).reshape(-1, 4)
    triangles.append(_split_quads(points, quads))
    problems = 0
    for polygon in polygons:
        if len(polygon) <= 4:
            continue
        local, ok = ear_clip(points[polygon])
        problems += not ok
        triangles.append(np.asarray(polygon, dtype=np.int64)[local])
    faces = np.concatenate([t.reshape(-1, 3) for t in triangles])
    return faces, problems


def _split_quads(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Split quads (n, 4) along the diagonal whose two triangles face the quad normal."""
    if len(quads) == 0:
        return np.zeros((0, 3), dtype=np.int64)
    p = points[quads]  # (n, 4, 3)
    normal = np.cross(p[:, 0] - p[:, 2], p[:, 1] - p[:, 3])  # Newell normal of a quad
    # diagonal 0-2 gives (0,1,2) and (0,2,3); diagonal 1-3 gives (1,2,3) and (1,3,0)
    n012 = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n023 = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])
    use_02 = np.minimum((n012 * normal).sum(axis=1), (n023 * normal).sum(axis=1)) >= 0
    first = np.where(use_02[:, None], quads[:, [0, 1, 2]], quads[:, [1, 2, 3]])
    second = np.where(use_02[:, None], quads[:, [0, 2, 3]], quads[:, [1, 3, 0]])
    return np.concatenate([first, second])


def _polygon_frame(points: np.ndarray):
    """Newell normal of a 3D polygon and an orthonormal in-plane basis ``(u, v)`` with
    ``u x v`` along the normal, so the polygon winds counter-clockwise in ``(u, v)``."""
    shifted = points - points.mean(axis=0)
    normal = np.cross(shifted, np.roll(shifted, -1, axis=0)).sum(axis=0)
    length = np.linalg.norm(normal)
    if not np.isfinite(length) or length == 0:
        return None
    normal = normal / length
    helper = np.zeros(3)
    helper[np.argmin(np.abs(normal))] = 1.0
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    return normal, u, v


def polygon_in_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """A polygon's fan triangulation ``(n - 2, 3)`` (the fallback) and its ``(n, 2)``
    coordinates in its own plane, centred (``None`` for a polygon with no plane or no
    extent)."""
    n = len(points)
    fan = np.stack([np.zeros(n - 2, dtype=np.int64), np.arange(1, n - 1), np.arange(2, n)], 1)
    frame = _polygon_frame(points)
    if frame is None:
        return fan, None
    _, u, v = frame
    centred = points - points.mean(axis=0)
    xy = np.ascontiguousarray(np.stack([centred @ u, centred @ v], axis=1))
    if float(np.ptp(xy, axis=0).max()) == 0:
        return fan, None
    return fan, xy


def ear_clip(points: np.ndarray):
    """Ear-clip one polygon given as ``(n, 3)`` points in order, in its plane.

    The clipping is mapbox-earcut's (the C++ earcut that trimesh's
    ``triangulate_polygon`` calls; it handles non-convex and keyhole polygons and keeps
    collinear corners); this function puts the polygon in its plane and checks the result.
    Replaced a hand-written ear clipper that took 15x to 20x as long on the peg-in-hole
    OBJs' n-gons, for triangles of the same areas (``tests/benchmarks/bench_libraries.py``;
    quads stay vectorised in :func:`triangulate_polygons`: one earcut call per quad takes
    300x as long).

    Returns ``(triangles, ok)``: ``(n - 2, 3)`` local indices wound like the polygon, and
    whether they tile it (``False`` for a degenerate or self-crossing polygon, which gets
    a fan, or whatever triangles earcut found, wound like the polygon).
    """
    n = len(points)
    fan, xy = polygon_in_plane(points)
    if xy is None:
        return fan, False
    ring_ends = np.array([n], dtype=np.uint32)
    triangles = np.asarray(mapbox_earcut.triangulate_float64(xy, ring_ends),
                           dtype=np.int64).reshape(-1, 3)
    if len(triangles) != n - 2:
        return fan, False
    areas = _twice_areas(xy, triangles)
    backwards = areas < 0
    triangles[backwards] = triangles[backwards][:, ::-1]
    extent = float(np.ptp(xy, axis=0).max())
    eps = 1e-12 * extent * extent  # orientation tolerance (twice a triangle area)
    tiles = abs(float(np.abs(areas).sum()) - _twice_area(xy)) <= n * eps
    return triangles, bool(tiles and not backwards.any())


def _twice_areas(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Twice the signed areas of ``(k, 3)`` triangles of ``(n, 2)`` points."""
    a, b, c = xy[triangles[:, 0]], xy[triangles[:, 1]], xy[triangles[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


def _twice_area(xy: np.ndarray) -> float:
    """Twice the signed area of a polygon of ``(n, 2)`` points (shoelace)."""
    x, y = xy[:, 0], xy[:, 1]
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
