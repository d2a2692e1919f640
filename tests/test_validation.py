"""Independent validation: FclChecker (containment, sweeps, clearance, contact tolerance)
and OMPL's path check (resolution pitfall)."""

from __future__ import annotations

import math

import fcl
import numpy as np
import pytest
import trimesh

from planner.meshes import winding_numbers
from planner.validation import (
    FclChecker,
    MotionValidator,
    StateValidityChecker,
    ompl_check_path,
    resolution_for_clearance,
)
from planner.validation.ompl_check import DEFAULT_RESOLUTION, MIN_RESOLUTION

BOUNDS = [[-5.0, -5.0, -5.0], [5.0, 5.0, 5.0]]


def box(extents, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return mesh


def hollow_box(outer: float, inner: float) -> trimesh.Trimesh:
    """A closed box shell with a sealed cubic cavity (two shells, cavity inward)."""
    cavity = box([inner] * 3)
    cavity.invert()
    return trimesh.util.concatenate([box([outer] * 3), cavity])


def box_distance(ca, ha, cb, hb) -> float:
    """Closed-form distance between axis-aligned boxes (centres, half extents)."""
    gap = np.abs(np.asarray(ca, float) - np.asarray(cb, float)) - (
        np.asarray(ha, float) + np.asarray(hb, float)
    )
    return float(np.linalg.norm(np.maximum(gap, 0.0)))


def window_wall():
    """Wall x in [-0.1, 0.1], y, z in [-3, 3] with a window |y| < 1, |z| < 1."""
    return [
        box([0.2, 6, 2], [0, 0, 2]),
        box([0.2, 6, 2], [0, 0, -2]),
        box([0.2, 2, 2], [0, 2, 0]),
        box([0.2, 2, 2], [0, -2, 0]),
    ], ["top", "bottom", "left", "right"]


ROBOT = box([1, 1, 1])  # half extent 0.5

# Through the window, then a segment cutting the corner of the C-obstacle of "left"
# (x <= 0.6, y >= 0.5) between x = 0.58 and x = 0.6, 0.01 deep; OMPL's default 1% step
# (0.17) samples x = 0.53 and 0.64 on it and misses the cut.
CORNER_CUT = [[-3, 0, 0], [0.3, 0.22, 0], [1.1, 1.02, 0], [3, 1.02, 0]]


def raw_fcl_collides(robot, obstacle, t) -> bool:
    def obj(mesh, translation):
        bvh = fcl.BVHModel()
        bvh.beginModel(len(mesh.vertices), len(mesh.faces))
        bvh.addSubModel(mesh.vertices, mesh.faces)
        bvh.endModel()
        return fcl.CollisionObject(bvh, fcl.Transform(np.asarray(translation, float)))

    result = fcl.CollisionResult()
    return fcl.collide(obj(robot, t), obj(obstacle, (0, 0, 0)), fcl.CollisionRequest(), result) > 0


# ---------------------------------------------------------------- state queries


def test_checker_satisfies_protocols():
    checker = FclChecker(ROBOT, [box([1, 1, 1])])
    assert isinstance(checker, StateValidityChecker)
    assert isinstance(checker, MotionValidator)


def test_winding_numbers_inside_outside_and_cavity():
    shell = hollow_box(4.0, 2.0)
    w = winding_numbers(np.array([[0, 0, 0], [1.5, 0, 0], [3, 0, 0]], float), shell.triangles)
    np.testing.assert_allclose(w, [0.0, 1.0, 0.0], atol=1e-9)


def test_robot_inside_obstacle_is_collision_though_raw_fcl_misses_it():
    big = box([4, 4, 4])
    assert not raw_fcl_collides(ROBOT, big, (0.3, 0, 0))  # the pitfall: triangles only
    checker = FclChecker(ROBOT, [big], names=["big"])
    assert checker.collides((0.3, 0, 0))
    assert not checker.is_valid((0.3, 0, 0))
    assert checker.distance((0.3, 0, 0)) == 0.0
    name, depth = checker.colliding_obstacle((0.3, 0, 0))
    assert name == "big"
    assert depth == pytest.approx(2.2, abs=1e-6)  # shortest way out: +x by 2.2
    assert checker.is_valid((3.0, 0, 0))
    assert checker.distance((3.0, 0, 0)) == pytest.approx(0.5)


def test_obstacle_inside_robot_is_collision_though_raw_fcl_misses_it():
    big_robot = box([4, 4, 4])
    pebble = box([0.2, 0.2, 0.2], [1.0, 1.0, 1.0])
    assert not raw_fcl_collides(big_robot, pebble, (0, 0, 0))
    checker = FclChecker(big_robot, [pebble])
    assert checker.collides((0, 0, 0))
    assert checker.colliding_obstacle((0, 0, 0))[0] == "obstacle_0"
    assert not checker.collides((3.5, 0, 0))
    assert checker.distance((3.5, 0, 0)) == pytest.approx(0.4)


def test_robot_in_sealed_cavity_is_free_with_closed_form_clearance():
    checker = FclChecker(ROBOT, [hollow_box(4.0, 2.0)])
    assert checker.is_valid((0, 0, 0))
    assert checker.distance((0, 0, 0)) == pytest.approx(0.5)
    assert checker.distance((0.2, 0.3, 0)) == pytest.approx(0.2)
    assert not checker.is_valid((1.0, 0, 0))  # inside the shell's wall
    assert checker.is_valid((4.0, 0, 0))


def test_distance_matches_closed_form_for_boxes():
    obstacles = [box([1, 1, 1]), box([2, 1, 0.5], [4, 0, 0])]
    checker = FclChecker(ROBOT, obstacles)
    rng = np.random.default_rng(0)
    for t in rng.uniform(-4, 8, size=(20, 3)):
        expected = min(
            box_distance(t, [0.5] * 3, [0, 0, 0], [0.5] * 3),
            box_distance(t, [0.5] * 3, [4, 0, 0], [1, 0.5, 0.25]),
        )
        got = checker.distance(t)
        if expected > 1e-9:
            assert got == pytest.approx(expected, rel=1e-9, abs=1e-12)
            assert checker.is_valid(t)
        else:
            assert got == 0.0
            assert not checker.is_valid(t)
    assert checker.n_valid + checker.n_invalid == 20


def test_touching_is_contact_at_zero_tolerance():
    block = box([1, 1, 1])
    exact = FclChecker(ROBOT, [block])
    assert exact.collides((1.0, 0, 0))
    assert not exact.is_valid((1.0, 0, 0))
    assert exact.colliding_obstacle((1.0, 0, 0)) == ("obstacle_0", 0.0)
    assert exact.is_valid((1.0 + 1e-9, 0, 0))


def test_contact_tolerance_accepts_shallow_rejects_deep():
    block = box([1, 1, 1])
    tolerant = FclChecker(ROBOT, [block], contact_tolerance=0.01)
    assert tolerant.is_valid((1.0, 0, 0))  # touching
    assert tolerant.is_valid((0.995, 0, 0))  # 0.005 deep
    assert tolerant.penetration_bound((0.995, 0, 0)) <= 0.01
    assert not tolerant.is_valid((0.98, 0, 0))  # 0.02 deep
    assert not tolerant.is_valid((0.0, 0, 0))
    # a tolerated slide along the face is valid; pushing through is not
    assert tolerant.check_segment((0.998, -2, 0), (0.998, 2, 0)).valid
    assert not tolerant.check_segment((1.0, -2, 0), (0.9, 2, 0)).valid
    assert not FclChecker(ROBOT, [block]).check_segment((1.0, -2, 0), (1.0, 2, 0)).valid
    with pytest.raises(ValueError):
        FclChecker(ROBOT, [block], contact_tolerance=-1.0)


def test_a_motion_through_a_tolerated_overlap_reuses_its_last_witness(monkeypatch):
    """A cap pressed 0.01 into a block's top, slid off sideways under a tolerance just
    above the overlap: every pose is tolerated, freed only by lifting it about 0.01. The
    witness of each pose is tried first at the next (a search of every shorter length
    along every direction first cost the Circle cap in its bottle 360 FCL queries a
    pose), and the motion is valid exactly when the tolerance covers the overlap."""
    block, cap = box([2, 2, 2]), box([1, 1, 1])
    start, end = (0.0, 0.0, 1.49), (0.0, 3.0, 1.49)
    calls = []
    checker = FclChecker(cap, [block], contact_tolerance=0.0102)
    original = checker._free_distance
    monkeypatch.setattr(checker, "_free_distance", lambda t: calls.append(1) or original(t))
    check = checker.check_segment(start, end)
    assert check.valid and check.n_checks > 10
    # the first tolerated pose searches the ladder; each later one: its own free test,
    # the last witness, and one shorter length along it
    assert len(calls) <= 3 * check.n_checks + len(checker._witness_lengths(0.0102)) * 8
    assert checker.penetration_bound((0.0, 1.0, 1.49)) <= 0.0102
    assert not FclChecker(cap, [block], contact_tolerance=0.009).check_segment(start,
                                                                                end).valid


def test_tolerance_accepting_finds_the_shortest_freeing_translation_of_a_surface():
    """A unit cube crossing a sheet (a surface: no penetration depth) 0.02 past its
    bottom: the tolerance returned is about 0.02 and accepted, a smaller one is not."""
    plate = trimesh.Trimesh([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]],
                            [[0, 1, 2], [0, 2, 3]])  # a square sheet at z = 0
    checker = FclChecker(ROBOT, [plate], solid=[False])
    at = (0.0, 0.0, 0.48)  # the cube's bottom 0.02 below the plate's rim
    needed = checker.tolerance_accepting(at, upto=1.0)
    assert needed is not None and 0.02 <= needed <= 0.02 + 1e-3
    assert checker.accepts_with(at, needed)
    assert FclChecker(ROBOT, [plate], contact_tolerance=needed, solid=[False]).is_valid(at)
    assert not checker.accepts_with(at, 0.9 * 0.02)
    assert checker.tolerance_accepting((0.0, 0.0, 3.0), upto=1.0) == 0.0
    deep = FclChecker(ROBOT, [box([4, 4, 4])])
    assert deep.tolerance_accepting((0.0, 0.0, 0.0), upto=1.0) is None  # 2.5 to leave


# ---------------------------------------------------------------- motions


def test_sweep_through_block_is_caught_though_waypoints_are_free():
    # FCL's continuousCollide (default conservative advancement) reports no collision
    # for this sweep; check_segment must not rely on it.
    checker = FclChecker(ROBOT, [box([1, 1, 1])], names=["block"])
    a, b = (-3.0, 0.0, 0.0), (3.0, 0.0, 0.0)
    assert checker.is_valid(a) and checker.is_valid(b)  # sampling only waypoints passes
    seg = checker.check_segment(a, b)
    assert not seg.valid
    assert seg.obstacle == "block"
    np.testing.assert_allclose(seg.first_invalid, [-1.0, 0, 0], atol=1e-6)
    assert seg.last_valid_fraction == pytest.approx(2.0 / 6.0, abs=1e-6)
    assert checker.check_motion(a, b) == (False, seg.last_valid_fraction)
    path = checker.check_path([(-3, 3, 0), a, b])
    assert not path.valid and path.first_bad_segment == 1


def test_sweep_through_thin_plate_is_caught():
    plate = box([0.01, 4, 4])
    tiny = box([0.05, 0.05, 0.05])
    checker = FclChecker(tiny, [plate])
    assert not checker.check_segment((-2, 0, 0), (2, 0, 0)).valid
    assert checker.check_segment((-2, 2.5, 0), (2, 2.5, 0)).valid


def test_path_around_block_has_closed_form_clearance():
    checker = FclChecker(ROBOT, [box([1, 1, 1])])
    result = checker.check_path([(-3, 0, 0), (-3, 2, 0), (3, 2, 0), (3, 0, 0)])
    assert result.valid and result.first_bad_segment is None
    assert result.min_clearance == pytest.approx(1.0, rel=1e-9)
    assert result.clearance_lower_bound <= result.min_clearance
    assert checker.check_motion((-3, 2, 0), (3, 2, 0)) == (True, None)
    assert checker.n_valid_motions == 1


def test_diagonal_pass_clearance_is_refined_to_the_true_minimum():
    checker = FclChecker(ROBOT, [box([1, 1, 1])])
    a, b = np.array([-2.0, 2.5, 0.3]), np.array([2.0, 1.2, -0.2])
    s = np.linspace(0, 1, 20001)[:, None]
    truth = min(box_distance(p, [0.5] * 3, [0, 0, 0], [0.5] * 3) for p in a + s * (b - a))
    seg = checker.check_segment(a, b)
    assert seg.valid
    assert seg.min_distance == pytest.approx(truth, rel=2e-3)
    assert seg.clearance_lower_bound <= truth + 1e-9


def test_window_path_clearance():
    wall, names = window_wall()
    checker = FclChecker(ROBOT, wall, names=names)
    straight = checker.check_path([(-3, 0, 0), (3, 0, 0)])
    assert straight.valid
    assert straight.min_clearance == pytest.approx(0.5, rel=1e-9)  # 1 - 0.5 in y and z
    cut = checker.check_path(CORNER_CUT)
    assert not cut.valid and cut.first_bad_segment == 1 and cut.obstacle == "left"
    np.testing.assert_allclose(cut.first_invalid, [0.58, 0.5, 0], atol=1e-6)  # entry
    name, depth = checker.colliding_obstacle((0.59, 0.51, 0))
    assert name == "left" and depth == pytest.approx(0.01, abs=1e-6)


def test_bad_inputs_raise():
    checker = FclChecker(ROBOT, [box([1, 1, 1])])
    with pytest.raises(ValueError):
        checker.is_valid((0, 0))
    with pytest.raises(ValueError):
        checker.check_path(np.zeros((0, 3)))
    with pytest.raises(ValueError):
        FclChecker(ROBOT, [box([1, 1, 1])], names=["a", "b"])


# ---------------------------------------------------------------- OMPL's check


def test_ompl_accepts_valid_path_and_simplifies_it():
    wall, names = window_wall()
    checker = FclChecker(ROBOT, wall, names=names)
    path = [(-3, 0, 0), (-1, 0.1, 0.1), (1, -0.1, 0), (3, 0, 0)]
    result = ompl_check_path(path, checker, BOUNDS, simplify=True)
    assert result.valid
    assert result.length == pytest.approx(
        sum(math.dist(p, q) for p, q in zip(path, path[1:])), rel=1e-12
    )
    # clearance 0.5 -> step 0.25 is above the 1% cap (0.173): the cap applies
    assert result.resolution_used == pytest.approx(DEFAULT_RESOLUTION)
    assert result.simplified_valid
    assert result.simplified_length <= result.length + 1e-12
    np.testing.assert_allclose(result.simplified[0], path[0])
    np.testing.assert_allclose(result.simplified[-1], path[-1])
    assert result.n_valid_checks > 0 and result.n_invalid_checks == 0


def test_ompl_rejects_corner_cut_at_clearance_resolution_but_default_accepts_it():
    wall, names = window_wall()
    checker = FclChecker(ROBOT, wall, names=names)
    assert not checker.check_path(CORNER_CUT).valid
    ours = ompl_check_path(CORNER_CUT, checker, BOUNDS)
    assert not ours.valid
    assert ours.resolution_used == pytest.approx(MIN_RESOLUTION)  # invalid: clearance 0
    assert ours.step < 0.028  # the cut is 0.028 long along the segment
    # the pitfall: OMPL's default resolution (1% of the extent) accepts the cut
    default = ompl_check_path(CORNER_CUT, checker, BOUNDS, resolution=DEFAULT_RESOLUTION)
    assert default.valid
    assert default.step == pytest.approx(0.01 * math.sqrt(300))


def test_resolution_for_clearance_is_half_clearance_clamped():
    extent = math.sqrt(300)
    assert resolution_for_clearance(0.02, BOUNDS) == pytest.approx(0.01 / extent)
    assert resolution_for_clearance(10.0, BOUNDS) == DEFAULT_RESOLUTION
    assert resolution_for_clearance(0.0, BOUNDS) == MIN_RESOLUTION
    assert resolution_for_clearance(1e-9, BOUNDS) == MIN_RESOLUTION


def test_ompl_rejects_out_of_bounds_path():
    checker = FclChecker(ROBOT, [box([1, 1, 1])])
    assert not ompl_check_path([(-3, 0, 0), (-3, 0, 6)], checker, BOUNDS, clearance=1.0).valid
    with pytest.raises(ValueError):
        ompl_check_path([(0, 0, 0)], checker, [[0, 0, 0], [0, 1, 1]])


def test_without_ompl_validation_is_fcls_and_ompl_planners_say_why(monkeypatch):
    import sys
    from pathlib import Path

    from planner.errors import InvalidParameterError
    from planner.io import load_scenario
    from planner.planning import plan

    scenario = load_scenario(Path(__file__).resolve().parents[1] / "scenarios"
                             / "peg_in_hole.yaml")
    monkeypatch.setitem(sys.modules, "ompl", None)  # `import ompl` fails, as off Linux/macOS
    outcome = plan(scenario, progress=False)
    assert outcome.found and outcome.validation["valid"] and outcome.validation["fcl"]["valid"]
    assert outcome.validation["ompl"]["available"] is False
    assert "wheels for CPython 3.10-3.13 on Linux" in outcome.validation["ompl"]["reason"]
    with pytest.raises(InvalidParameterError, match="OMPL is not installed"):
        plan(scenario, planner="ompl:RRTConnect", progress=False)


def test_without_ompl_the_cli_says_so_in_one_line(monkeypatch, tmp_path, capsys):
    """``plan`` notes it on stderr (one line), FCL still validates; an OMPL planner, in
    ``plan`` or ``batch``, is refused in one line saying why."""
    import json
    import sys
    from pathlib import Path

    from planner.cli import main

    scenario = str(Path(__file__).resolve().parents[1] / "scenarios" / "peg_in_hole.yaml")
    monkeypatch.setitem(sys.modules, "ompl", None)
    assert main(["plan", scenario, "--out", str(tmp_path / "a"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("minkplan: note: OMPL is not installed") and len(
        err.splitlines()) == 1, err
    validation = json.loads((tmp_path / "a" / "path.json").read_text())["validation"]
    assert validation["fcl"]["valid"] and validation["ompl"]["available"] is False
    for args in (["plan", scenario, "--out", str(tmp_path / "b"), "--planner",
                  "ompl:RRTConnect"],
                 ["batch", scenario, "--out", str(tmp_path / "c"), "--planners",
                  "minkplan,ompl:PRM"]):
        assert main([*args, "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert "OMPL is not installed" in err and len(err.splitlines()) == 1, err
