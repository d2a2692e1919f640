"""Solids and surfaces: the exact winding-number test, surface semantics in the planner and
the validators, and certificates re-verified before a no-path is reported.

The regression: OMPL.app's Easy frame (a floor and a back wall glued into one closed,
consistently wound surface, inside out in part) was trusted as a solid, and the exact
source certified false walls: a small problem built from it was answered ``no_path`` while
an OMPL planner found a path FCL accepts.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

import planner
from planner._minkowski_core import CSpace
from planner.errors import InvalidMeshError
from planner.meshes import validate_solid
from planner.planning.ompl_baseline import plan_ompl
from planner.problem import Body, PlannerSettings, Robot, Scenario
from planner.validation import FclChecker

EASY = Path(__file__).resolve().parents[2] / "shared" / "assets" / "omplapp" / "Easy.cfg"


def folded_box() -> trimesh.Trimesh:
    """A unit box with one top corner pulled through its bottom: one closed, consistently
    wound shell that is inside out where it folds (winding number -1 there), the kind of
    surface Easy's frame is."""
    box = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    vertices = box.vertices.copy()
    corner = np.flatnonzero(np.all(vertices == [0, 0, 1], axis=1))
    vertices[corner] = [0.3, 0.4, -0.6]
    return trimesh.Trimesh(vertices, box.faces, process=False)


def test_a_closed_mesh_with_inverted_faces_is_no_solid():
    with pytest.raises(InvalidMeshError, match=r"not a solid: 2 of 12 faces and 6 of 6 crossings "
                                               r"of faces have the inside in front of them "
                                               r"\(winding number -1"):
        validate_solid(folded_box(), name="folded")
    # a whole shell inside out is flipped; overlapping outward shells are their union
    floor = trimesh.creation.box(bounds=[[0, 0, 0], [10, 1, 10]])
    floor.invert()
    wall = trimesh.creation.box(bounds=[[0, 0, 0], [10, 10, 1]])
    frame = validate_solid(trimesh.util.concatenate([floor, wall]), name="frame")
    assert frame.volume == pytest.approx(100 + 100)
    bars = trimesh.util.concatenate([trimesh.creation.box(bounds=[[0, 0, 0], [2, 1, 1]]),
                                     trimesh.creation.box(bounds=[[1, 0, 0], [3, 1, 1]])])
    assert validate_solid(bars, name="bars").volume == pytest.approx(4.0)


def test_the_core_refuses_a_surface_claimed_to_be_a_solid():
    folded = folded_box()
    arrays = (np.asarray(folded.vertices, dtype=np.float64),
              np.asarray(folded.faces, dtype=np.int64))
    cube = trimesh.creation.box(extents=[0.2, 0.2, 0.2])
    robot = (np.asarray(cube.vertices, dtype=np.float64), np.asarray(cube.faces, dtype=np.int64))
    bounds = np.array([[-2.0, -2, -2], [3.0, 3, 3]])
    with pytest.raises(InvalidMeshError, match="bounds no solid"):
        CSpace.exact([arrays], robot, bounds, 0.01, 0.1)
    assert len(CSpace.exact([arrays], robot, bounds, 0.01, 0.1, solid=[False])) > 0
    scenario = Scenario(name="claim", units="m",
                        robot=Robot("cube", cube, "box"),
                        obstacles=[Body("folded", folded, "test", solid=True)],
                        start=[2, 2, 2], goal=[2.5, 2, 2], orientation=np.eye(3),
                        bounds=(bounds[0], bounds[1]), settings=PlannerSettings())
    with pytest.raises(InvalidMeshError, match="not a solid"):
        planner.plan(scenario)


def test_containment_counts_only_in_solids():
    block = trimesh.creation.box(extents=[4, 4, 4])
    robot = trimesh.creation.box(extents=[0.5, 0.5, 0.5])
    assert FclChecker(robot, [block]).collides([0, 0, 0])
    assert not FclChecker(robot, [block], solid=[False]).collides([0, 0, 0])
    assert FclChecker(robot, [block], solid=[False]).collides([1.9, 0, 0])
    # a solid robot swallowing a surface obstacle collides; a surface robot does not
    assert FclChecker(block, [robot], solid=[False]).collides([0, 0, 0])
    assert not FclChecker(block, [robot], robot_solid=False).collides([0, 0, 0])


def sealed_box_scenario(solid: bool, start) -> Scenario:
    shell = trimesh.creation.box(extents=[6, 6, 6])
    robot = Robot("cube", trimesh.creation.box(extents=[1, 1, 1]), "box")
    return Scenario(name="sealed", units="m", robot=robot,
                    obstacles=[Body("shell", shell, "box", solid=solid,
                                    kind_reason="test")],
                    start=start, goal=[0, 0, 6], orientation=np.eye(3),
                    bounds=(np.array([-8.0, -8, -8]), np.array([8.0, 8, 8])),
                    settings=PlannerSettings(time_limit=20))


def test_a_robot_sealed_in_a_surface_box_has_a_verified_certificate():
    outcome = planner.plan(sealed_box_scenario(False, [0, 0, 0]))
    assert outcome.status == "no_path"
    assert outcome.certificate["exact"]
    assert outcome.report["scenario"]["obstacles"][0]["kind"] == "surface"
    # the same start inside a solid box is a collision, not a sealed room
    inside_solid = planner.plan(sealed_box_scenario(True, [0, 0, 0]))
    assert inside_solid.reason == "start_in_collision"


def test_a_path_around_a_surface_box_is_found_and_valid():
    outcome = planner.plan(sealed_box_scenario(False, [0, 0, -6]))
    assert outcome.status == "found"
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]


@pytest.fixture(scope="module")
def floor_and_post() -> Scenario:
    """The problem of the regression: Easy's imported frame, one 20×70×20 box post, the
    robot resting just above the floor (bounds y in [5, 8])."""
    easy = planner.load_scenario(EASY)
    frame = next(b for b in easy.obstacles if len(b.mesh.faces) == 52)
    post = trimesh.creation.box(extents=[20, 70, 20])
    post.apply_translation([210, 25, -160])
    lo, hi = easy.bounds
    return Scenario(name="floor_and_post", units="unitless", robot=easy.robot,
                    obstacles=[frame, Body("post", post, "box")],
                    start=[270, 7.95, -200], goal=[150, 7.95, -120], orientation=np.eye(3),
                    bounds=(np.array([lo[0], 5.0, lo[2]]), np.array([hi[0], 8.0, hi[2]])),
                    settings=PlannerSettings(time_limit=20, seed=1))


@pytest.mark.assets
def test_easy_frame_is_a_surface_and_the_floor_problem_is_solved(floor_and_post):
    frame = floor_and_post.obstacles[0]
    assert not frame.solid and "winding number -1" in frame.kind_reason
    outcome = planner.plan(floor_and_post)
    assert outcome.status == "found", outcome.message
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]
    # OMPL's planner on the same FCL checker agrees that a path exists
    baseline = plan_ompl(floor_and_post, "RRTConnect")
    assert baseline.status == "found"
