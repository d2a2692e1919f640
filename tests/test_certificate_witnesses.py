"""Every wall cell of a no-path certificate carries witnesses that a check trusting
nothing of minkplan confirms: here with scipy's convex hulls (a triangle pair's piece),
trimesh's containment and FCL's box-against-triangles test (a vertex inside a solid),
and the bounds; the witnesses' parts cover each wall cell's box."""

from __future__ import annotations

import fcl
import numpy as np
import pytest
import trimesh
from scipy.spatial import ConvexHull, QhullError
from test_exact_planning import write_scenario
from test_local_proof import LOCAL_ALWAYS, box_room

import planner
from planner.problem import Body, PlannerSettings, Robot, Scenario

SLACK = 1e-9
"""Relative rounding slack of the independent tests (a wall cell may touch its piece)."""


def corners(box: np.ndarray) -> np.ndarray:
    lo, hi = box
    return np.array([[(lo, hi)[i >> a & 1][a] for a in range(3)] for i in range(8)])


def piece_holds(box: np.ndarray, obstacle: np.ndarray, robot: np.ndarray) -> bool:
    """Whether every translation of ``box`` makes the robot's triangle meet the
    obstacle's: the box's corners lie in the convex hull of ``o - r`` (the translations
    where they meet), up to rounding."""
    points = (obstacle[:, None, :] - robot[None, :, :]).reshape(-1, 3)
    scale = float(np.abs(points).max() + np.abs(box).max())
    try:
        hull = ConvexHull(points)
    except QhullError:
        return False  # a flat piece holds no box
    return bool(np.all(corners(box) @ hull.equations[:, :3].T + hull.equations[:, 3]
                       <= SLACK * scale))


def box_in_solid(box: np.ndarray, solid: trimesh.Trimesh) -> bool:
    """Whether the box lies inside the closed mesh: its centre inside, and no triangle
    meets it (FCL's box against the triangles)."""
    centre, half = box.mean(axis=0), (box[1] - box[0]) / 2
    if not solid.contains([centre])[0]:
        return False
    model = fcl.BVHModel()
    model.beginModel(len(solid.vertices), len(solid.faces))
    model.addSubModel(np.asarray(solid.vertices), np.asarray(solid.faces))
    model.endModel()
    grown = fcl.Box(*(2 * half * (1 + SLACK)))
    request = fcl.CollisionRequest()
    result = fcl.CollisionResult()
    return not fcl.collide(fcl.CollisionObject(grown, fcl.Transform(centre)),
                           fcl.CollisionObject(model, fcl.Transform()), request, result)


def check_witnesses(outcome, scenario) -> dict[str, int]:
    """Confirm every wall cell's witnesses independently; counts by kind."""
    obstacles = {o.name: o for o in scenario.obstacles}
    lo, hi = (np.asarray(b, dtype=np.float64) for b in scenario.bounds)
    kinds: dict[str, int] = {}
    for wall in outcome.certificate["walls"]:
        box = np.asarray(wall["box"])
        parts = wall["witnesses"]
        assert parts, f"wall cell {wall['leaf']} has no witness"
        volume = sum(float(np.prod(np.subtract(*np.asarray(p["box"])[::-1]))) for p in parts)
        assert volume == pytest.approx(float(np.prod(box[1] - box[0])), rel=1e-9)
        for part in parts:
            sub = np.asarray(part["box"])
            assert np.all(sub[0] >= box[0] - 1e-12) and np.all(sub[1] <= box[1] + 1e-12)
            kind = part["kind"]
            kinds[kind] = kinds.get(kind, 0) + 1
            if kind == "triangles":
                assert piece_holds(sub, np.asarray(part["obstacle_triangle"]),
                                   np.asarray(part["robot_triangle"])), part
            elif kind == "robot_vertex":
                solid = obstacles[part["obstacle"]]
                assert solid.solid
                assert box_in_solid(sub + np.asarray(part["vertex"]), solid.mesh), part
            elif kind == "obstacle_vertex":
                assert scenario.robot.solid
                assert box_in_solid(np.asarray(part["vertex"]) - sub[::-1],
                                    scenario.robot.mesh), part
            elif kind == "bounds":
                axis, upper = divmod(part["side"], 2)
                assert sub[0][axis] >= hi[axis] if upper else sub[1][axis] <= lo[axis]
            else:
                raise AssertionError(f"unexpected witness kind {kind!r}")
    return kinds


def test_witnesses_of_a_peg_on_a_plate_hold_for_independent_tests(tmp_path):
    scenario = write_scenario(tmp_path, 9.98)
    outcome = planner.plan(scenario, progress=False)
    assert outcome.status == "no_path", outcome.message
    kinds = check_witnesses(outcome, scenario)
    assert kinds.get("triangles", 0) + kinds.get("robot_vertex", 0) \
        + kinds.get("obstacle_vertex", 0) > 0, kinds


def test_witnesses_of_a_cube_sealed_in_a_surface_box_hold_for_independent_tests():
    scenario = box_room(False, [0, 0, 0], [0, 0, 7])
    outcome = planner.plan(scenario, params=LOCAL_ALWAYS)
    assert outcome.status == "no_path", outcome.message
    kinds = check_witnesses(outcome, scenario)
    assert kinds.get("triangles", 0) > 0, kinds


def hollow_box(outer: float, inner: float) -> trimesh.Trimesh:
    """A solid cube of side ``outer`` with a cubic cavity of side ``inner``."""
    cavity = trimesh.creation.box(extents=[inner] * 3)
    cavity.invert()
    return trimesh.util.concatenate([trimesh.creation.box(extents=[outer] * 3), cavity])


def trapped(robot: Robot, obstacle: Body) -> Scenario:
    return Scenario(name="trapped", units="m", robot=robot, obstacles=[obstacle],
                    start=[0, 0, 0], goal=[0, 0, 9], orientation=np.eye(3),
                    bounds=(np.full(3, -12.0), np.full(3, 12.0)),
                    settings=PlannerSettings(time_limit=60))


def test_witnesses_of_a_post_caught_in_a_solid_cage_include_its_vertices():
    # the cage (the robot) cannot leave the post in its cavity: walls where a corner of
    # the post lies inside the cage's material
    scenario = trapped(Robot("cage", hollow_box(4, 2), "test"),
                       Body("post", trimesh.creation.box(extents=[1, 1, 1]), "test"))
    outcome = planner.plan(scenario, progress=False)
    assert outcome.status == "no_path", outcome.message
    assert check_witnesses(outcome, scenario).get("obstacle_vertex", 0) > 0


def test_witnesses_of_an_open_box_in_a_cavity_include_its_vertices():
    # a surface robot (a cube without its top, 768 triangles) in a solid's cavity: walls
    # where a vertex of the robot lies inside the solid's material
    cube = trimesh.creation.box(extents=[1, 1, 1])
    for _ in range(3):
        cube = cube.subdivide()
    open_cube = trimesh.Trimesh(cube.vertices, cube.faces[cube.face_normals[:, 2] < 0.5],
                                process=False)
    scenario = trapped(Robot("open", open_cube, "test", solid=False, kind_reason="test"),
                       Body("shell", hollow_box(6, 3), "test"))
    outcome = planner.plan(scenario, params=LOCAL_ALWAYS)
    assert outcome.status == "no_path", outcome.message
    assert check_witnesses(outcome, scenario).get("robot_vertex", 0) > 0


def test_a_wrong_witness_fails_the_independent_tests():
    triangle = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    robot = np.array([[0.0, 0, -0.5], [0, 0, 0.5], [0.2, 0.2, 0]])
    inside = np.array([[0.1, 0.1, -0.05], [0.15, 0.15, 0.05]])
    assert piece_holds(inside, triangle, robot)
    assert not piece_holds(inside + [0, 0, 2], triangle, robot)
    cube = trimesh.creation.box(extents=[2, 2, 2])
    assert box_in_solid(np.array([[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]]), cube)
    assert not box_in_solid(np.array([[0.5, 0.5, 0.5], [1.5, 1.5, 1.5]]), cube)
