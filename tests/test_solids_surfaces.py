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
from planner.problem import Body, Part, PlannerSettings, Robot, Scenario
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


def t_junction_box() -> trimesh.Trimesh:
    """A unit cube whose top is split at the middle of one top edge (a vertex there),
    while the side face below keeps that edge whole: a T-junction, open as it stands."""
    v = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1],
         [0, 1, 1], [0.5, 0, 1]]
    f = [[0, 2, 1], [0, 3, 2],                      # bottom
         [4, 8, 7], [8, 6, 7], [8, 5, 6],           # top, split at vertex 8 on edge 4-5
         [0, 1, 5], [0, 5, 4],                      # front (y = 0): edge 4-5 whole
         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
    return trimesh.Trimesh(np.array(v, float), np.array(f), process=False)


@pytest.mark.parametrize("reversed_face", [0, 5])
def test_a_face_wound_against_its_neighbours_is_turned_and_said(reversed_face):
    """One face of a box reversed (the first, which the consistent winding keeps as it is,
    or another): one face changed, not a shell turned inside out; a box exported inside
    out is one shell flipped. Both are in the part's changes."""
    from planner.meshes.kinds import classify

    box = trimesh.creation.box()
    faces = np.array(box.faces)
    faces[reversed_face] = faces[reversed_face][::-1]
    part = classify(trimesh.Trimesh(box.vertices, faces, process=False), name="box")
    assert part.solid and part.changes == {"fixed_winding_faces": 1}
    assert part.mesh.volume == pytest.approx(1.0)
    inside_out = classify(trimesh.Trimesh(box.vertices, box.faces[:, ::-1], process=False),
                          name="box")
    assert inside_out.changes == {"flipped_shells": 1} and inside_out.mesh.volume > 0
    assert classify(box, name="box").changes == {}


def test_degenerate_faces_dropped_are_said():
    """A face repeating a vertex (``[0, 0, 1]``) and a zero-area sliver along an edge are
    dropped to make the solid, and counted in the part's changes (they were dropped
    silently)."""
    from planner.meshes.kinds import classify

    box = trimesh.creation.box()
    collapsed = np.vstack([box.faces, [[0, 0, 1]]])
    part = classify(trimesh.Trimesh(box.vertices, collapsed, process=False), name="box")
    assert part.solid and len(part.mesh.faces) == 12
    assert part.changes == {"removed_collapsed_faces": 1}
    a, b = box.faces[0][:2]
    middle = (box.vertices[a] + box.vertices[b]) / 2
    sliver = trimesh.Trimesh(np.vstack([box.vertices, [middle]]),
                             np.vstack([box.faces, [[a, len(box.vertices), b]]]),
                             process=False)
    part = classify(sliver, name="box")
    assert part.solid and len(part.mesh.faces) == 12
    assert part.changes == {"removed_degenerate_faces": 1}


def test_repeated_faces_and_back_to_back_pairs_dropped_are_said():
    """A face given twice, and a fin of no thickness (a face and its reverse), are
    dropped to make the solid and counted in the part's changes (they were dropped
    silently; the fin is geometry the input had)."""
    from planner.meshes.kinds import classify

    box = trimesh.creation.box()
    repeated = trimesh.Trimesh(box.vertices, np.vstack([box.faces, box.faces[:1]]),
                               process=False)
    part = classify(repeated, name="box")
    assert part.solid and len(part.mesh.faces) == 12
    assert part.changes == {"removed_duplicate_faces": 1}
    fin = np.vstack([box.vertices, [[0.0, 0.0, 2.0]]])
    a, b = box.faces[0][:2]
    pair = [[a, b, len(box.vertices)], [b, a, len(box.vertices)]]
    part = classify(trimesh.Trimesh(fin, np.vstack([box.faces, pair]), process=False),
                    name="box")
    assert part.solid and len(part.mesh.faces) == 12
    assert part.changes == {"removed_back_to_back_faces": 2}


def test_a_faces_reversed_copy_is_dropped_and_said():
    """A try-out: a box with one face given again, reversed. Dropping both of the pair
    opens the surface, so it was refused as "not watertight (3 boundary edges)"; the copy
    is dropped (the later of the two, the face kept being turned where it is the one
    wound against its neighbours), and said."""
    from planner.meshes.kinds import classify

    box = trimesh.creation.box()
    copy_last = np.vstack([box.faces, box.faces[3][::-1]])
    part = classify(trimesh.Trimesh(box.vertices, copy_last, process=False), name="box")
    assert part.solid and len(part.mesh.faces) == 12
    assert part.changes == {"removed_reversed_copies": 1}
    assert part.mesh.volume == pytest.approx(1.0)
    copy_first = np.vstack([box.faces[:3], box.faces[3][::-1], box.faces[3:]])
    part = classify(trimesh.Trimesh(box.vertices, copy_first, process=False), name="box")
    assert part.solid and part.mesh.volume == pytest.approx(1.0)
    assert part.changes == {"removed_reversed_copies": 1, "fixed_winding_faces": 1}


def test_t_junctions_are_split_and_the_part_is_a_solid():
    from planner.meshes.kinds import classify

    mesh = t_junction_box()
    with pytest.raises(InvalidMeshError, match="not watertight"):
        validate_solid(mesh, name="t")
    part = classify(mesh, name="t")
    assert part.solid and part.changes == {"t_junctions_split": 1}
    assert part.mesh.is_watertight and part.mesh.volume == pytest.approx(1.0)
    np.testing.assert_array_equal(np.sort(part.mesh.vertices, axis=0),
                                  np.sort(mesh.vertices, axis=0))  # no vertex moved


def test_kinds_force_a_solid_or_a_surface():
    from planner.meshes.kinds import classify

    box = trimesh.creation.box(extents=[1, 1, 1])
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2], process=False)
    surface = classify(open_box, name="lid")
    assert not surface.solid and "not watertight" in surface.reason
    assert len(surface.mesh.faces) == 10
    with pytest.raises(InvalidMeshError, match="not watertight"):
        classify(open_box, name="lid", kind="solid")
    asked = classify(box, name="box", kind="surface")
    assert not asked.solid and asked.reason == "kind surface asked for"
    repaired = classify(open_box, name="lid", kind="solid", repair=True)
    assert repaired.solid and repaired.changes["filled_holes"] == 1
    with pytest.raises(InvalidMeshError, match="kind 'hollow'"):
        classify(box, name="box", kind="hollow")


@pytest.mark.parametrize("name", ["factory_round_peg_8mm", "factory_rect_peg_8mm"])
def test_factory_peg_assemblies_load_and_plan(name):
    """NVIDIA's Factory holes are open only at T-junctions: split, they are solids, and the
    pegs come out; every removal validated by FCL at the contact tolerance."""
    from conftest import asset

    assembly = planner.load_assembly(asset(f"assemblies/{name}/{name}.yaml"))
    hole = next(p for p in assembly.parts if p.name == "hole")
    assert hole.solid and hole.repairs.get("t_junctions_split", 0) > 0
    result = planner.plan_assembly(assembly)
    assert result.found, result.message
    for step in result.removal:
        assert step.validation["valid"], step


def surface_membership_disagreements(obstacle: Part, robot: Part, n: int, seed: int) -> int:
    """Random translations over the C-obstacle's box where the exact source and FCL (on
    the meshes as given, each part a solid or a surface) disagree."""
    from planner.sources import ExactSource, SourceSettings

    pair = ExactSource(SourceSettings(exact=True), "test").pair(obstacle, robot)
    lo = obstacle.mesh.bounds[0] - robot.mesh.bounds[1]
    hi = obstacle.mesh.bounds[1] - robot.mesh.bounds[0]
    points = np.random.default_rng(seed).uniform(lo, hi, size=(n, 3))
    ours = pair.contains(points)
    checker = FclChecker(robot.mesh, [obstacle.mesh], solid=[obstacle.solid],
                         robot_solid=robot.solid)
    theirs = np.array([checker.collides(p) for p in points])
    assert 0.05 < ours.mean() < 0.95  # both answers occur
    return int((ours != theirs).sum())


@pytest.mark.assets
def test_surface_c_obstacle_membership_agrees_with_fcl_on_real_soups():
    """OMPL.app triangle soups as FCL sees them: Easy's frame (a surface) for Easy's robot
    (a solid), and spirelli's open world piece for its open robot (both surfaces);
    10,000 random translations each."""
    easy = planner.load_scenario(EASY)
    frame = next(b for b in easy.obstacles if len(b.mesh.faces) == 52)
    assert surface_membership_disagreements(frame, easy.robot, 10_000, 1) == 0
    spirelli = planner.load_scenario(EASY.with_name("spirelli.cfg"), hold_orientation="start")
    soup = next(b for b in spirelli.obstacles if not b.solid)
    assert not spirelli.robot.solid
    assert surface_membership_disagreements(soup, spirelli.robot, 10_000, 2) == 0
