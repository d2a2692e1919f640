"""The native module's own surface: stub agrees with the binary, queries are exact on
closed-form shapes, errors map to planner.errors, the GIL is released."""

import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from planner import _minkowski_core as core
from planner.errors import InvalidMeshError, InvalidParameterError, ResourceLimitError


def ball(center, r, n=200):
    """A convex piece of ``n`` points on a sphere: many facet planes, so its sum's boundary
    cells are sampled (a box's are resolved by planes at any size)."""
    k = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * k / n), np.pi * (1 + 5 ** 0.5) * k
    pts = np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])
    return np.asarray(center, float) + r * pts


def cube(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return np.array([
        [hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]]
        for k in range(8)
    ])


def test_stub_matches_the_binary():
    out = subprocess.run([sys.executable, "-m", "mypy.stubtest", "planner._minkowski_core"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr


def test_pairwise_sum_of_cubes_and_queries():
    a = [cube([-1, -1, -1], [1, 1, 1])]
    b = [cube([9.5, -0.5, -0.5], [10.5, 0.5, 0.5])]
    s = core.Primitives.pairwise_sums(a, b, subtract=False)
    assert len(s) == 1
    np.testing.assert_allclose(s.bounds, [[8.5, -1.5, -1.5], [11.5, 1.5, 1.5]])
    assert list(s.facet_counts()) == [6]
    inside = s.contains(np.array([[10.0, 0, 0], [12.0, 0, 0], [11.5, 1.5, 1.5]]))
    assert inside.tolist() == [True, False, True]  # closed set: a corner is inside
    d = s.signed_distance(np.array([[10.0, 0, 0], [13.5, 0, 0], [12.5, 2.5, 1.5]]))
    np.testing.assert_allclose(d, [-1.5, 2.0, np.sqrt(2.0)], atol=1e-12)
    assert not s.segment_is_free(np.array([0.0, 0, 0]), np.array([20.0, 0, 0]))
    assert s.segment_is_free(np.array([0.0, 5, 0]), np.array([20.0, 5, 0]))
    (t0, t1), = s.segment_intervals(np.array([0.0, 0, 0]), np.array([20.0, 0, 0]))
    assert t0 == pytest.approx(8.5 / 20) and t1 == pytest.approx(11.5 / 20)
    # subtract: A ⊕ (−B)
    c = core.Primitives.pairwise_sums(a, b, subtract=True)
    np.testing.assert_allclose(c.bounds, [[-11.5, -1.5, -1.5], [-8.5, 1.5, 1.5]])


def test_union_surface_of_a_cube_is_closed_and_bounded():
    import trimesh

    s = core.Primitives.from_pieces([cube([0, 0, 0], [1, 1, 1])])
    r = core.union_surface(s, 0.05)
    mesh = trimesh.Trimesh(r["vertices"], r["faces"], process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert r["complex_cells"] == 0 and r["error_bound"] <= 0.05 * (1 + 1e-9)
    assert abs(mesh.volume - 1.0) <= mesh.area * r["error_bound"]
    d = np.abs(s.signed_distance(np.asarray(mesh.vertices)))
    assert d.max() <= r["error_bound"]


def test_octree_labels():
    s = core.Primitives.from_pieces([cube([0, 0, 0], [1, 1, 1])])
    o = core.build_octree(s, 0.1)
    h, origin = o["h"], np.asarray(o["origin"])
    lo = origin + o["ijk"] * h
    size = (2.0 ** o["level"].astype(float)) * h
    centers = lo + size[:, None] / 2
    full = o["label"] == 1
    empty = o["label"] == 0
    assert full.any() and empty.any() and (o["label"] == 2).any()
    assert s.contains(centers[full]).all()
    # an EMPTY cell meets no primitive: for the unit cube, the boxes are disjoint
    lo_e, hi_e = lo[empty], lo[empty] + size[empty][:, None]
    assert ((hi_e < 0) | (lo_e > 1)).any(axis=1).all()
    # a MIXED cell is cut by the cube's boundary
    mixed = o["label"] == 2
    lo_m, hi_m = lo[mixed], lo[mixed] + size[mixed][:, None]
    assert (~((hi_m < 0) | (lo_m > 1)).any(axis=1)).all()
    assert (~((lo_m >= 0) & (hi_m <= 1)).all(axis=1)).all()
    vol = (size ** 3).sum()
    assert vol == pytest.approx((2.0 ** o["depth"] * h) ** 3)


def test_errors_map_to_planner_errors():
    with pytest.raises(InvalidMeshError, match="piece 0"):
        core.Primitives.from_pieces([np.zeros((3, 3))])
    with pytest.raises(InvalidMeshError, match="non-finite"):
        core.Primitives.from_pieces([np.full((4, 3), np.nan)])
    with pytest.raises(InvalidMeshError, match=r"\(n, 3\)"):
        core.Primitives.from_pieces([np.zeros((4, 2))])
    with pytest.raises(InvalidMeshError, match="no convex pieces"):
        core.Primitives.pairwise_sums([], [cube([0, 0, 0], [1, 1, 1])])
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    with pytest.raises(InvalidMeshError, match="degenerate"):
        core.Primitives.from_pieces([flat])
    s = core.Primitives.from_pieces([cube([0, 0, 0], [1, 1, 1])])
    with pytest.raises(InvalidParameterError, match="eps"):
        core.union_surface(s, -1.0)
    # two overlapping balls: a grid is needed (one primitive, or apart ones, are their
    # hulls without one)
    with pytest.raises(ResourceLimitError, match="cells"):
        core.union_surface(core.Primitives.from_pieces([ball([0, 0, 0], 1.0),
                                                        ball([0.5, 0, 0], 1.0)]), 1e-4,
                           max_cells=1000)


def test_native_work_releases_the_gil():
    # overlapping balls: a grid is needed (apart ones are their hulls, at once)
    pieces = [ball(np.array([i, 0, 0]) * 1.0, 0.6) for i in range(6)]
    s = core.Primitives.from_pieces(pieces)
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    t0 = time.perf_counter()
    core.union_surface(s, 0.01, simplify=False)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if t0 < x < t1]
    # a held GIL would starve the ticker for the whole native call
    assert len(during) >= max(3, int((t1 - t0) / 0.01)), (len(during), t1 - t0)
