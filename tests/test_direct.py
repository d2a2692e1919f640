"""The direct motion: the straight segment from start to goal tested exactly, before any
C-space, for large problems (IndustReal's gears come off their shafts that way).

Checked independently: the pieces-only sums answer membership and segment queries as the
reduced-convolution sums do and as FCL's collision of the meshes does; a blocked straight
line is never taken (the C-space is built and plans around it); an end resting in contact
is stepped out as the planner steps it out.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from conftest import SHARED_ASSETS

import planner
from planner import _minkowski_core as core
from planner import viz
from planner.errors import InvalidParameterError, ResourceLimitError
from planner.planning import OctreeParams
from planner.planning.direct import PieceObstacles, direct_motion
from planner.problem import Body, PlannerSettings, Robot, Scenario
from planner.sources import choose_for
from planner.validation import FclChecker

DIRECT_ALWAYS = OctreeParams(direct_first_pairs=0)


def wall_scene(gap: bool, start, goal) -> Scenario:
    """A unit cube robot, a floor slab under z = 0, and a wall across x = 0 (with a
    1.6-wide gap at y = 3 when ``gap``); bounds x, y in ±5, z in [0, 3]."""
    floor = trimesh.creation.box(extents=[10, 10, 1])
    floor.apply_translation([0, 0, -0.5])
    if gap:
        left = trimesh.creation.box(extents=[0.4, 7.2, 3])
        left.apply_translation([0, -1.4, 1.5])
        right = trimesh.creation.box(extents=[0.4, 1.2, 3])
        right.apply_translation([0, 4.4, 1.5])
        wall = trimesh.util.concatenate([left, right])
    else:
        wall = trimesh.creation.box(extents=[0.4, 10, 3])
        wall.apply_translation([0, 0, 1.5])
    robot = Robot("cube", trimesh.creation.box(extents=[1, 1, 1]), "box")
    bodies = [Body("floor", floor, "box"), Body("wall", wall, "box", solid=not gap,
                                                kind_reason="test")]
    return Scenario(name="walls", units="m", robot=robot, obstacles=bodies,
                    start=start, goal=goal, orientation=np.eye(3),
                    bounds=(np.array([-5.0, -5, 0.5]), np.array([5.0, 5, 3])),
                    settings=PlannerSettings(time_limit=30))


def test_pieces_only_sums_agree_with_the_convolution_and_with_fcl():
    a = trimesh.creation.annulus(r_min=0.4, r_max=1.0, height=0.6, sections=24)
    b = trimesh.creation.icosphere(2, radius=0.3)
    b.vertices += [0.1, -0.05, 0.2]
    full = core.ExactSum((a.vertices, a.faces), (-b.vertices, b.faces[:, ::-1]))
    pieces = core.ExactSum((a.vertices, a.faces), (-b.vertices, b.faces[:, ::-1]),
                           pieces=True)
    assert full.facets > 0 and pieces.facets == 0
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.6, 1.6, size=(4000, 3))
    inside = pieces.contains(points)
    assert np.array_equal(inside, full.contains(points))
    assert 200 < inside.sum() < 3800  # both kinds of point are tested
    # FCL's membership oracle: p is in A ⊕ (−B) exactly when A meets B moved by p
    robot = Robot("ball", b, "mesh")
    checker = FclChecker.for_parts(robot, [Body("ring", a, "mesh")], contact_tolerance=0.0)
    for p, flag in zip(points[:600], inside[:600]):
        assert checker.collides(p) == flag, p
    for _ in range(300):
        p, q = rng.uniform(-1.6, 1.6, size=(2, 3))
        assert pieces.segment_is_free(p.tolist(), q.tolist()) == \
            full.segment_is_free(p.tolist(), q.tolist())


def test_a_pieces_only_sum_refuses_a_surface():
    box = trimesh.creation.box()
    pieces = core.ExactSum((box.vertices, box.faces), (box.vertices, box.faces), pieces=True)
    with pytest.raises(InvalidParameterError, match="pieces=True"):
        pieces.surface(0.1)


def test_a_free_straight_motion_is_the_answer_and_builds_no_cspace():
    scenario = wall_scene(True, [-3, 3, 1.2], [3, 3, 1.2])
    outcome = planner.plan(scenario, params=DIRECT_ALWAYS)
    assert outcome.status == "found" and outcome.reason == "direct", outcome.message
    assert np.allclose(outcome.waypoints, [[-3, 3, 1.2], [3, 3, 1.2]])
    assert outcome.validation["fcl"]["valid"] and outcome.cspace is None
    assert outcome.report["direct"]["free"] and "cells" not in outcome.report
    assert outcome.timings["octree"] == 0.0
    # the default tries it only for large problems
    assert planner.plan(scenario).reason == "path"


def test_a_blocked_straight_motion_is_never_taken():
    scenario = wall_scene(True, [-3, 0, 1.2], [3, 0, 1.2])  # the wall's solid part between
    outcome = planner.plan(scenario, params=DIRECT_ALWAYS)
    assert outcome.report["direct"] == {"free": False,
                                        "seconds": outcome.report["direct"]["seconds"]}
    assert outcome.status == "found" and outcome.reason == "path", outcome.message
    assert outcome.validation["fcl"]["valid"]
    assert np.max(outcome.waypoints[:, 1]) > 2.0  # through the gap at y = 3
    closed = wall_scene(False, [-3, 0, 1.2], [3, 0, 1.2])
    assert planner.plan(closed, params=DIRECT_ALWAYS).status == "no_path"


def test_an_end_resting_in_contact_is_stepped_out_first():
    # the cube rests on the floor (z = 0.5: its bottom face on z = 0), a tolerated contact
    scenario = wall_scene(True, [-3, 3, 0.5], [3, 3, 1.2])
    scenario = dataclasses.replace(scenario, bounds=(np.array([-5.0, -5, 0.5]),
                                                     np.array([5.0, 5, 3])))
    source = choose_for([scenario.robot, *scenario.obstacles], scenario.settings)
    checker = FclChecker.for_parts(scenario.robot, scenario.obstacles, contact_tolerance=1e-6)
    obstacles = PieceObstacles(scenario, source)
    assert obstacles.contains(np.array([[-3, 3, 0.5]]))[0]  # touching is in the closed set
    motion = direct_motion(scenario, source, checker, reach=2e-6, margin=0.0).motion
    assert motion is not None and len(motion) == 3
    assert np.allclose(motion[0], [-3, 3, 0.5]) and np.allclose(motion[-1], [3, 3, 1.2])
    assert not obstacles.contains(motion[1:2])[0]
    assert checker.check_path(motion).valid
    # already at the goal, in the same contact: no motion (as the planner answers it)
    here = dataclasses.replace(scenario, goal=np.array([-3.0, 3, 0.5]))
    stay = direct_motion(here, source, checker, reach=2e-6, margin=0.0).motion
    assert stay is not None and np.array_equal(stay, [[-3, 3, 0.5], [-3, 3, 0.5]])
    # in collision (sunk into the floor) is no direct motion
    sunk = dataclasses.replace(scenario, start=np.array([-3.0, 3, 0.4]))
    sunk_direct = direct_motion(sunk, source, checker, reach=2e-6, margin=0.0)
    assert sunk_direct.motion is None and sunk_direct.in_collision == "start"


@pytest.mark.skipif(not (SHARED_ASSETS / "assemblies").is_dir(),
                    reason="../shared/assets is absent (a user's clone): IndustReal's gears")
def test_each_industreal_gear_comes_off_its_shaft_directly():
    from planner.assembly import removal_scenario  # noqa: PLC0415

    assembly = planner.load_assembly(
        SHARED_ASSETS / "assemblies/industreal_gears/industreal_gears.yaml")
    for gear in ("gear_small", "gear_large"):
        scenario = removal_scenario(assembly, gear, ["gear_base"], "+z")
        outcome = planner.plan(scenario)
        # before: refused (the boundary convolution passes the facet budget)
        assert outcome.status == "found" and outcome.reason == "direct", outcome.message
        assert outcome.validation["valid"]
        # straight up, but for the escape out of the resting contact (within its reach)
        reach = OctreeParams().escape_rel * outcome.validation["fcl"]["contact_tolerance"]
        assert outcome.waypoints[-1][2] > 0.04
        assert np.abs(outcome.waypoints[:, :2]).max() <= reach


def test_an_end_in_collision_is_the_answer_without_a_cspace():
    scenario = wall_scene(True, [-3, 3, 1.2], [0, 0, 1.5])  # the goal inside the wall
    outcome = planner.plan(scenario, params=DIRECT_ALWAYS)
    assert outcome.status == "no_path" and outcome.reason == "goal_in_collision"
    assert outcome.collision["obstacle"] == "wall" and outcome.cspace is None
    checker = FclChecker.for_parts(scenario.robot, scenario.obstacles)
    assert checker.collides(np.array([0.0, 0, 1.5]))


def test_a_refusal_after_a_blocked_straight_motion_says_so():
    scenario = wall_scene(True, [-3, 0, 1.2], [3, 0, 1.2])
    with planner.memory_limit(0.001), pytest.raises(ResourceLimitError) as refused:
        planner.plan(scenario, params=DIRECT_ALWAYS)
    message = str(refused.value)
    assert "after the straight motion was found blocked" in message and "\n" not in message


def test_a_scene_leaves_out_a_c_obstacle_over_the_memory_limit(caplog):
    scenario = wall_scene(True, [-3, 3, 1.2], [3, 3, 1.2])
    outcome = planner.plan(scenario, params=DIRECT_ALWAYS)
    with planner.memory_limit(0.001):
        scene = viz.scene_for_plan(scenario, outcome, c_obstacle=True)
    assert "leaves out the C-obstacle of wall" in caplog.text
    # the floor's C-obstacle (a box and the robot: a few cells resolved by planes) fits
    assert "path/line" in repr(scene) and "cspace/c_obstacle/wall" not in repr(scene)
    assert "<html>" in viz.to_html(scene)
