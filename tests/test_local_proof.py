"""Local no-path proofs: an end walled off by verified FULL cells in a box around it,
tried first for large triangle soups (OMPL.app's spirelli held at one orientation).

The proofs are checked independently: every wall cell is in collision for FCL at its
centre and corners, and the walled-off component lies where the robot can be (closed form
for a sealed box); a pocket with an exit is never proved closed.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest
import trimesh
from conftest import SHARED_ASSETS

import planner
from planner.deadline import Deadline
from planner.errors import ResourceLimitError
from planner.planning import OctreeParams
from planner.planning.local_proof import prove_end_enclosed, wall_off
from planner.planning.slabs import subsets
from planner.problem import Body, PlannerSettings, Robot, Scenario
from planner.sources import choose_for
from planner.validation import FclChecker
from planner.validation.certificate_check import check_certificate

LOCAL_ALWAYS = OctreeParams(local_first_pairs=0)


def box_room(open_top: bool, start, goal) -> Scenario:
    """A unit cube robot in a 6 × 6 × 6 box given as a surface (its top face left out when
    ``open_top``), bounds ±8."""
    shell = trimesh.creation.box(extents=[6, 6, 6])
    if open_top:
        keep = shell.face_normals[:, 2] < 0.5
        shell = trimesh.Trimesh(shell.vertices, shell.faces[keep], process=False)
    robot = Robot("cube", trimesh.creation.box(extents=[1, 1, 1]), "box")
    return Scenario(name="room", units="m", robot=robot,
                    obstacles=[Body("shell", shell, "box", solid=False, kind_reason="test")],
                    start=start, goal=goal, orientation=np.eye(3),
                    bounds=(np.array([-8.0, -8, -8]), np.array([8.0, 8, 8])),
                    settings=PlannerSettings(time_limit=30))


def corners_and_centre(box: np.ndarray) -> np.ndarray:
    lo, hi = box
    corners = [[(lo, hi)[i >> a & 1][a] for a in range(3)] for i in range(8)]
    return np.vstack([corners, (lo + hi) / 2])


def assert_walls_collide(outcome, scenario: Scenario, n: int) -> None:
    """Every (sampled) wall cell of the certificate is in collision for FCL throughout."""
    checker = FclChecker.for_parts(scenario.robot, scenario.obstacles)
    walls = outcome.certificate["walls"]
    rng = np.random.default_rng(0)
    for k in rng.choice(len(walls), size=min(n, len(walls)), replace=False):
        wall = walls[int(k)]
        box = np.asarray(wall["box"])
        if wall["obstacle"] == "bounds":
            continue  # beyond a face of the problem's own bounds
        for p in corners_and_centre(box):
            assert checker.collides(p), f"wall cell {wall['leaf']} is free for FCL at {p}"


def test_a_robot_sealed_in_a_surface_box_is_walled_off_locally():
    scenario = box_room(False, [0, 0, 0], [0, 0, 7])
    outcome = planner.plan(scenario, params=LOCAL_ALWAYS)
    assert outcome.status == "no_path", outcome.message
    certificate = outcome.certificate
    assert certificate["local"]["end"] == "start" and "in a box around it" in outcome.message
    assert certificate["verified"] and certificate["exact"]
    assert certificate["wall_cells_without_primitive"] == 0
    assert certificate["wall_cells_by_obstacle"] == {"shell": certificate["wall_cells"]}
    # closed form: the cube's centre stays within 2.5 of the origin inside, and the
    # C-obstacle of the shell (a surface) is |x|_inf in [2.5, 3.5]: no component cell
    # reaches past it
    boxes = np.asarray(certificate["component"]["boxes"])
    assert np.abs(boxes).max() <= 3.5 + 1e-9
    assert_walls_collide(outcome, scenario, 300)
    # the box is local: it does not hold the goal
    box = np.asarray(certificate["local"]["box"])
    assert not np.all((box[0] <= [0, 0, 7]) & ([0, 0, 7] <= box[1]))


def test_a_room_with_an_open_top_is_not_walled_off_and_the_path_is_found():
    scenario = box_room(True, [0, 0, 0], [0, 0, 7])
    outcome = planner.plan(scenario, params=LOCAL_ALWAYS)
    assert outcome.status == "found", outcome.message
    tried = outcome.report["local_proof"]
    assert tried["proved"] is False
    assert [(a["end"], a["outcome"]) for a in tried["attempts"]] == [
        (end, "the flood fill did not close")
        for end in ("start", "goal")]
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]


def test_small_problems_are_not_tried_locally_by_default():
    outcome = planner.plan(box_room(False, [0, 0, 0], [0, 0, 7]))
    assert outcome.status == "no_path"
    assert "local_proof" not in outcome.report  # 12 x 12 triangle pairs: the global octree


@pytest.mark.assets
def test_spirelli_held_at_the_start_orientation_is_walled_off_near_the_start():
    cfg = SHARED_ASSETS / "omplapp" / "spirelli.cfg"
    scenario = planner.load_problem(cfg, hold_orientation="start")
    outcome = planner.plan(scenario)
    assert outcome.status == "no_path", outcome.message
    certificate = outcome.certificate
    assert certificate["verified"] and certificate["exact"] and certificate["local"]
    assert certificate["wall_cells_without_primitive"] == 0
    # the slab's vertices asked whether they lie in the solid world piece for a whole
    # cell (the core's inside grid): the crossing region is walled off in large cells
    # (about 8,000 walls; 62,516 when a sample of twelve vertices was asked)
    assert certificate["wall_cells"] < 20_000
    assert_walls_collide(outcome, scenario, 200)
    # no component cell holds the goal, and the start's cell is in the component
    boxes = np.asarray(certificate["component"]["boxes"])
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    assert not np.any(np.all((boxes[:, 0] <= goal) & (goal <= boxes[:, 1]), axis=1))
    assert np.any(np.all((boxes[:, 0] <= start) & (start <= boxes[:, 1]), axis=1))


@pytest.mark.assets
def test_escape_held_at_the_start_orientation_is_walled_off_by_the_rings_shells():
    # the ring (a surface: eight tube segments sharing their caps, seven inside out) is
    # linked with the pipe; the wall cells are translations where the pipe's connected
    # surface crosses a closed shell of the ring, checked again without the core
    cfg = SHARED_ASSETS / "omplapp" / "escape.cfg"
    scenario = planner.load_problem(cfg, hold_orientation="start")
    assert not scenario.robot.solid
    assert [label for label, _ in subsets(scenario.robot)][0] == "whole part"
    outcome = planner.plan(scenario)
    assert outcome.status == "no_path", outcome.message
    certificate = outcome.certificate
    assert certificate["verified"] and certificate["exact"] and certificate["local"]
    check = check_certificate(certificate, scenario)
    assert check.valid and check.component_closed, check.failures
    assert check.witnesses.get("robot_shell", 0) > 0, check.witnesses
    assert_walls_collide(outcome, scenario, 40)


def test_the_flood_stops_at_the_deadline(monkeypatch):
    # a deadline already passed: the flood fill tests a few nodes, not the room's
    # thousands, and says the time limit stopped it
    scenario = box_room(False, [0, 0, 0], [0, 0, 7])
    source = choose_for([scenario.robot, *scenario.obstacles], scenario.settings)
    checker = FclChecker.for_parts(scenario.robot, scenario.obstacles)
    tests = []
    collides = checker.collides
    monkeypatch.setattr(checker, "collides", lambda p: tests.append(p) or collides(p))
    deadline = Deadline(time.perf_counter())
    assert prove_end_enclosed(scenario, source, checker, "start", deadline=deadline) is None
    assert deadline.reached and len(tests) < 32


def test_a_local_proof_out_of_memory_is_refused_in_one_line_naming_it():
    room = box_room(False, [0, 0, 0], [0, 0, 7])
    shell = room.obstacles[0].mesh.subdivide().subdivide().subdivide()  # 768 triangles
    scenario = dataclasses.replace(room, obstacles=[dataclasses.replace(room.obstacles[0],
                                                                        mesh=shell)])
    with planner.memory_limit(0.002), pytest.raises(ResourceLimitError) as refused:
        planner.plan(scenario, params=LOCAL_ALWAYS)
    message = str(refused.value)
    assert "the local proof at the start" in message and "--memory-limit" in message
    assert "\n" not in message


def slotted_room(slot: float, start, goal) -> Scenario:
    """:func:`box_room` sealed, but with a slot ``|x| < slot / 2`` across its top (0: none),
    and a unit cube robot of 768 triangles (edges 0.125: its x slab's triangles span
    |x| <= 0.25)."""
    room = box_room(slot > 0, start, goal)
    shell = room.obstacles[0].mesh
    if slot > 0:
        plates = [trimesh.creation.box(extents=[3 - slot / 2, 6, 1e-9]) for _ in range(2)]
        for sign, plate in zip((-1, 1), plates):
            plate.apply_translation([sign * (3 + slot / 2) / 2, 0, 3])
            top = plate.face_normals[:, 2] > 0.5
            shell = trimesh.util.concatenate(
                [shell, trimesh.Trimesh(plate.vertices, plate.faces[top], process=False)])
    cube = trimesh.creation.box(extents=[1, 1, 1])
    for _ in range(3):
        cube = cube.subdivide()
    return dataclasses.replace(
        room, robot=dataclasses.replace(room.robot, mesh=cube),
        obstacles=[dataclasses.replace(room.obstacles[0], mesh=shell)])


@pytest.fixture
def slabs_for_small_robots(monkeypatch):
    """Slabs tried for robots of 500 triangles or more (the default is for larger)."""
    from planner.planning import slabs  # noqa: PLC0415

    monkeypatch.setattr(slabs, "SLAB_MIN_TRIANGLES", 500)


@pytest.mark.usefixtures("slabs_for_small_robots")
def test_a_slab_of_the_robot_walls_it_off_and_one_that_slips_out_is_not_taken():
    sealed = slotted_room(0.0, [0, 0, 0], [0, 0, 7])
    outcome = planner.plan(sealed, params=LOCAL_ALWAYS)
    assert outcome.status == "no_path", outcome.message
    robot = outcome.certificate["local"]["robot"]
    assert robot["subset"] == "x slab" and robot["triangles"] < 768
    assert_walls_collide(outcome, sealed, 200)  # FCL, on the whole robot
    # a 0.75 slot across x: the x slab (0.5 wide in x) slips through it, no proof;
    # the y slab (1 wide in x, as the cube) does not, and walls the cube off
    slotted = slotted_room(0.75, [0, 0, 0], [0, 0, 7])
    slotted = dataclasses.replace(slotted, settings=dataclasses.replace(slotted.settings,
                                                                        time_limit=300))
    outcome = planner.plan(slotted, params=LOCAL_ALWAYS)
    assert outcome.status == "no_path", outcome.message
    assert outcome.certificate["local"]["robot"]["subset"] == "y slab"
    assert_walls_collide(outcome, slotted, 200)
    # the slot is real: the x slab alone gets out through it (FCL)
    x_slab = next(robot for label, robot in subsets(slotted.robot) if label == "x slab")
    checker = FclChecker.for_parts(x_slab, slotted.obstacles)
    assert checker.check_path(np.array([[0.0, 0, 0], [0, 0, 7]])).valid
    assert not FclChecker.for_parts(slotted.robot, slotted.obstacles).check_path(
        np.array([[0.0, 0, 0], [0, 0, 7]])).valid


@pytest.mark.usefixtures("slabs_for_small_robots")
def test_a_slab_collides_only_where_the_whole_part_does():
    scenario = slotted_room(0.75, [0, 0, 0], [0, 0, 7])
    whole = FclChecker.for_parts(scenario.robot, scenario.obstacles)
    rng = np.random.default_rng(1)
    points = rng.uniform(-3.6, 3.6, size=(3000, 3))
    whole_hits = np.array([whole.collides(p) for p in points])
    labels = []
    for label, slab in subsets(scenario.robot):
        labels.append(label)
        if label == "whole part":
            continue
        assert not slab.solid and len(slab.mesh.faces) < len(scenario.robot.mesh.faces)
        checker = FclChecker.for_parts(slab, scenario.obstacles)
        hits = np.array([checker.collides(p) for p in points])
        assert hits.any() and not np.any(hits & ~whole_hits), label
        assert np.any(whole_hits & ~hits), label  # strictly less: the slab is thinner
    assert labels == ["x slab", "y slab", "z slab", "whole part"]


@pytest.mark.usefixtures("slabs_for_small_robots")
def test_a_time_limit_spent_on_local_proofs_is_the_answer_not_a_larger_cspace():
    # proved in about 0.7 s with no limit; a quarter of a second ends in the local proofs
    slotted = slotted_room(0.75, [0, 0, 0], [0, 0, 7])
    slotted = dataclasses.replace(slotted, settings=dataclasses.replace(slotted.settings,
                                                                        time_limit=0.25))
    outcome = planner.plan(slotted, params=LOCAL_ALWAYS)
    assert outcome.status == "not_found" and outcome.reason == "time_limit", outcome.message
    assert "local proofs" in outcome.message and outcome.cspace is None
    assert outcome.timings["total"] < 60  # not a search over the whole bounds
    attempts = outcome.report["local_proof"]["attempts"]
    assert "time limit" in attempts[-1]["outcome"], attempts


class _GrowingCSpace:
    """A stand-in C-space isolating :func:`wall_off`'s round loop: never walled off, each
    round's component ten times the last, refining costs ``per_leaf`` seconds a leaf."""

    n_obstacle_prims = 0

    def __init__(self, per_leaf: float) -> None:
        self.per_leaf, self.members, self.refined = per_leaf, 10, []

    def enclosure(self, point):
        return {"wall_prims": [], "verified": False,
                "component_leaves": list(range(self.members))}

    def leaves(self):
        return {}

    def refine(self, chosen, ring, levels):
        time.sleep(self.per_leaf * len(chosen))
        self.refined.append(len(chosen))
        self.members *= 10
        return {"refined": len(chosen)}


def test_a_wall_off_round_projected_past_the_deadline_is_not_started():
    cs = _GrowingCSpace(per_leaf=0.02)  # 0.2 s for the first round, 2 s for the next
    t0 = time.perf_counter()
    deadline = Deadline(t0 + 1.0)
    raw, rounds = wall_off(cs, np.zeros(3), bounds_faces=[False] * 6, deadline=deadline,
                           select=lambda cs, leaves, members: list(members))
    assert raw is None and rounds == 1 and cs.refined == [10]
    assert time.perf_counter() - t0 < 1.0  # stopped before the deadline, not after it
    assert deadline.reached  # the planner answers time_limit, not a C-space over the bounds


def test_the_pace_of_one_local_cspace_keeps_the_next_from_passing_the_deadline():
    # the start's proof measures the seconds per robot triangle of its C-space; the goal's
    # proof (the same deadline) does not start one that this pace says would end too late
    sealed = box_room(False, [0, 0, 0], [0, 0, 7])
    source = choose_for([sealed.robot, *sealed.obstacles], sealed.settings)
    checker = FclChecker.for_parts(sealed.robot, sealed.obstacles)
    measured = Deadline(time.perf_counter() + 60.0)
    proof = prove_end_enclosed(sealed, source, checker, "start", deadline=measured)
    assert proof is not None and measured.cspace_pace > 0 and not measured.reached
    slow = Deadline(time.perf_counter() + 60.0, cspace_pace=60.0)  # a minute a triangle
    t0 = time.perf_counter()
    assert prove_end_enclosed(sealed, source, checker, "start", deadline=slow) is None
    assert slow.reached and time.perf_counter() - t0 < 10.0
