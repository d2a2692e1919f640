"""Triangulation of polygons in their own plane: quads along the diagonal that keeps both
triangles facing the polygon's normal, larger polygons by ear clipping (non-convex and
"keyhole" polygons, collinear corners). Used for OBJ n-gons and for filling holes.

Entry points: :func:`triangulate_polygons`, :func:`ear_clip`.
"""

from __future__ import annotations

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


def ear_clip(points: np.ndarray):
    """Ear-clip one polygon given as ``(n, 3)`` points in order.

    Returns ``(triangles, ok)``: ``(n - 2, 3)`` local indices wound like the polygon, and
    whether every cut was a proper ear (``False`` for degenerate polygons or when a
    forced cut was needed).
    """
    n = len(points)
    fan = np.stack([np.zeros(n - 2, dtype=np.int64), np.arange(1, n - 1), np.arange(2, n)], 1)
    frame = _polygon_frame(points)
    if frame is None:
        return fan, False
    _, u, v = frame
    centred = points - points.mean(axis=0)
    xy = np.stack([centred @ u, centred @ v], axis=1)
    extent = float(np.ptp(xy, axis=0).max())
    if extent == 0:
        return fan, False
    eps = 1e-12 * extent * extent  # orientation tolerance (twice a triangle area)

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (
            b[..., 1] - a[..., 1]
        ) * (c[..., 0] - a[..., 0])

    ring = list(range(n))
    out: list[tuple[int, int, int]] = []
    ok = True
    while len(ring) > 3:
        m = len(ring)
        idx = np.asarray(ring)
        prev_i, next_i = np.roll(idx, 1), np.roll(idx, -1)
        turn = orient(xy[prev_i], xy[idx], xy[next_i])
        reflex = idx[turn <= eps]
        chosen = -1
        for pos in np.flatnonzero(turn > eps):
            a, b, c = prev_i[pos], idx[pos], next_i[pos]
            others = reflex[(reflex != a) & (reflex != b) & (reflex != c)]
            if len(others):
                q = xy[others]
                # points coinciding with a corner (keyhole bridges) do not block the ear
                same = (
                    np.all(q == xy[a], axis=1)
                    | np.all(q == xy[b], axis=1)
                    | np.all(q == xy[c], axis=1)
                )
                q = q[~same]
                inside = (
                    (orient(xy[a], xy[b], q) >= -eps)
                    & (orient(xy[b], xy[c], q) >= -eps)
                    & (orient(xy[c], xy[a], q) >= -eps)
                )
                if inside.any():
                    continue
            chosen = int(pos)
            break
        if chosen < 0:  # no proper ear: self-touching or numerically degenerate polygon
            ok = False
            chosen = int(np.argmax(turn))
        out.append((int(prev_i[chosen]), int(idx[chosen]), int(next_i[chosen])))
        del ring[chosen % m]
    out.append((ring[0], ring[1], ring[2]))
    return np.asarray(out, dtype=np.int64), ok
