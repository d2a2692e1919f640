"""Closest points on triangles and mesh distances (planner.meshes.closest) against a
dense brute force, at unit scale and at a millimetre in metres (where trimesh's own
closest point is off by most of a triangle)."""

import numpy as np
import pytest
import trimesh

from planner.meshes.closest import closest_points_on_triangles, mesh_distance


def _brute(tri, p, n=200):
    """The nearest of a dense barycentric grid of the triangle's points, and the edges'."""
    k = np.arange(n + 1) / n
    u, v = np.meshgrid(k, k)
    keep = u + v <= 1
    w = np.stack([1 - u[keep] - v[keep], u[keep], v[keep]], axis=1)
    pts = w @ tri
    d = np.linalg.norm(pts - p, axis=1)
    return pts[np.argmin(d)], d.min()


@pytest.mark.parametrize("scale", [1.0, 1e-3])
def test_closest_points_match_a_dense_search(scale):
    rng = np.random.default_rng(3)
    tris = rng.random((300, 3, 3)) * scale + 0.05
    tris[::10, 2] = tris[::10, 0] + (tris[::10, 1] - tris[::10, 0]) * 0.4  # degenerate
    pts = tris.mean(axis=1) + rng.normal(size=(300, 3)) * scale
    got = closest_points_on_triangles(tris, pts)
    for tri, p, q in zip(tris, pts, got, strict=True):
        _, best = _brute(tri, p)
        d = np.linalg.norm(q - p)
        assert d <= best + 1e-12 * scale and d >= best - 0.02 * scale, (d, best)
        # the answer is a point of the triangle: its distance to the plane is rounding
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        if np.linalg.norm(n) > 1e-9 * scale * scale:
            assert abs(np.dot(q - tri[0], n / np.linalg.norm(n))) < 1e-12 * scale


def test_points_on_small_triangles_are_their_own_nearest_points():
    # trimesh 5.2's closest_point misplaces nearly all of these
    rng = np.random.default_rng(0)
    tris = rng.random((2000, 3, 3)) * 1e-3 + 0.05
    w = rng.dirichlet([1, 1, 1], size=2000)
    pts = np.einsum("ij,ijk->ik", w, tris)
    got = closest_points_on_triangles(tris, pts)
    assert np.abs(got - pts).max() < 1e-15


def test_mesh_distance_is_the_exact_distance_to_a_box():
    box = trimesh.creation.box((0.002, 0.001, 0.003))
    rng = np.random.default_rng(1)
    pts = rng.uniform(-0.004, 0.004, size=(500, 3))
    half = np.array([0.001, 0.0005, 0.0015])
    outside = np.linalg.norm(np.maximum(np.abs(pts) - half, 0.0), axis=1)
    inside = np.min(half - np.abs(pts), axis=1)
    exact = np.where(outside > 0, outside, inside)
    assert np.allclose(mesh_distance(box.vertices, box.faces, pts), exact, rtol=0, atol=1e-15)


def test_triangles_of_nearly_collinear_corners_are_measured_by_their_edges():
    # corners on a line but not exactly in binary: the region test's quantities are
    # rounding, and dividing them placed points anywhere on the line (0.55 off here)
    rng = np.random.default_rng(5)
    a, d = rng.random((5000, 3)), rng.random((5000, 3)) - 0.5
    b = a + d * rng.random((5000, 1))
    c = a + d * (1 + rng.random((5000, 1))) * 1.0000000001
    tri = np.stack([a, b, c], axis=1)
    p = a + d * rng.random((5000, 1)) * 1.5 + (rng.random((5000, 3)) - 0.5) * 0.3

    def on_segment(s0, s1):
        e = s1 - s0
        t = np.clip(np.einsum("ij,ij->i", p - s0, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        return np.linalg.norm(s0 + e * t[:, None] - p, axis=1)

    edges = np.min([on_segment(tri[:, i], tri[:, (i + 1) % 3]) for i in range(3)], axis=0)
    got = np.linalg.norm(closest_points_on_triangles(tri, p) - p, axis=1)
    assert np.abs(got - edges).max() < 1e-12
