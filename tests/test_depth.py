"""planner.penetration_depth: closed-form cases, FCL's EPA on convex pairs, a non-convex
peg in a hole, a brute-force directional reference, separated pairs against FCL's
distance, and the assembled-pose overlap report."""

import fcl
import manifold3d
import numpy as np
import pytest
import shapes
import trimesh

import planner
from planner.errors import InvalidMeshError, InvalidParameterError, ScenarioError
from planner.io import parse_assembly
from planner.validation import FclChecker


def _convex(mesh: trimesh.Trimesh) -> fcl.Convex:
    faces = np.hstack([np.full((len(mesh.faces), 1), 3), mesh.faces]).ravel()
    return fcl.Convex(np.asarray(mesh.vertices, dtype=np.float64), len(mesh.faces),
                      faces.astype(np.int32))


def epa_depth(a: trimesh.Trimesh, b: trimesh.Trimesh, solver) -> float:
    """FCL's GJK/EPA penetration depth of two convex meshes with ``solver`` (a
    ``fcl.GJKSolverType``; the two report it with opposite signs)."""
    request = fcl.CollisionRequest(enable_contact=True, num_max_contacts=1)
    request.gjk_solver_type = solver
    result = fcl.CollisionResult()
    hit = fcl.collide(fcl.CollisionObject(_convex(a)), fcl.CollisionObject(_convex(b)),
                      request, result)
    assert hit, "the pair does not overlap"
    return abs(float(result.contacts[0].penetration_depth))


def directional_min(a, b, directions: np.ndarray, step: float, tol: float) -> float:
    """The smallest free translation found along sampled unit ``directions``: per
    direction, the first free sample at spacing ``step``, bisected against the collision
    before it to ``tol``. Every value is a free translation (FCL, containment included),
    so the minimum bounds the true depth from above."""
    checker = FclChecker(a, [b])
    best = np.inf
    for u in directions:
        lo, hi = 0.0, step
        while checker.collides(hi * u):
            lo, hi = hi, hi + step
            if hi >= best:
                break
        else:
            while hi - lo > tol:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if checker.collides(mid * u) else (lo, mid)
            best = min(best, hi)
    return best


def _unit(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    axes = np.vstack([np.eye(3), -np.eye(3)])
    return np.vstack([axes, v / np.linalg.norm(v, axis=1, keepdims=True)])


def assert_separating(a, b, r) -> None:
    """The returned translation frees ``a`` from ``b`` per FCL (under the tolerance), and
    is as long as the upper bound."""
    assert np.isclose(np.linalg.norm(r.translation), r.upper, rtol=1e-12)
    assert np.isclose(np.linalg.norm(r.direction), 1.0)
    assert FclChecker(a, [b], contact_tolerance=r.tolerance).is_valid(r.translation)
    assert r.validated and r.converged
    assert r.upper - r.lower <= r.tolerance


@pytest.mark.parametrize("d", [0.05, 0.3, 0.9])
def test_unit_cubes_overlapping_along_x(d):
    a, b = shapes.box(), shapes.box(center=(1.0 - d, 0.0, 0.0))
    r = planner.penetration_depth(a, b, tolerance=1e-4)
    assert r.lower <= d <= r.upper and not r.separated
    assert r.direction @ np.array([-1.0, 0.0, 0.0]) > 0.9999
    assert_separating(a, b, r)


def test_boxes_overlapping_per_axis_take_the_smallest():
    # overlaps: 0.6 in x, 0.15 in y, 0.4 in z
    a, b = shapes.box(), shapes.box(size=(2.0, 2.0, 2.0), center=(0.9, -1.35, 1.1))
    r = planner.penetration_depth(a, b)
    assert r.lower <= 0.15 <= r.upper
    assert r.direction @ np.array([0.0, 1.0, 0.0]) > 0.9999
    assert_separating(a, b, r)


def test_vertices_and_faces_are_accepted():
    a, b = shapes.box(), shapes.box(center=(0.0, 0.0, 0.8))
    r = planner.penetration_depth((a.vertices, a.faces), (b.vertices, b.faces))
    assert r.lower <= 0.2 <= r.upper


@pytest.mark.parametrize("seed", range(6))
def test_convex_pairs_match_fcl_epa(seed):
    rng = np.random.default_rng(seed)
    a = shapes.random_convex(30, scale=(1.0, 0.7, 0.5), seed=seed)
    b = shapes.random_convex(30, scale=(0.6, 0.9, 0.8), seed=100 + seed,
                             center=rng.uniform(-0.8, 0.8, size=3))
    epa = [epa_depth(a, b, s) for s in (fcl.GJKSolverType.GST_LIBCCD,
                                        fcl.GJKSolverType.GST_INDEP)]
    r = planner.penetration_depth(a, b, tolerance=1e-4)
    assert_separating(a, b, r)
    # EPA stops on a point of the boundary, never nearer than the true depth; ours is
    # within the tolerance of it, and its translation is free (FCL)
    assert r.lower <= min(epa) + 1e-6 and r.upper <= min(epa) + r.tolerance + 1e-6
    if abs(epa[0] - epa[1]) < 1e-6:  # both EPAs converged to one answer: the same as ours
        assert r.lower - 1e-6 <= epa[0] <= r.upper + 1e-6, (r, epa)


def test_fcl_epa_can_overshoot_where_ours_is_proved():
    # seed 2 of the pairs above: both of FCL's EPAs stop over 0.09 beyond our free translation
    rng = np.random.default_rng(2)
    a = shapes.random_convex(30, scale=(1.0, 0.7, 0.5), seed=2)
    b = shapes.random_convex(30, scale=(0.6, 0.9, 0.8), seed=102,
                             center=rng.uniform(-0.8, 0.8, size=3))
    r = planner.penetration_depth(a, b, tolerance=1e-4)
    assert not FclChecker(a, [b]).collides(r.translation)
    assert all(e > r.upper + 0.05 for e in (epa_depth(a, b, fcl.GJKSolverType.GST_LIBCCD),
                                            epa_depth(a, b, fcl.GJKSolverType.GST_INDEP)))


def _peg_and_block(shift: float):
    """A 4 × 4 × 2 block with a 1.2 × 1.2 blind hole 1.5 deep from its top (z = 1), and a
    1 × 1 × 2 peg standing in it, 0.5 above the hole's floor, pushed ``shift`` into the
    wall at x = 0.6."""
    block = manifold3d.Manifold.cube([4.0, 4.0, 2.0], center=True)
    hole = manifold3d.Manifold.cube([1.2, 1.2, 2.0], center=True).translate([0.0, 0.0, 0.5])
    solid = shapes.from_manifold(block - hole, "block")
    peg = shapes.box(size=(1.0, 1.0, 2.0), center=(0.1 + shift, 0.0, 1.0))
    return peg, solid


def test_peg_in_a_hole_depth_is_to_the_side_wall():
    peg, block = _peg_and_block(0.15)
    r = planner.penetration_depth(peg, block, tolerance=1e-3)
    assert r.lower <= 0.15 <= r.upper
    assert r.direction @ np.array([-1.0, 0.0, 0.0]) > 0.999
    assert_separating(peg, block, r)
    # the block's convex hull swallows the peg's lower half: lifting it by 1 is its answer
    hull = planner.penetration_depth(peg, block.convex_hull, tolerance=1e-3)
    assert hull.lower <= 1.0 <= hull.upper


@pytest.mark.parametrize("seed", range(3))
def test_random_overlaps_against_sampled_directions(seed):
    rng = np.random.default_rng(seed)
    a = shapes.l_bracket(length=2.0, height=1.5, thickness=0.5, depth=1.0)
    b = shapes.random_convex(20, scale=(0.5, 0.5, 0.5), seed=seed,
                             center=rng.uniform(-0.5, 0.5, size=3))
    if not FclChecker(a, [b]).collides(np.zeros(3)):
        b.apply_translation(-b.centroid + a.vertices[rng.integers(len(a.vertices))])
    assert FclChecker(a, [b]).collides(np.zeros(3))
    r = planner.penetration_depth(a, b)
    brute = directional_min(a, b, _unit(60, seed), step=0.05, tol=1e-6)
    # every sampled free translation is at least the true depth, which is at least lower;
    # upper is within the tolerance of the true depth, hence of the sampled minimum
    assert r.lower <= brute + 1e-9
    assert r.upper <= brute + r.tolerance + 1e-9
    assert_separating(a, b, r)


@pytest.mark.parametrize("shift", [(0.3, 0.2, 0.1), (0.05, 0.03, 0.02), (-0.6, 0.4, 0.0)])
def test_deep_nonconvex_overlaps_converge(shift):
    # a bracket against itself moved a little: facets of the convolution inside the
    # C-obstacle lie nearer than the depth; witness points show the cells they cross inside
    a = shapes.l_bracket(length=2.0, height=1.5, thickness=0.5, depth=1.0)
    b = a.copy()
    b.apply_translation(shift)
    r = planner.penetration_depth(a, b)
    assert_separating(a, b, r)
    brute = directional_min(a, b, _unit(30, 0), step=0.05, tol=1e-6)
    assert r.lower <= brute + 1e-9 and r.upper <= brute + r.tolerance + 1e-9


@pytest.mark.parametrize("pair", ["convex", "bracket"])
def test_separated_pairs_give_fcl_distance(pair):
    if pair == "convex":
        a = shapes.random_convex(30, seed=7)
        b = shapes.random_convex(30, seed=8, center=(4.0, 1.0, -0.5))
    else:
        a = shapes.l_bracket(length=2.0, height=1.5, thickness=0.5, depth=1.0)
        b = shapes.box(size=(0.3, 0.3, 0.3), center=(0.2, 0.2, 0.0))  # in the L's corner
    r = planner.penetration_depth(a, b)
    fcl_distance = FclChecker(a, [b]).distance(np.zeros(3))
    assert r.separated and fcl_distance > 0
    assert abs(r.distance - fcl_distance) <= 1e-9 * fcl_distance
    assert r.lower == r.upper == -r.distance
    assert np.isclose(np.linalg.norm(r.translation), r.distance)
    # the translation brings them into contact, and not beyond
    assert FclChecker(a, [b]).collides(r.translation * (1 + 1e-6))
    assert not FclChecker(a, [b]).collides(r.translation * (1 - 1e-6))


def test_parts_whose_boxes_lie_apart_are_measured_without_the_convolution():
    """Boxes apart: the separation is the least distance between the triangles, with no
    convolution built (IndustReal's medium gear 0.2 m from the large one was refused: the
    convolution needed 2.9 GiB). A unit cube and one turned 45 degrees about z, 3 along x:
    its vertical edge lies 2.5 - sqrt(1/2) from the first's face."""
    from planner.depth import SEPARATION_BY_TRIANGLES

    a = shapes.box()
    b = shapes.box(center=(3.0, 0.0, 0.0))
    b.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 4, [0, 0, 1],
                                                              [3.0, 0.0, 0.0]))
    r = planner.penetration_depth(a, b)
    assert r.stats["method"] == SEPARATION_BY_TRIANGLES and r.stats["facets"] == 0
    assert r.separated and r.distance == pytest.approx(2.5 - np.sqrt(0.5), rel=1e-12)
    np.testing.assert_allclose(r.translation, [r.distance, 0.0, 0.0], atol=1e-12)
    assert r.validated
    assert FclChecker(a, [b]).collides(r.translation * (1 + 1e-6))
    assert not FclChecker(a, [b]).collides(r.translation * (1 - 1e-6))


@pytest.mark.assets
def test_real_gears_far_apart_give_their_separation():
    from conftest import asset

    gears = "assemblies/industreal_gears/meshes/industreal_gear_{}.obj"
    medium = planner.load_mesh(asset(gears.format("medium")))
    large = planner.load_mesh(asset(gears.format("large")))
    medium.apply_translation([0.2, 0.0, 0.0])
    r = planner.penetration_depth(medium, large)
    assert r.separated and r.validated
    assert r.distance == pytest.approx(FclChecker(medium, [large]).distance(np.zeros(3)),
                                       rel=1e-9)


@pytest.mark.parametrize("center", [(1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (1.0, 1.0, 1.0)])
def test_touching_parts_have_zero_depth(center):
    # face, edge and corner contact: in contact (closed solids), not separated
    a, b = shapes.box(), shapes.box(center=center)
    r = planner.penetration_depth(a, b)
    assert not r.separated and r.distance == 0.0
    assert r.lower == 0.0 and 0.0 < r.upper <= r.tolerance
    assert_separating(a, b, r)


def test_bad_input_is_refused():
    a = shapes.box()
    with pytest.raises(InvalidParameterError, match="tolerance"):
        planner.penetration_depth(a, a, tolerance=0.0)
    with pytest.raises(InvalidMeshError):
        planner.penetration_depth(a, "no such file.stl")
    open_box = trimesh.Trimesh(a.vertices, a.faces[:-1], process=False)
    with pytest.raises(InvalidMeshError):
        planner.penetration_depth(open_box, a)


def test_a_small_cell_budget_still_gives_a_proved_interval(caplog):
    peg, block = _peg_and_block(0.15)
    r = planner.penetration_depth(peg, block, tolerance=1e-5, max_cells=20)
    assert r.lower <= 0.15 <= r.upper
    assert not r.converged and "stopped" in caplog.text


def test_assembled_pose_overlap_reports_the_depth():
    text = ("parts:\n  - {name: a, box: [1, 1, 1]}\n"
            "  - {name: b, box: [1, 1, 1], position: [0.7, 0.1, 0]}\n")
    with pytest.raises(ScenarioError) as info:
        parse_assembly(text)
    message = str(info.value)
    # the later part is the one to move: its entry, and the way that frees it
    assert "parts[1]: part 'b' collides with 'a'" in message
    assert "penetration depth in [" in message and "along (1, 0, 0)" in message
    depth = info.value.details["overlap"]["penetration_depth"]
    assert depth["lower"] <= 0.3 <= depth["upper"]


def test_a_real_peg_pushed_into_its_cad_hole_is_read_as_the_assembly_reads_it():
    """Factory's round hole has 36 T-junctions (open as the OBJ has it, a solid once they
    are split, as offsets and assemblies read it): the depth reads it the same way, names
    the file, and the peg pushed 1 mm sideways into the bore wall comes out along -x,
    against sampled directions."""
    from conftest import asset

    folder = "assemblies/factory_round_peg_8mm/meshes/"
    hole_path = asset(folder + "factory_round_hole_8mm_subdiv_3x.obj")
    peg = planner.load_mesh(asset(folder + "factory_round_peg_8mm_loose.obj"))
    peg.apply_translation([0.001, 0.0, 0.002])
    assert not planner.load_mesh(hole_path).is_watertight
    r = planner.penetration_depth(peg, hole_path)
    assert r.direction @ np.array([-1.0, 0.0, 0.0]) > 0.999
    hole = planner.meshes.kinds.classify(planner.load_mesh(hole_path), name="hole",
                                         kind="solid").mesh
    brute = directional_min(peg, hole, _unit(40, 0), step=2e-4, tol=1e-8)
    assert r.lower <= brute + 1e-12 and r.upper <= brute + r.tolerance + 1e-12
    assert 0.0009 < r.lower and r.upper < 0.001
    assert_separating(peg, hole, r)
    with pytest.raises(InvalidMeshError, match=r"b \(factory_round_hole_8mm_subdiv_3x\.obj\)"):
        broken = planner.load_mesh(hole_path)
        broken.faces = broken.faces[:-40]
        planner.penetration_depth(peg, broken)


def test_a_tolerance_finer_than_the_search_resolves_is_refused_naming_the_floor():
    peg, block = _peg_and_block(0.15)
    with pytest.raises(InvalidParameterError, match="use at least"):
        planner.penetration_depth(peg, block, tolerance=1e-300)


def test_a_tolerance_not_small_against_the_pair_is_refused_naming_the_ceiling():
    """1e3 on parts of about 6 cm gave [0.0003, 250]: a width of more than a tenth of the
    pair's size (the diagonal of the box around both) is refused, saying what would do."""
    a, b = shapes.box(), shapes.box(center=(0.0, 0.75, 0.0))
    size = float(np.linalg.norm(np.ptp(np.vstack([a.bounds, b.bounds]), axis=0)))
    ceiling = planner.depth.COARSEST_TOLERANCE * size
    with pytest.raises(InvalidParameterError, match=rf"tolerance = 1000.0: more than 0.1 of "
                       rf"the pair's size .*; use at most {ceiling:.3g}"):
        planner.penetration_depth(a, b, tolerance=1e3)
    r = planner.penetration_depth(a, b, tolerance=0.9 * ceiling)
    assert r.lower <= 0.25 <= r.upper and r.tolerance == 0.9 * ceiling


def test_an_open_operand_is_repaired_when_asked_and_says_what_changed():
    a, b = shapes.box(), shapes.box(center=(0.0, 0.75, 0.0))
    open_box = trimesh.Trimesh(a.vertices, a.faces[:-2], process=False)  # one square off
    with pytest.raises(InvalidMeshError,
                       match=r"not watertight.*repair=True \(minkplan: --repair\)"):
        planner.penetration_depth(open_box, b)
    r = planner.penetration_depth(open_box, b, repair=True)
    assert r.lower <= 0.25 <= r.upper and r.validated
    assert r.stats["changes"] == {"a": {"filled_holes": 1}, "b": {}}


def test_a_trimesh_object_is_taken_as_its_file_is():
    """Factory's round hole as a trimesh.Trimesh with load_mesh's triangles is made a solid
    by splitting its T-junctions, as the file is, and says so; trimesh's own reader fans
    the OBJ's polygons into triangles that overlap once the mesh is closed: no solid to be
    had honestly, refused with the advice to read it with planner.load_mesh."""
    from conftest import asset

    folder = "assemblies/factory_round_peg_8mm/meshes/"
    hole_path = asset(folder + "factory_round_hole_8mm_subdiv_3x.obj")
    peg = planner.load_mesh(asset(folder + "factory_round_peg_8mm_loose.obj"))
    peg.apply_translation([0.0005, 0.0, 0.0])
    by_path = planner.penetration_depth(peg, hole_path)
    split = by_path.stats["changes"]["b"]["t_junctions_split"]
    assert split > 0
    loaded = planner.load_mesh(hole_path)
    as_object = planner.penetration_depth(peg, trimesh.Trimesh(loaded.vertices, loaded.faces))
    assert as_object.stats["changes"]["b"] == {"t_junctions_split": split}
    assert as_object.lower == pytest.approx(by_path.lower, abs=1e-9)
    with pytest.raises(InvalidMeshError, match=r"mesh 'b': .*read it with planner\.load_mesh"):
        planner.penetration_depth(peg, trimesh.load(hole_path))


@pytest.mark.assets
def test_two_meshing_gears_pushed_together_are_answered_from_the_facets_near_them():
    """IndustReal's medium gear moved 1 mm into the large one: the whole reduced
    convolution of the two (over four million facets) exceeds the memory budget, so the
    depth is searched on the facets in the cube it can reach (a few tens of thousands);
    the answer is proved, separates the gears per FCL and is no deeper than the shift."""
    from conftest import asset

    folder = "assemblies/industreal_gears/meshes/"
    medium = planner.load_mesh(asset(folder + "industreal_gear_medium.obj"))
    large = planner.load_mesh(asset(folder + "industreal_gear_large.obj"))
    medium.apply_translation([-0.001, 0.0, 0.0])
    r = planner.penetration_depth(medium, large, tolerance=1e-4)
    assert 0 < r.stats["facets"] < 100_000
    assert 0.0 < r.lower <= r.upper <= 0.001 + r.tolerance
    assert_separating(medium, large, r)


def test_a_sum_made_for_one_depth_query_refuses_other_queries():
    """It keeps only the facets near its point: a distance bound or a segment test
    elsewhere could be wrong, so they are refused; the point query (no facets) and the
    depth it was made for are answered."""
    from planner._minkowski_core import ExactSum

    a, b = shapes.box(), shapes.box(center=(0.7, 0.0, 0.0))
    arrays = [(np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64))
              for m in (b, a)]
    minus_a = (-arrays[1][0], arrays[1][1][:, ::-1].copy())
    near = ExactSum(arrays[0], minus_a, depth_near=([0.0, 0.0, 0.0], 1e-3))
    found = near.depth(np.zeros(3), 1e-3)
    assert found["inside"] and found["lower"] <= 0.3 <= found["upper"]
    assert near.contains(np.zeros((1, 3)))[0]
    with pytest.raises(InvalidParameterError, match="signed_distance: this sum was made for "
                       "one depth query"):
        near.signed_distance(np.array([[0.0, 0.0, 1.2]]))
    with pytest.raises(InvalidParameterError, match="segment_is_free"):
        near.segment_is_free([0.0, 0.0, 0.0], [0.0, 0.0, 2.0])
