"""Closest points on triangles and distances to a triangle mesh, exact to rounding at any
scale.

``trimesh.triangles.closest_point`` (5.2) compares barycentric quantities against fixed
absolute tolerances, so for triangles a millimetre across in metre units it returns points
off by up to most of the triangle: a part in metres is the common case here. These use the
region test of Ericson's *Real-Time Collision Detection* (5.1.5) on dot products only,
which has no scale in it.

Entry points: :func:`closest_points_on_triangles`, :func:`mesh_distance`.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["closest_points_on_triangles", "mesh_distance"]


def closest_points_on_triangles(triangles, points) -> np.ndarray:
    """``(n, 3)`` points of the ``(n, 3, 3)`` triangles nearest the ``(n, 3)`` points (one
    triangle per point); a degenerate triangle gives its nearest point too."""
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp, cp = p - b, p - c
    d3, d4 = dot(ab, bp), dot(ac, bp)
    d5, d6 = dot(ab, cp), dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    out = np.empty_like(p)
    done = np.zeros(len(p), dtype=bool)

    def take(mask, value):
        nonlocal done
        mask = mask & ~done
        out[mask] = value[mask] if np.ndim(value) == 2 else value
        done |= mask

    def ratio(num, den):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(den != 0.0, num / np.where(den != 0.0, den, 1.0), 0.0)

    take((d1 <= 0) & (d2 <= 0), a)                                   # vertex a
    take((d3 >= 0) & (d4 <= d3), b)                                  # vertex b
    take((d6 >= 0) & (d5 <= d6), c)                                  # vertex c
    t = ratio(d1, d1 - d3)
    take((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * t[:, None])     # edge ab
    t = ratio(d2, d2 - d6)
    take((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * t[:, None])     # edge ac
    t = ratio(d4 - d3, (d4 - d3) + (d5 - d6))
    take((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), b + (c - b) * t[:, None])  # edge bc
    den = va + vb + vc
    v, w = ratio(vb, den), ratio(vc, den)
    face = a + ab * v[:, None] + ac * w[:, None]
    take(np.ones(len(p), dtype=bool), face)                          # the face
    # den is |ab x ac|^2: near zero relative to |ab|^2 |ac|^2 the region test divides
    # rounding by rounding, and the triangle is measured as its edges instead
    flat = ~(den > FLAT * dot(ab, ab) * dot(ac, ac))
    return _flat_measured_by_edges(tri, p, out, flat)


FLAT = 1e-12
"""Triangles whose squared cross product is below this fraction of ``|ab|^2 |ac|^2`` (an
angle under about 1e-6 radians at ``a``, or no area) are measured by their edges: they lie
within that of them."""


def _flat_measured_by_edges(tri, p, out, flat) -> np.ndarray:
    """Where a triangle is flat (``flat``), its nearest point is taken on one of its
    edges: the nearest of the three segments' nearest points."""
    if not flat.any():
        return out
    best = np.full(int(flat.sum()), np.inf)
    q = p[flat]
    for i, j in ((0, 1), (1, 2), (2, 0)):
        s0, s1 = tri[flat, i], tri[flat, j]
        d = s1 - s0
        length2 = np.einsum("ij,ij->i", d, d)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(np.where(length2 > 0, np.einsum("ij,ij->i", q - s0, d)
                                 / np.where(length2 > 0, length2, 1.0), 0.0), 0.0, 1.0)
        cand = s0 + d * t[:, None]
        dist = np.linalg.norm(cand - q, axis=1)
        better = dist < best
        best[better] = dist[better]
        sub = out[flat]
        sub[better] = cand[better]
        out[flat] = sub
    return out


def mesh_distance(vertices, faces, points, chunk: int = 200_000) -> np.ndarray:
    """``(n,)`` unsigned distances from the ``(n, 3)`` points to the triangles of the mesh,
    exact to rounding: each point's nearest vertex bounds its distance from above, and
    only the triangles whose bounding spheres come within that bound are measured (the
    few largest triangles, which would widen every point's search, against every point).
    Meant for small meshes or few points: a mesh of many long triangles (a CAD part's
    strips) gives each point thousands of candidates."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return np.zeros(0)
    tri = v[f]
    centre = tri.mean(axis=1)
    radius = np.linalg.norm(tri - centre[:, None], axis=2).max(axis=1)
    best, _ = cKDTree(v).query(p)
    large = radius > np.quantile(radius, 0.99) if len(radius) > 100 else np.ones(len(f), bool)
    pairs = [np.stack(np.meshgrid(np.arange(len(p)), np.flatnonzero(large),
                                  indexing="ij"), axis=-1).reshape(-1, 2)]
    small = np.flatnonzero(~large)
    if len(small):
        reach = best + radius[small].max()
        near = cKDTree(centre[small]).query_ball_point(p, reach)
        pairs += [np.column_stack([np.full(len(ts), i), small[ts]])
                  for i, ts in enumerate(near) if ts]
    index = np.concatenate(pairs).astype(np.int64)
    for s in range(0, len(index), chunk):
        i, t = index[s:s + chunk, 0], index[s:s + chunk, 1]
        d = np.linalg.norm(closest_points_on_triangles(tri[t], p[i]) - p[i], axis=1)
        np.minimum.at(best, i, d)
    return best
