"""Every wall cell of a no-path certificate carries witnesses that a check trusting
nothing of minkplan's core confirms (planner.validation.certificate_check, minkplan
verify): scipy's convex hulls (a triangle pair's piece), trimesh's containment and FCL's
box-against-triangles test (a vertex inside a solid), the bounds; the witnesses' parts
cover each wall cell's box, and the component's faces are covered by its walls. A
certificate with a wall or a witness taken away or moved fails."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import trimesh
from test_exact_planning import write_scenario
from test_local_proof import LOCAL_ALWAYS, box_room

import planner
from planner.cli import main
from planner.io import load_scenario
from planner.problem import Body, PlannerSettings, Robot, Scenario
from planner.validation.certificate_check import (
    box_in_solid,
    check_certificate,
    closed_mod_2,
    odd_parity,
    piece_holds,
)


def check_witnesses(outcome, scenario) -> dict[str, int]:
    """The certificate checked without the core; its witnesses' parts by kind."""
    check = check_certificate(outcome.certificate, scenario)
    assert check.valid and check.point_in_component and check.component_closed, \
        check.failures
    assert check.walls == outcome.certificate["wall_cells"] and check.unchecked == 0
    return check.witnesses


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


def test_a_tampered_certificate_fails_and_the_command_says_so(tmp_path, capsys):
    hollow_box(4, 2).export(tmp_path / "cage.stl")
    (tmp_path / "s.yaml").write_text(
        "name: cage\nrobot: {name: cage, mesh: cage.stl}\n"
        "obstacles:\n  - {name: post, box: [1, 1, 1]}\n"
        "start: [0, 0, 0]\ngoal: [0, 0, 9]\n"
        "bounds: {min: [-12, -12, -12], max: [12, 12, 12]}\n")
    scenario = load_scenario(tmp_path / "s.yaml")
    outcome = planner.plan(scenario, progress=False)
    assert outcome.status == "no_path", outcome.message
    good = outcome.certificate
    assert check_certificate(good, scenario).valid
    # a wall cell taken away: the component is no longer closed
    holed = copy.deepcopy(good)
    del holed["walls"][len(holed["walls"]) // 2]
    check = check_certificate(holed, scenario)
    assert not check.valid and not check.component_closed
    # a witness moved: a triangle of the robot, or a vertex, shifted far away
    for kind, key in (("triangles", "robot_triangle"), ("obstacle_vertex", "vertex")):
        moved = copy.deepcopy(good)
        wall = next(w for w in moved["walls"] if w["witnesses"][0]["kind"] == kind)
        wall["witnesses"][0][key] = (np.asarray(wall["witnesses"][0][key]) + 100.0).tolist()
        check = check_certificate(moved, scenario)
        assert not check.valid and check.component_closed and check.n_failures == 1
        assert f"{kind} witness does not hold" in check.failures[0]
    # geometry that is not the scenario's: an obstacle renamed, a triangle invented
    renamed = copy.deepcopy(good)
    for wall in renamed["walls"]:
        for witness in wall["witnesses"]:
            witness["obstacle"] = "nonexistent"
    assert not check_certificate(renamed, scenario).valid
    invented = copy.deepcopy(good)
    wall = next(w for w in invented["walls"] if w["witnesses"][0]["kind"] == "triangles")
    witness = wall["witnesses"][0]
    witness["robot_triangle"] = (np.asarray(witness["robot_triangle"]) * (1 + 1e-6)).tolist()
    assert not check_certificate(invented, scenario).valid
    # the walled point is not the scenario's start; a part listed twice; a wall twice
    moved_point = copy.deepcopy(good)
    moved_point["walled_point"] = [0.1, 0.0, 0.0]
    assert not check_certificate(moved_point, scenario).valid
    doubled = copy.deepcopy(good)
    doubled["walls"][0]["witnesses"] = doubled["walls"][0]["witnesses"] * 2
    assert not check_certificate(doubled, scenario).valid
    twice = copy.deepcopy(good)
    twice["walls"].append(copy.deepcopy(twice["walls"][0]))
    assert not check_certificate(twice, scenario).valid
    # the command line: exit 0 for the certificate as written, 1 for the tampered one
    out = tmp_path / "out"
    assert main(["plan", str(tmp_path / "s.yaml"), "--out", str(out), "--no-progress"]) == 1
    capsys.readouterr()
    assert main(["verify", str(tmp_path / "s.yaml"), str(out)]) == 0
    assert "holds: the start lies in a closed component" in capsys.readouterr().out
    (tmp_path / "bad.json").write_text(json.dumps(holed))
    assert main(["verify", str(tmp_path / "s.yaml"), str(tmp_path / "bad.json")]) == 1
    assert "does not hold" in capsys.readouterr().out
    assert main(["verify", str(tmp_path / "s.yaml"), str(tmp_path / "none.json")]) == 2
    broken = copy.deepcopy(good)
    del broken["walls"][0]["box"]
    (tmp_path / "broken.json").write_text(json.dumps(broken))
    assert main(["verify", str(tmp_path / "s.yaml"), str(tmp_path / "broken.json")]) == 2
    assert "not a minkplan certificate" in capsys.readouterr().err


def test_verify_takes_the_orientation_the_certificate_is_for_and_says_what_it_was_given(
        tmp_path, capsys):
    """A try-out: verify of a problem planned with --hold-orientation asked to plan with it;
    an assembly file said "base: unknown key"; a folder of a found path said
    "certificate.json not found". The certificate records its orientation: verify takes
    the end of the problem that has it; the others say what they were given."""
    hollow_box(4, 2).export(tmp_path / "cage.stl")
    (tmp_path / "s.yaml").write_text(
        "name: cage\nrobot: {name: cage, mesh: cage.stl}\n"
        "obstacles:\n  - {name: post, box: [1, 1, 1]}\n"
        "start: {position: [0, 0, 0], orientation: {rpy: [0, 0, 30]}}\n"
        "goal: [0, 0, 9]\n"
        "bounds: {min: [-12, -12, -12], max: [12, 12, 12]}\n")
    out = tmp_path / "out"
    assert main(["plan", str(tmp_path / "s.yaml"), "--out", str(out), "--no-progress",
                 "--hold-orientation", "start"]) == 1
    capsys.readouterr()
    assert main(["verify", str(tmp_path / "s.yaml"), str(out)]) == 0
    assert "holds" in capsys.readouterr().out
    assemblies = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies"
    assembly = assemblies / "peg_in_block.yaml"
    assert main(["verify", str(assembly), str(out)]) == 2
    assert "an assembly, not a planning problem" in capsys.readouterr().err
    (tmp_path / "free.yaml").write_text(
        "name: free\nrobot: {name: cube, box: [1, 1, 1]}\nobstacles: []\n"
        "start: [0, 0, 0]\ngoal: [3, 0, 0]\nbounds: {min: [-5, -5, -5], max: [5, 5, 5]}\n")
    found = tmp_path / "found"
    assert main(["plan", str(tmp_path / "free.yaml"), "--out", str(found),
                 "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["verify", str(tmp_path / "free.yaml"), str(found)]) == 2
    said = capsys.readouterr().err
    assert "holds no certificate.json: its plan's status is 'found'" in said


def test_a_decomposition_certificate_is_said_to_rest_on_primitives(tmp_path, capsys):
    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "sealed_chamber.yaml"
    out = tmp_path / "out"
    assert main(["plan", str(scenario), "--out", str(out), "--no-progress"]) == 1
    capsys.readouterr()
    assert main(["verify", str(scenario), str(out)]) == 1
    said = capsys.readouterr().out
    assert "not checked" in said and "convex primitives of the decomposition" in said
    assert "holds" not in said


def frame_and_tube(centre=(0.0, 0.0, 0.0)) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A square frame of four bars (closed boxes, subdivided) about ``centre``, and a
    long open tube (no caps) along z through its hole."""
    placed = [([1, 6, 1], [2.5, 0, 0]), ([1, 6, 1], [-2.5, 0, 0]),
              ([4, 1, 1], [0, 2.5, 0]), ([4, 1, 1], [0, -2.5, 0])]
    move = trimesh.transformations.translation_matrix
    bars = [trimesh.creation.box(extents=e, transform=move(np.add(c, centre))) for e, c in placed]
    frame = trimesh.util.concatenate([b.subdivide().subdivide() for b in bars])
    tube = trimesh.creation.box(extents=[0.6, 0.6, 30])
    tube = trimesh.Trimesh(tube.vertices + centre,
                           tube.faces[np.abs(tube.face_normals[:, 2]) < 0.5], process=False)
    return frame, tube


def frame_on_a_rod() -> Scenario:
    """The frame (the robot, a surface) around the tube (a surface) that it cannot leave
    by translation."""
    frame, tube = frame_and_tube()
    return Scenario(name="frame", units="m",
                    robot=Robot("frame", frame, "test", solid=False, kind_reason="test"),
                    obstacles=[Body("tube", tube, "test", solid=False, kind_reason="test")],
                    start=[0, 0, 0], goal=[9, 0, 0], orientation=np.eye(3),
                    bounds=(np.full(3, -12.0), np.full(3, 12.0)),
                    settings=PlannerSettings(time_limit=60))


def test_witnesses_of_a_tube_in_a_frame_off_the_origins_include_the_frames_shells():
    # the roles swapped (the tube moves, the frame's bars are the obstacle's shells), and
    # neither part about its own origin, so that a sign or a reflection wrong would show
    frame, tube = frame_and_tube((2.0, 3.0, 0.0))
    tube.apply_translation([-1.3, 0.7, -0.4])  # the robot's frame off its middle
    scenario = Scenario(name="tube", units="m",
                        robot=Robot("tube", tube, "test", solid=False, kind_reason="test"),
                        obstacles=[Body("frame", frame, "test", solid=False, kind_reason="test")],
                        start=[1.3, -0.7, 0.4], goal=[10.3, -0.7, 0.4], orientation=np.eye(3),
                        bounds=(np.full(3, -12.0), np.full(3, 14.0)),
                        settings=PlannerSettings(time_limit=60))
    outcome = planner.plan(scenario, progress=False)
    assert outcome.status == "no_path", outcome.message
    assert check_witnesses(outcome, scenario).get("obstacle_shell", 0) > 0
    assert {shell["of"] for shell in outcome.certificate["shells"]} == {"obstacle"}


def test_witnesses_of_a_frame_on_a_tube_include_its_closed_shells(tmp_path, capsys):
    # the tube crosses a bar's closed shell: its connected surface holds a point inside
    # the bar and reaches far outside it, for every translation of a wall cell
    scenario = frame_on_a_rod()
    outcome = planner.plan(scenario, progress=False)
    assert outcome.status == "no_path", outcome.message
    kinds = check_witnesses(outcome, scenario)
    assert kinds.get("robot_shell", 0) > 0, kinds
    certificate = outcome.certificate
    assert all(shell["of"] == "robot" and len(shell["faces"]) >= 12
               for shell in certificate["shells"])
    index = next(i for i, w in enumerate(certificate["walls"])
                 if any(p["kind"] == "robot_shell" for p in w["witnesses"]))

    def tampered(change) -> bool:
        broken = copy.deepcopy(certificate)
        part = next(p for p in broken["walls"][index]["witnesses"] if p["kind"] == "robot_shell")
        change(broken, part)
        return check_certificate(broken, scenario).valid

    shell_of = lambda b, p: b["shells"][p["shell"]]  # noqa: E731
    assert not tampered(lambda b, p: shell_of(b, p)["faces"].pop()), "a shell left open"
    assert not tampered(lambda b, p: p.update(point=(np.asarray(p["point"]) + [0, 0, 0.3]
                                                     ).tolist())), "the point off its triangle"
    assert not tampered(lambda b, p: p.update(far_vertex=p["point"])), \
        "the far vertex inside the shell's box, and no vertex"
    assert not tampered(lambda b, p: p.update(kind="obstacle_shell")), "the robot's shell " \
        "named as the obstacle's"


def test_shell_witnesses_of_a_part_a_millimetre_across_hold():
    # the frame on its rod scaled to a tenth of a millimetre a bar, in metres: the check
    # must not depend on scale (trimesh's closest point and FCL's box test did, and
    # failed valid certificates of parts this size)
    scenario = frame_on_a_rod()
    k = 1e-4
    robot = scenario.robot.mesh.copy()
    robot.apply_scale(k)
    tube = scenario.obstacles[0].mesh.copy()
    tube.apply_scale(k)
    small = Scenario(name="frame-mm", units="m",
                     robot=Robot("frame", robot, "test", solid=False, kind_reason="test"),
                     obstacles=[Body("tube", tube, "test", solid=False, kind_reason="test")],
                     start=[0, 0, 0], goal=[9 * k, 0, 0], orientation=np.eye(3),
                     bounds=(np.full(3, -12.0 * k), np.full(3, 12.0 * k)),
                     settings=PlannerSettings(time_limit=60))
    outcome = planner.plan(small, progress=False)
    assert outcome.status == "no_path", outcome.message
    assert check_witnesses(outcome, small).get("robot_shell", 0) > 0


def test_parity_ignores_zero_area_triangles_as_the_core_does():
    # a flat triangle (three points on a line) kept in a shell crosses no ray's parity
    cube = np.asarray(trimesh.creation.box(extents=[2, 2, 2]).triangles)
    flat = np.array([[[-1.0, -1, -1], [0, -1, -1], [1, -1, -1]]])
    shell = np.concatenate([cube, flat])
    assert odd_parity(shell, np.zeros(3), 1e-9) is True
    assert odd_parity(shell, np.array([3.0, 0, 0]), 1e-9) is False
    assert closed_mod_2(shell.reshape(-1, 3), np.arange(len(shell) * 3).reshape(-1, 3)) is False
    assert closed_mod_2(cube.reshape(-1, 3), np.arange(len(cube) * 3).reshape(-1, 3)) is True


def test_malformed_shell_witnesses_are_refused_naming_the_field():
    scenario = frame_on_a_rod()
    outcome = planner.plan(scenario, progress=False)
    certificate = outcome.certificate
    index = next(i for i, w in enumerate(certificate["walls"])
                 if any(p["kind"] == "robot_shell" for p in w["witnesses"]))

    def refused(change) -> str:
        broken = copy.deepcopy(certificate)
        change(broken, next(p for p in broken["walls"][index]["witnesses"]
                            if p["kind"] == "robot_shell"))
        try:
            check_certificate(broken, scenario)
        except ValueError as exc:
            return str(exc)
        raise AssertionError("accepted")

    assert refused(lambda b, p: p.update(shell="0")).startswith(f"walls[{index}]: shell = '0'")
    assert "face = -1" in refused(lambda b, p: b["shells"][0]["faces"].__setitem__(0, -1))
    assert "face = 7.5" in refused(lambda b, p: b["shells"][0]["faces"].__setitem__(0, 7.5))
    assert refused(lambda b, p: b["walls"][index].update(leaf="x")).startswith(
        f"walls[{index}]: leaf = 'x'")
    assert "missing 'point'" in refused(lambda b, p: p.pop("point"))
    assert "kind = 'nested'" in refused(lambda b, p: p.update(kind="nested"))
    assert "schema = 'minkplan/certificate/9'" in refused(
        lambda b, p: b.update(schema="minkplan/certificate/9"))


def test_a_certificate_checked_at_another_orientation_says_so():
    scenario = frame_on_a_rod()
    certificate = planner.plan(scenario, progress=False).certificate
    assert np.allclose(certificate["robot_orientation"], np.eye(3))
    turned = copy.deepcopy(certificate)
    turned["robot_orientation"] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    check = check_certificate(turned, scenario)
    assert not check.valid and "another orientation" in check.failures[0]
