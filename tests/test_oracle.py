"""Tests of the independent references in ``tests/oracle.py`` and ``tests/shapes.py``.

The oracle is what the Minkowski-sum acceptance tests trust, so it is checked against
closed forms and exact convex sums, and each check comes with a negative control
showing it can fail (FCL without the containment test, the mirrored convention, a
shifted surface).
"""

import numpy as np
import pytest
import trimesh

try:  # tests/ as a package or as a plain directory on sys.path
    from . import oracle, shapes
except ImportError:
    import oracle
    import shapes


def _rng(seed=0):
    return np.random.default_rng(seed)


def _uniform(bounds, n, rng, pad=0.0):
    lo, hi = np.asarray(bounds[0]) - pad, np.asarray(bounds[1]) + pad
    return rng.uniform(lo, hi, size=(n, 3))


# --------------------------------------------------------------------------------------
# shapes
# --------------------------------------------------------------------------------------

SHAPES = {
    "box": lambda: shapes.box((1.0, 2.0, 3.0), (1.0, -2.0, 0.5)),
    "bored_block": shapes.bored_block,
    "l_bracket": shapes.l_bracket,
    "slotted_bar": shapes.slotted_bar,
    "torus": lambda: shapes.torus(10.0, 3.0, 32, 16),
    "cross_of_bars": shapes.cross_of_bars,
    "icosphere": lambda: shapes.icosphere(2, 0.9),
    "plate_with_hole": shapes.plate_with_hole,
    "nonconvex_part_2k": shapes.nonconvex_part_2k,
    "random_convex": shapes.random_convex,
}


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_shapes_are_closed_solids(name):
    mesh = SHAPES[name]()
    assert mesh.vertices.dtype == np.float64
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0
    assert mesh.body_count == 1


def test_shapes_closed_forms():
    assert shapes.cross_of_bars().volume == pytest.approx(3 * 30 * 36 - 2 * 6**3)
    assert shapes.slotted_bar().volume == pytest.approx(3 * 1 * 0.5 - 2 * 0.2 * 0.6 * 0.5)
    assert shapes.l_bracket().volume == pytest.approx((4 * 1 + 1 * 2) * 2)
    assert shapes.torus(10, 3, 32, 16).euler_number == 0
    assert shapes.plate_with_hole().euler_number == 0
    assert shapes.bored_block().euler_number == 0
    part = shapes.nonconvex_part_2k()
    assert 1500 <= len(part.faces) <= 2500
    assert part.convex_hull.volume > 1.2 * part.volume           # really non-convex
    # deterministic
    again = shapes.nonconvex_part_2k()
    assert np.array_equal(part.vertices, again.vertices)
    assert np.array_equal(part.faces, again.faces)


# --------------------------------------------------------------------------------------
# point in mesh
# --------------------------------------------------------------------------------------

def test_points_in_mesh_box_closed_form_including_grid_points():
    mesh = shapes.box((2.0, 4.0, 6.0))
    rng = _rng(1)
    pts = np.concatenate([
        _uniform(mesh.bounds, 4000, rng, pad=0.5),
        # structured points: on the lines through vertices and edges, a classic trap for
        # ray casting along an axis
        np.stack(np.meshgrid(*[np.linspace(-4, 4, 17)] * 3, indexing="ij"), -1).reshape(-1, 3),
    ])
    half = np.array([1.0, 2.0, 3.0])
    margin = np.min(np.abs(np.abs(pts) - half), axis=1)
    off_surface = margin > 1e-9
    expected = np.all(np.abs(pts) < half, axis=1)
    got = oracle.points_in_mesh(mesh, pts)
    assert np.array_equal(got[off_surface], expected[off_surface])
    assert oracle.points_in_mesh(mesh, np.zeros(3)).tolist() == [True]


@pytest.mark.parametrize("name", ["torus", "nonconvex_part_2k", "slotted_bar", "icosphere"])
def test_points_in_mesh_agrees_with_trimesh(name):
    mesh = SHAPES[name]()
    pts = _uniform(mesh.bounds, 1500, _rng(2), pad=0.1 * mesh.scale)
    got = oracle.points_in_mesh(mesh, pts)
    near = oracle.surface_distance(mesh, pts) < 1e-7 * mesh.scale
    assert np.array_equal(got[~near], mesh.contains(pts)[~near])
    assert 0.1 < got.mean() < 0.9


def test_points_in_mesh_nested_shells():
    """A hollow ball (outer shell + inverted inner shell): the cavity is outside."""
    outer = shapes.icosphere(3, 2.0)
    inner = shapes.icosphere(3, 1.0)
    inner.invert()
    hollow = trimesh.util.concatenate([outer, inner])
    got = oracle.points_in_mesh(hollow, np.array([[0.0, 0, 0], [1.5, 0, 0], [0, 0, 1.5],
                                                  [2.5, 0, 0]]))
    assert got.tolist() == [False, True, True, False]


# --------------------------------------------------------------------------------------
# membership oracle
# --------------------------------------------------------------------------------------

def test_fcl_alone_misses_containment_and_the_oracle_does_not():
    """The trap: FCL mesh-mesh collide only intersects triangles."""
    big = shapes.box((4.0, 4.0, 4.0))
    small = shapes.icosphere(1, 0.5)
    collider = oracle.CollisionOracle(big, small)
    t = np.zeros((1, 3))
    assert not collider.collides(t, use_inside_test=False)[0]      # FCL: "no contact"
    assert collider.collides(t)[0]                                  # solids overlap
    assert oracle.in_minkowski_sum(np.zeros(3), big, small) is True
    assert oracle.in_minkowski_sum(np.zeros(3), small, big) is True
    # and the other way round: the big part around the small one
    assert oracle.in_c_obstacle(np.zeros(3), small, big) is True
    assert oracle.in_minkowski_sum(np.array([10.0, 0, 0]), big, small) is False


CONVEX_PAIRS = {
    "box+icosphere": lambda: (shapes.box((1.0, 2.0, 3.0)), shapes.icosphere(2, 0.9)),
    "random hulls": lambda: (shapes.random_convex(30, (1.0, 2.0, 0.5), seed=1),
                             shapes.random_convex(25, (0.5, 0.3, 1.0), seed=2,
                                                  center=(0.7, -0.2, 0.4))),
    "box+far box": lambda: (shapes.box((1.0, 1.0, 1.0)),
                            shapes.box((0.5, 1.5, 0.25), center=(10.0, 0.0, 0.0))),
    "plate+needle": lambda: (shapes.box((4.0, 4.0, 0.1)),
                             shapes.random_convex(12, (0.02, 0.02, 2.0), seed=5)),
}


@pytest.mark.parametrize("name", sorted(CONVEX_PAIRS))
def test_membership_agrees_with_exact_convex_sum(name):
    a, b = CONVEX_PAIRS[name]()
    exact = oracle.exact_convex_sum(a, b)
    rng = _rng(3)
    diag = float(np.linalg.norm(exact.extents))
    pts = _uniform(exact.bounds, 3000, rng, pad=0.1 * diag)
    far = oracle.surface_distance(exact, pts) > 1e-4 * diag
    pts = pts[far]
    assert len(pts) >= 1000
    want = oracle.points_in_mesh(exact, pts)
    assert 0.1 < want.mean() < 0.9                  # both classes are well represented
    got = oracle.in_minkowski_sum(pts, a, b)
    assert got.dtype == bool and got.shape == (len(pts),)
    assert np.array_equal(got, want)


def test_membership_check_can_fail():
    """Negative controls for the test above: the same comparison catches a mirrored
    operand (A ⊕ (−B)) and FCL without the containment test."""
    a, b = CONVEX_PAIRS["random hulls"]()
    exact = oracle.exact_convex_sum(a, b)
    diag = float(np.linalg.norm(exact.extents))
    pts = _uniform(exact.bounds, 2000, _rng(4), pad=0.1 * diag)
    pts = pts[oracle.surface_distance(exact, pts) > 1e-4 * diag]
    want = oracle.points_in_mesh(exact, pts)
    wrong_sign = oracle.in_minkowski_sum(pts, a, oracle.mirrored(b))
    assert np.sum(wrong_sign != want) > 50
    # a small operand fits wholly inside the big one for p deep in the sum
    a, b = shapes.random_convex(30, (2.0, 2.0, 2.0), seed=9), shapes.icosphere(1, 0.3)
    exact = oracle.exact_convex_sum(a, b)
    pts = _uniform(exact.bounds, 2000, _rng(4))
    pts = pts[oracle.surface_distance(exact, pts) > 1e-4 * diag]
    want = oracle.points_in_mesh(exact, pts)
    fcl_only = oracle.MinkowskiOracle(a, b)._pair.collides(pts, use_inside_test=False)
    assert np.sum(fcl_only != want) > 50
    assert np.all(want[fcl_only])                   # it only ever misses, deep inside
    assert np.array_equal(oracle.in_minkowski_sum(pts, a, b), want)


def test_c_obstacle_convention_two_independent_paths():
    """in_c_obstacle (R + t against O) and in_minkowski_sum(t, O, −R) are separate code
    paths; they agree, and the mirror image −CO = R ⊕ (−O) does not."""
    obstacle = shapes.l_bracket()
    robot = shapes.l_bracket(2.0, 1.5, 0.5, 1.0, center=(3.0, 1.0, 0.5))
    co_box = np.array([obstacle.bounds[0] - robot.bounds[1], obstacle.bounds[1] - robot.bounds[0]])
    ts = _uniform(co_box, 2500, _rng(5), pad=0.5)
    via_collision = oracle.in_c_obstacle(ts, obstacle, robot)
    via_sum = oracle.in_minkowski_sum(ts, obstacle, oracle.mirrored(robot))
    assert np.array_equal(via_collision, via_sum)
    assert 0.1 < via_collision.mean() < 0.9
    mirror = oracle.in_minkowski_sum(ts, robot, oracle.mirrored(obstacle))
    assert np.sum(mirror != via_collision) > 100
    # a translation by hand: the robot's foot moved onto the origin overlaps the bracket
    t = -robot.bounds[0] + np.array([-1.9, -1.4, -0.9])   # robot's min corner near O's min
    assert oracle.in_c_obstacle(t, obstacle, robot) is True
    assert oracle.in_c_obstacle(t + np.array([0.0, 0.0, 10.0]), obstacle, robot) is False


def test_c_obstacle_convex_against_exact():
    obstacle = shapes.random_convex(20, (1.0, 1.0, 2.0), seed=7)
    robot = shapes.random_convex(15, (0.5, 1.0, 0.3), seed=8, center=(2.0, 0.0, 1.0))
    exact = oracle.exact_convex_sum(obstacle, oracle.mirrored(robot))
    diag = float(np.linalg.norm(exact.extents))
    ts = _uniform(exact.bounds, 2000, _rng(6), pad=0.1 * diag)
    ts = ts[oracle.surface_distance(exact, ts) > 1e-4 * diag]
    assert np.array_equal(oracle.in_c_obstacle(ts, obstacle, robot),
                          oracle.points_in_mesh(exact, ts))


# --------------------------------------------------------------------------------------
# boundary points and Hausdorff estimates
# --------------------------------------------------------------------------------------

def test_boundary_points_convex_are_on_the_exact_boundary():
    a, b = CONVEX_PAIRS["random hulls"]()
    exact = oracle.exact_convex_sum(a, b)
    diag = float(np.linalg.norm(exact.extents))
    pts = oracle.boundary_points_by_bisection(a, b, 150, seed=1)
    assert pts.shape == (150, 3)
    assert oracle.surface_distance(exact, pts).max() < 1e-5 * diag


def test_boundary_points_non_star_shaped_sum():
    """Torus ⊕ ball against manifold3d's answer (exact here: B is convex and contains the
    origin).  Rays cross the tube several times, and the inner side of the ring (seen
    from no single interior point) must be reached."""
    a, b = shapes.torus(10.0, 3.0, 24, 12), shapes.icosphere(1, 0.9)
    exact = shapes.from_manifold(shapes.to_manifold(a).minkowski_sum(shapes.to_manifold(b)),
                                 allow_degenerate=True)
    pts = oracle.boundary_points_by_bisection(a, b, 200, seed=2)
    assert oracle.surface_distance(exact, pts).max() < 1e-4
    radial = np.linalg.norm(pts[:, :2], axis=1)
    assert np.sum(radial < 10.0 - 3.0) > 10                       # the hole side
    assert np.sum(radial > 10.0 + 3.0) > 10                       # the outside


def test_hausdorff_estimate_convex_known_offsets():
    a, b = shapes.box((1.0, 2.0, 3.0)), shapes.icosphere(2, 0.9)
    exact = oracle.exact_convex_sum(a, b)
    d1, d2 = oracle.hausdorff_estimate(exact, a, b, 150, seed=0)
    assert d1 < 1e-4 and d2 < 1e-4
    # an icosphere of radius 1.0 instead of 0.9: the support functions differ by at most
    # 0.1 (attained at the vertex directions), so the Hausdorff distance is 0.1
    for r in (1.0, 0.8):
        approx = oracle.exact_convex_sum(a, shapes.icosphere(2, r))
        d1, d2 = oracle.hausdorff_estimate(approx, a, b, 150, seed=0)
        assert 0.09 < d1 < 0.1 + 1e-4
        assert 0.09 < d2 < 0.1 + 1e-3


def test_hausdorff_estimate_non_convex_and_shifted():
    a, b = shapes.l_bracket(), shapes.icosphere(1, 0.5)
    exact = shapes.from_manifold(shapes.to_manifold(a).minkowski_sum(shapes.to_manifold(b)),
                                 allow_degenerate=True)
    d1, d2 = oracle.hausdorff_estimate(exact, a, b, 150, seed=3)
    assert d1 < 1e-4 and d2 < 1e-4
    shift = 0.05
    moved = exact.copy()
    moved.apply_translation([shift, 0.0, 0.0])
    d1, d2 = oracle.hausdorff_estimate(moved, a, b, 150, seed=3)
    # every point of a surface moved by v is within |v| of the original surface
    assert 0.5 * shift < d1 <= shift * (1 + 1e-3)
    assert 0.5 * shift < d2 <= shift * 1.03


def test_approx_to_true_distances_exact_for_convex():
    """Outside the sum exact (FCL distance), inside an upper bound that is tight."""
    a, b = CONVEX_PAIRS["random hulls"]()
    exact = oracle.exact_convex_sum(a, b)
    shrunk = exact.copy()
    shrunk.vertices = exact.vertices * 0.97 + exact.centroid * 0.03 + np.array([0.02, 0, 0])
    pts, face = trimesh.sample.sample_surface(shrunk, 200, seed=1)
    est = oracle.approx_to_true_distances(shrunk, pts, shrunk.face_normals[face],
                                          oracle.MinkowskiOracle(a, b))
    true = oracle.surface_distance(exact, pts)
    diag = float(np.linalg.norm(exact.extents))
    assert np.all(est >= true - 1e-5 * diag)
    assert est.max() == pytest.approx(true.max(), rel=0.02)


def test_sampled_hausdorff_and_exact_sum_closed_forms():
    a = shapes.box((1.0, 2.0, 3.0))
    b = shapes.box((0.5, 0.5, 0.5), center=(10.0, 0.0, 0.0))
    s = oracle.exact_convex_sum(a, b)
    assert s.volume == pytest.approx(1.5 * 2.5 * 3.5)
    assert np.allclose(s.bounds, [[9.25, -1.25, -1.75], [10.75, 1.25, 1.75]])
    assert oracle.sampled_hausdorff(s, shapes.box((1.5, 2.5, 3.5), (10, 0, 0)), 2000) == (
        pytest.approx(0.0, abs=1e-9), pytest.approx(0.0, abs=1e-9))
    bigger = shapes.box((1.5, 2.5, 3.7), (10, 0, 0))
    assert oracle.sampled_hausdorff(s, bigger, 2000) == (pytest.approx(0.1),
                                                         pytest.approx(0.1))
    # commutative
    assert oracle.exact_convex_sum(b, a).volume == pytest.approx(s.volume)
