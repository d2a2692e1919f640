"""Scenario YAML: parsing, conventions, defaults and every kind of error."""

from __future__ import annotations

import math
import re
import textwrap
from pathlib import Path

import numpy as np
import pytest
import trimesh

from planner.errors import InvalidParameterError, ScenarioError
from planner.io import load_scenario, parse_scenario
from planner.io.fields import parse_orientation, settings_from_mapping
from planner.primitives import make_primitive
from planner.problem import PlannerSettings as Settings
from planner.problem import Pose, default_bounds

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = REPO / "scenarios" / "_schema_examples"


def rx(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


@pytest.fixture
def folder(tmp_path):
    """A folder with peg.stl (10 x 10 x 40 box), block.stl (100 x 100 x 20 box), an open
    mesh and a file that is not a mesh."""
    trimesh.creation.box(extents=[10, 10, 40]).export(tmp_path / "peg.stl")
    trimesh.creation.box(extents=[100, 100, 20]).export(tmp_path / "block.stl")
    box = trimesh.creation.box(extents=[1, 1, 1])
    trimesh.Trimesh(box.vertices, box.faces[:-2], process=False).export(tmp_path / "open.stl")
    (tmp_path / "broken.stl").write_text("this is not a mesh\n")
    return tmp_path


def write(folder: Path, text: str, name: str = "scenario.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    return path


MINIMAL = """
robot: {mesh: peg.stl}
obstacles:
  - {mesh: block.stl, position: [0, 0, 0]}
start: [0, 0, 60]
goal: [0, 0, 0]
"""


# ----------------------------------------------------------------------------- parsing


def test_minimal_form_parses_with_defaults(folder):
    scenario = load_scenario(write(folder, MINIMAL))
    assert scenario.name == "scenario"
    assert scenario.units == "unitless"
    assert scenario.robot.name == "peg"
    assert [b.name for b in scenario.obstacles] == ["block"]
    np.testing.assert_array_equal(scenario.start, [0, 0, 60])
    np.testing.assert_array_equal(scenario.goal, [0, 0, 0])
    np.testing.assert_array_equal(scenario.orientation, np.eye(3))
    np.testing.assert_allclose(scenario.robot.mesh.bounds, [[-5, -5, -20], [5, 5, 20]])
    np.testing.assert_allclose(scenario.obstacles[0].mesh.bounds, [[-50, -50, -10], [50, 50, 10]])
    assert scenario.settings == Settings()
    assert scenario.settings.seed == 0 and scenario.settings.time_limit == 30.0
    assert scenario.path == (folder / "scenario.yaml").resolve()
    assert scenario.notes == ()
    for mesh in (scenario.robot.mesh, scenario.obstacles[0].mesh):
        assert mesh.is_watertight and mesh.volume > 0


def test_minimal_example_file_parses_exactly_as_written():
    scenario = load_scenario(EXAMPLES / "minimal.yaml")
    assert scenario.name == "minimal"
    assert (EXAMPLES / "minimal.yaml").read_text().strip() == MINIMAL.strip()


def test_full_example_parses_into_the_values_written():
    scenario = load_scenario(EXAMPLES / "full.yaml")
    assert scenario.name == "peg-over-plate"
    assert scenario.units == "mm"
    assert scenario.robot.name == "peg"
    # peg.stl is 10 x 10 x 40; scale [1, 1, 1.5]; identity orientation
    np.testing.assert_allclose(scenario.robot.mesh.bounds, [[-5, -5, -30], [5, 5, 30]])
    assert [b.name for b in scenario.obstacles] == ["plate", "post", "ball", "wall"]
    plate, post, ball, wall = (b.mesh for b in scenario.obstacles)
    half = 50 * math.sqrt(2)  # 100 x 100 plate turned 45 degrees about z
    np.testing.assert_allclose(plate.bounds, [[-half, -half, -20], [half, half, 0]], atol=1e-9)
    np.testing.assert_allclose(post.bounds, [[35, -5, 0], [45, 5, 30]], atol=1e-9)
    assert len(post.faces) == 4 * 24  # 24 sections: sides (2 each) and both caps
    np.testing.assert_allclose(ball.bounds, [[-48, -8, 2], [-32, 8, 18]], atol=1e-9)
    assert len(ball.vertices) == 162  # icosphere with 2 subdivisions
    np.testing.assert_allclose(wall.bounds, [[-30, 44, 0], [30, 46, 40]], atol=1e-9)
    np.testing.assert_array_equal(scenario.start, [0, 0, 60])
    np.testing.assert_array_equal(scenario.goal, [0, 0, 40])
    np.testing.assert_allclose(scenario.orientation, np.eye(3), atol=1e-15)
    np.testing.assert_array_equal(scenario.bounds[0], [-100, -100, -50])
    np.testing.assert_array_equal(scenario.bounds[1], [100, 100, 120])
    assert scenario.settings == Settings(resolution=0.5, time_limit=10, seed=42,
                                         contact_tolerance=0.001,
                                         decomposition_threshold=0.1, exact="auto",
                                         clearance=0.5, simplify=True)
    assert isinstance(scenario.settings.seed, int)
    for body in scenario.obstacles:
        assert body.mesh.is_watertight and body.mesh.volume > 0
    summary = scenario.describe()
    assert summary["units"] == "mm" and summary["settings"]["seed"] == 42


def test_docs_show_the_full_example_verbatim():
    docs = (REPO / "docs" / "scenario.md").read_text()
    blocks = re.findall(r"```yaml\n(.*?)```", docs, flags=re.S)
    assert (EXAMPLES / "full.yaml").read_text() in blocks
    assert MINIMAL.lstrip("\n") in blocks


def test_full_form_with_every_option_in_one_file(folder):
    path = write(folder, """
        name: everything
        units: m
        robot:
          name: mover
          box: [1, 2, 3]
        obstacles:
          - {mesh: block.stl, name: b, scale: 0.5, position: [1, 2, 3]}
          - {mesh: block.stl}
          - {mesh: block.stl, position: [0, 0, 100]}
          - {sphere: 2, position: [50, 50, 50]}
          - {cylinder: {radius: 1, height: 4}, orientation: {rpy: [90, 0, 0]}}
        start: {position: [0, 0, 60], orientation: {axis: [0, 0, 1], angle_deg: 90}}
        goal: {position: [0, 0, 30], orientation: [0.7071067811865476, 0, 0, 0.7071067811865476]}
        planner:
          resolution: null
          time_limit: 1e3
          seed: 7
          contact_tolerance: 0
          decomposition_threshold: 1
          exact: false
          clearance: 0.25
          simplify: no
        """)
    scenario = load_scenario(path)
    assert scenario.name == "everything" and scenario.units == "m"
    assert scenario.robot.name == "mover"
    assert scenario.robot.source == "box [1, 2, 3]"
    assert [b.name for b in scenario.obstacles] == ["b", "block", "block_2", "sphere",
                                                    "cylinder"]
    # the robot box [1, 2, 3] turned 90 degrees about z: extents [2, 1, 3], not translated
    np.testing.assert_allclose(scenario.robot.mesh.bounds, [[-1, -0.5, -1.5], [1, 0.5, 1.5]],
                               atol=1e-12)
    np.testing.assert_allclose(scenario.orientation, rz(90), atol=1e-12)
    np.testing.assert_allclose(scenario.obstacles[0].mesh.bounds,
                               [[-24, -23, -2], [26, 27, 8]])
    # cylinder axis z turned by roll 90 degrees: axis along -y
    np.testing.assert_allclose(scenario.obstacles[4].mesh.extents, [2, 4, 2], atol=1e-12)
    assert scenario.settings == Settings(resolution=None, time_limit=1000.0, seed=7,
                                         contact_tolerance=0.0, decomposition_threshold=1.0,
                                         exact=False, clearance=0.25, simplify=False)
    # default bounds hold the far obstacles
    lo, hi = scenario.bounds
    assert np.all(lo <= [-50, -50, -10]) and np.all(hi >= [52, 52, 110])


def test_parse_scenario_from_text_and_from_mapping(folder):
    from_text = parse_scenario(MINIMAL, folder)
    data = {"robot": {"mesh": "peg.stl"}, "obstacles": [{"mesh": "block.stl"}],
            "start": [0, 0, 60], "goal": [0, 0, 0]}
    from_dict = parse_scenario(data, base_dir=folder)
    for scenario in (from_text, from_dict):
        assert scenario.path is None
        np.testing.assert_array_equal(scenario.start, [0, 0, 60])
        np.testing.assert_allclose(scenario.bounds[0], from_text.bounds[0])
    with pytest.raises(ScenarioError, match=r"^<scenario>: goal: missing required field$"):
        parse_scenario({"robot": {"box": [1, 1, 1]}, "start": [0, 0, 0]})


def test_relative_mesh_paths_resolve_against_the_yaml_folder(tmp_path, monkeypatch):
    meshes = tmp_path / "meshes"
    meshes.mkdir()
    trimesh.creation.box(extents=[1, 2, 3]).export(meshes / "part.stl")
    trimesh.creation.box(extents=[4, 4, 4]).export(meshes / "base.stl")
    scenarios = tmp_path / "scenarios" / "deep"
    scenarios.mkdir(parents=True)
    path = write(scenarios, """
        robot: {mesh: ../../meshes/part.stl}
        obstacles: [{mesh: ../../meshes/base.stl}, {mesh: %s}]
        start: [0, 0, 10]
        goal: [5, 0, 10]
        """ % (meshes / "base.stl"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    trimesh.creation.box(extents=[9, 9, 9]).export(elsewhere / "part.stl")  # a decoy
    monkeypatch.chdir(elsewhere)
    scenario = load_scenario(Path("..") / "scenarios" / "deep" / "scenario.yaml")
    np.testing.assert_allclose(scenario.robot.mesh.extents, [1, 2, 3])
    assert scenario.robot.source == str((meshes / "part.stl").resolve())
    assert [b.name for b in scenario.obstacles] == ["base", "base_1"]
    with pytest.raises(ScenarioError) as info:
        parse_scenario(path.read_text(), base_dir=tmp_path)  # wrong folder: not found
    assert info.value.field == "robot.mesh"


def test_loaded_mesh_is_shared_but_copied(folder):
    scenario = parse_scenario("""
robot: {box: [1, 1, 1]}
obstacles: [{mesh: block.stl}, {mesh: block.stl, position: [0, 0, 50]}]
start: [0, 0, 20]
goal: [0, 0, 30]
""", folder)
    first, second = (b.mesh for b in scenario.obstacles)
    assert first is not second
    np.testing.assert_allclose(second.bounds[0], first.bounds[0] + [0, 0, 50])


def test_repair_opt_in(folder):
    text = """robot: {box: [1, 1, 1]}
obstacles:
  - {mesh: open.stl%s}
start: [0, 0, 5]
goal: [0, 0, 6]
"""
    # kind: auto (the default): an open mesh is a surface, and the report says why
    surface = parse_scenario(text % "", folder).obstacles[0]
    assert not surface.solid and "not watertight" in surface.kind_reason
    assert surface.describe()["kind"] == "surface"
    with pytest.raises(ScenarioError) as info:
        parse_scenario(text % ", kind: solid", folder, filename="s.yaml")
    assert str(info.value).startswith("s.yaml:3: obstacles[0].mesh: ")
    assert "not watertight" in str(info.value) and "repair: true" in str(info.value)
    scenario = parse_scenario(text % ", repair: true", folder)
    mesh = scenario.obstacles[0].mesh
    assert mesh.is_watertight and math.isclose(mesh.volume, 1.0)
    assert scenario.obstacles[0].solid and scenario.obstacles[0].repairs["filled_holes"] == 1


def test_scientific_notation_is_a_number(folder):
    scenario = parse_scenario("""
robot: {sphere: 1e-1}
start: [1.5e2, -2E1, 3e0]
goal: [0, 0, 0]
planner: {time_limit: 2e1}
""", folder)
    np.testing.assert_array_equal(scenario.start, [150, -20, 3])
    assert scenario.settings.time_limit == 20
    np.testing.assert_allclose(scenario.robot.mesh.extents, [0.2, 0.2, 0.2])


# ------------------------------------------------------------------------ orientations


def test_quaternion_is_scalar_first():
    half = math.sqrt(0.5)
    rotation = parse_orientation([half, 0, 0, half])  # 90 degrees about z
    np.testing.assert_allclose(rotation @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(parse_orientation({"quaternion": [half, 0, 0, half]}), rotation)
    np.testing.assert_allclose(parse_orientation([1, 0, 0, 0]), np.eye(3))
    # scalar-last reading of the same numbers would be a 180-degree turn about x + z
    assert not np.allclose(parse_orientation([0, half, 0, half]), rotation)


def test_rpy_is_degrees_about_fixed_xyz():
    np.testing.assert_allclose(parse_orientation({"rpy": [90, 0, 0]}) @ [0, 1, 0],
                               [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(parse_orientation({"rpy": [10, 20, 30]}),
                               rz(30) @ ry(20) @ rx(10), atol=1e-12)


def test_axis_angle_is_right_handed_degrees():
    rotation = parse_orientation({"axis": [0, 0, 2], "angle_deg": 90})
    np.testing.assert_allclose(rotation, rz(90), atol=1e-12)
    np.testing.assert_allclose(parse_orientation({"axis": [1, 0, 0], "angle_deg": -30}),
                               rx(-30), atol=1e-12)


def test_three_forms_agree():
    rotation = rz(30) @ ry(-40) @ rx(75)
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    quaternion = trimesh.transformations.quaternion_from_matrix(matrix)  # [w, x, y, z]
    angle, axis, _ = trimesh.transformations.rotation_from_matrix(matrix)
    for spec in ([float(v) for v in quaternion], {"rpy": [75, -40, 30]},
                 {"axis": axis.tolist(), "angle_deg": math.degrees(angle)}):
        np.testing.assert_allclose(parse_orientation(spec), rotation, atol=1e-12)


def test_start_orientation_applies_to_robot_and_goal_may_omit_it(folder):
    scenario = parse_scenario("""
robot: {box: [1, 2, 3]}
start: {position: [0, 0, 0], orientation: {rpy: [90, 0, 0]}}
goal: [1, 1, 1]
""", folder)
    np.testing.assert_allclose(scenario.orientation, rx(90), atol=1e-12)
    np.testing.assert_allclose(scenario.robot.mesh.extents, [1, 3, 2], atol=1e-12)
    np.testing.assert_allclose(scenario.goal_pose.rotation, rx(90), atol=1e-12)
    placed = scenario.robot_at(scenario.goal)
    np.testing.assert_allclose(placed.bounds.mean(axis=0), [1, 1, 1], atol=1e-12)


def test_goal_only_orientation_is_used(folder):
    scenario = parse_scenario("""
robot: {box: [1, 2, 3]}
start: [0, 0, 0]
goal: {position: [1, 1, 1], orientation: {axis: [0, 0, 1], angle_deg: 90}}
""", folder)
    np.testing.assert_allclose(scenario.orientation, rz(90), atol=1e-12)


def test_equivalent_start_and_goal_orientations_are_accepted(folder):
    half = math.sqrt(0.5)
    scenario = parse_scenario(f"""
robot: {{box: [1, 2, 3]}}
start: {{position: [0, 0, 0], orientation: {{rpy: [0, 0, 90]}}}}
goal: {{position: [1, 1, 1], orientation: [{-half}, 0, 0, {-half}]}}
""", folder)  # -q is the same rotation as q
    np.testing.assert_allclose(scenario.orientation, rz(90), atol=1e-12)


def test_pose_matrix():
    pose = Pose([1, 2, 3], rz(90))
    expected = np.eye(4)
    expected[:3, :3] = rz(90)
    expected[:3, 3] = [1, 2, 3]
    np.testing.assert_allclose(pose.matrix, expected)
    assert not pose.position.flags.writeable
    with pytest.raises(InvalidParameterError):
        Pose([1, 2], np.eye(3))


# ----------------------------------------------------------------------------- bounds


def test_default_bounds_contain_everything(folder):
    scenario = parse_scenario("""
robot: {box: [2, 4, 6]}
obstacles:
  - {box: [10, 10, 10], position: [100, 0, 0]}
  - {sphere: 3, position: [-20, 30, -40]}
start: [0, 0, 50]
goal: [-60, 10, 0]
""", folder)
    lo, hi = scenario.bounds
    robot = scenario.robot.mesh.bounds
    boxes = [scenario.start[None], scenario.goal[None], robot + scenario.start,
             robot + scenario.goal]
    for body in scenario.obstacles:
        o = body.mesh.bounds
        boxes += [o, np.array([o[0] - robot[1], o[1] - robot[0]])]  # C-obstacle box
    for box in boxes:
        assert np.all(lo < box.min(axis=0)) and np.all(box.max(axis=0) < hi)
    # no bigger than the union plus the documented 10 % margin
    union = np.concatenate(boxes)
    pad = 0.1 * np.ptp(union, axis=0).max()
    np.testing.assert_allclose(lo, union.min(axis=0) - pad)
    np.testing.assert_allclose(hi, union.max(axis=0) + pad)


def test_default_bounds_function_closed_form():
    robot = trimesh.creation.box(extents=[2, 2, 2])
    obstacle = trimesh.creation.box(extents=[2, 2, 2])
    obstacle.apply_translation([10, 0, 0])
    lo, hi = default_bounds(robot, [obstacle], [0, 0, 0], [0, 0, 0], margin=0.0)
    # C-obstacle box [9 - 1, 11 + 1] in x; the robot's box [-1, 1] at the origin
    np.testing.assert_allclose(lo, [-1, -2, -2])
    np.testing.assert_allclose(hi, [12, 2, 2])
    lo, hi = default_bounds(robot, [], [0, 0, 0], [0, 0, 0])
    np.testing.assert_allclose(lo, [-1.2] * 3)
    np.testing.assert_allclose(hi, [1.2] * 3)


# ----------------------------------------------------------------------------- errors

BASE = {
    "robot": "robot: {mesh: peg.stl}",
    "obstacles": "obstacles:\n  - {mesh: block.stl}",
    "start": "start: [0, 0, 60]",
    "goal": "goal: [0, 0, 30]",
}


def scenario_text(**replace):
    """The base scenario with some top-level entries replaced (None: removed), one per
    line, in the order robot, obstacles, start, goal, then any extra ones."""
    parts = dict(BASE)
    parts.update(replace)
    return "\n".join(v for v in parts.values() if v is not None) + "\n"


# (id, text, field, line or None, substring of the message)
ERRORS = [
    ("yaml-syntax", scenario_text(goal="goal: [0, 0, 30"), None, 5, "YAML syntax error"),
    ("yaml-indent", "robot:\n  mesh: peg.stl\n bad: 1\n", None, 3, "YAML syntax error"),
    ("duplicate-key", scenario_text(extra="start: [1, 1, 1]"), "start", 6, "duplicate key"),
    ("empty", "", None, None, "top level: the scenario is empty"),
    ("not-a-mapping", "- robot\n- start\n", None, None, "top level: expected a mapping"),
    ("robot-string", scenario_text(robot="robot: peg.stl"), "robot", 1,
     "expected a mapping such as {{mesh: peg.stl}}"),  # (.format-escaped)
    ("missing-goal", scenario_text(goal=None), "goal", None, "missing required field"),
    ("missing-robot", scenario_text(robot=None), "robot", None, "missing required field"),
    ("missing-shape", scenario_text(robot="robot:\n  name: r"), "robot.mesh", 1,
     "missing required field"),
    ("missing-position", scenario_text(start="start: {orientation: [1, 0, 0, 0]}"),
     "start.position", 4, "missing required field"),
    ("missing-bounds-max", scenario_text(extra="bounds:\n  min: [0, 0, 0]"), "bounds.max",
     6, "missing required field"),
    ("start-string", scenario_text(start='start: "up"'), "start", 4, "got string 'up'"),
    ("start-short", scenario_text(start="start: [0, 0]"), "start", 4,
     "expected 3 numbers [x, y, z], got 2"),
    ("position-long", scenario_text(obstacles="obstacles:\n  - mesh: block.stl\n"
                                              "    position: [0, 0, 0, 0]"),
     "obstacles[0].position", 4, "expected 3 numbers"),
    ("start-bool", scenario_text(start="start: [0, true, 0]"), "start[1]", 4,
     "expected a number, got boolean true"),
    ("start-inf", scenario_text(start="start: [0, 0, .inf]"), "start[2]", 4,
     "finite"),
    ("goal-nan", scenario_text(goal="goal:\n  - 0\n  - .nan\n  - 0"), "goal[1]", 7,
     "finite"),
    ("obstacles-mapping", scenario_text(obstacles="obstacles: {mesh: block.stl}"),
     "obstacles", 2, "expected a list"),
    ("mesh-missing", scenario_text(obstacles="obstacles:\n  - {mesh: block.stl}\n"
                                             "  - {mesh: blok.stl}"),
     "obstacles[1].mesh", 4, "file 'blok.stl' not found (looked in {folder}); "
                             "did you mean 'block.stl'?"),
    ("mesh-not-string", scenario_text(robot="robot: {mesh: 3}"), "robot.mesh", 1,
     "expected a file path"),
    ("mesh-unreadable", scenario_text(robot="robot: {mesh: broken.stl}"), "robot.mesh", 1,
     "not an STL file"),
    ("mesh-two-shapes", scenario_text(robot="robot: {mesh: peg.stl, box: [1, 1, 1]}"),
     "robot.box", 1, "give only one of mesh, box"),
    ("box-zero", scenario_text(obstacles="obstacles:\n  - box: [1, 0, 1]"),
     "obstacles[0].box[1]", 3, "must be > 0"),
    ("box-short", scenario_text(obstacles="obstacles:\n  - box: [1, 1]"),
     "obstacles[0].box", 3, "expected 3 side lengths"),
    ("sphere-negative", scenario_text(obstacles="obstacles:\n  - {sphere: -2}"),
     "obstacles[0].sphere", 3, "must be > 0"),
    ("cylinder-height", scenario_text(
        obstacles="obstacles:\n  - cylinder:\n      radius: 1\n      height: -1"),
     "obstacles[0].cylinder.height", 5, "must be > 0"),
    ("cylinder-radius-missing", scenario_text(
        obstacles="obstacles:\n  - cylinder: {height: 1}"),
     "obstacles[0].cylinder", 3, "missing required key 'radius'"),
    ("cylinder-sections", scenario_text(
        obstacles="obstacles:\n  - cylinder: {radius: 1, height: 1, sections: 2}"),
     "obstacles[0].cylinder.sections", 3, "must be in 3.."),
    ("scale-zero", scenario_text(robot="robot: {mesh: peg.stl, scale: [1, 0, 1]}"),
     "robot.scale", 1, "must be > 0"),
    ("orientation-mismatch", scenario_text(
        start="start:\n  position: [0, 0, 60]\n  orientation: {rpy: [0, 0, 90]}",
        goal="goal:\n  position: [0, 0, 30]\n  orientation: {rpy: [0, 0, 0]}"),
     "goal.orientation", 9, "differs from start.orientation by 90 degrees"),
    ("orientation-three", scenario_text(
        obstacles="obstacles:\n  - {mesh: block.stl, orientation: [0, 0, 90]}"),
     "obstacles[0].orientation", 3, "ambiguous"),
    ("quaternion-norm", scenario_text(
        obstacles="obstacles:\n  - {mesh: block.stl, orientation: [1, 1, 0, 0]}"),
     "obstacles[0].orientation", 3, "unit length"),
    ("axis-zero", scenario_text(
        obstacles="obstacles:\n  - mesh: block.stl\n    orientation:\n"
                  "      axis: [0, 0, 0]\n      angle_deg: 10"),
     "obstacles[0].orientation.axis", 5, "zero vector"),
    ("angle-without-axis", scenario_text(
        obstacles="obstacles:\n  - {mesh: block.stl, orientation: {angle_deg: 10}}"),
     "obstacles[0].orientation.axis", 3, "missing required field"),
    ("robot-orientation", scenario_text(robot="robot: {mesh: peg.stl, orientation: [1, 0, 0, 0]}"),
     "robot.orientation", 1, "start"),
    ("unknown-top", scenario_text(extra="planer: {seed: 1}"), "planer", 6,
     "unknown key; did you mean 'planner'?"),
    ("unknown-nested", scenario_text(obstacles="obstacles:\n  - mesh: block.stl\n"
                                               "    postion: [0, 0, 0]"),
     "obstacles[0].postion", 4, "unknown key; did you mean 'position'?"),
    ("unknown-setting", scenario_text(extra="planner:\n  seed: 3\n  time_limt: 5"),
     "planner.time_limt", 8, "did you mean 'time_limit'?"),
    ("unknown-no-suggestion", scenario_text(extra="zzz: 1"), "zzz", 6, "unknown key ("),
    ("duplicate-name", scenario_text(
        robot="robot: {mesh: peg.stl, name: part}",
        obstacles="obstacles:\n  - {mesh: block.stl, name: part}"),
     "obstacles[0].name", 3, "name 'part' is already used by robot"),
    ("bounds-min-ge-max", scenario_text(extra="bounds:\n  min: [0, 0, 0]\n"
                                              "  max: [100, 0, 100]"),
     "bounds.max", 8, "max must be greater than min on every axis; not on y"),
    ("start-outside", scenario_text(extra="bounds: {min: [-10, -10, 0], max: [10, 10, 50]}"),
     "start", 4, "outside bounds (z = 60 not in [0, 50])"),
    ("goal-outside", scenario_text(
        goal="goal:\n  position: [0, 20, 30]",
        extra="bounds: {min: [-10, -10, 0], max: [10, 10, 100]}"),
     "goal.position", 6, "outside bounds (y = 20 not in [-10, 10])"),
    ("setting-range", scenario_text(extra="planner: {time_limit: 0}"),
     "planner.time_limit", 6, "must be > 0"),
    ("setting-type", scenario_text(extra="planner:\n  seed: 1.5"), "planner.seed", 7,
     "expected an integer"),
    ("setting-exact", scenario_text(extra="planner:\n  exact: maybe"), "planner.exact", 7,
     "expected auto, true or false"),
    ("setting-threshold", scenario_text(extra="planner:\n  decomposition_threshold: 2"),
     "planner.decomposition_threshold", 7, "must be <= 1"),
    ("units-empty", scenario_text(extra="units: ''"), "units", 6, "non-empty string"),
]


@pytest.mark.parametrize(("text", "field", "line", "expected"),
                         [case[1:] for case in ERRORS], ids=[case[0] for case in ERRORS])
def test_errors_name_file_line_and_field(folder, text, field, line, expected):
    path = write(folder, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    error = info.value
    message = str(error)
    assert "\n" not in message
    assert error.field == field
    assert error.line == line
    where = f"{path}:{line}: " if line is not None else f"{path}: "
    assert message.startswith(where + (f"{field}: " if field else "")), message
    assert expected.format(folder=folder.resolve()) in message, message
    assert isinstance(error, ValueError)


def test_missing_scenario_file(tmp_path):
    with pytest.raises(ScenarioError, match="scenario file not found"):
        load_scenario(tmp_path / "nope.yaml")


def test_parse_scenario_rejects_a_path(folder):
    with pytest.raises(TypeError, match="load_scenario"):
        parse_scenario(folder / "scenario.yaml")  # type: ignore[arg-type]


# ------------------------------------------------------------------------- settings


def test_planner_settings_keys_and_validation():
    assert Settings.keys() == ("resolution", "time_limit", "seed", "contact_tolerance",
                               "decomposition_threshold", "exact", "clearance", "simplify")
    assert settings_from_mapping({"time_limit": 5, "exact": True}) == Settings(
        time_limit=5.0, exact=True)
    assert settings_from_mapping(None) == Settings()
    assert settings_from_mapping({"seed": None}).seed == 0  # null takes the default
    with pytest.raises(ScenarioError) as info:
        settings_from_mapping({"sede": 1})
    assert info.value.field == "planner.sede" and "did you mean 'seed'" in str(info.value)
    with pytest.raises(InvalidParameterError, match="PlannerSettings.clearance"):
        Settings(clearance=-1)
    with pytest.raises(InvalidParameterError, match="PlannerSettings.simplify"):
        Settings(simplify="yes")  # type: ignore[arg-type]


# ------------------------------------------------------------------------ primitives


@pytest.mark.parametrize("spec", [
    {"box": [1, 2, 3]},
    {"sphere": 2},
    {"sphere": {"radius": 2, "subdivisions": 0}},
    {"cylinder": {"radius": 1, "height": 3}},
    {"cylinder": {"radius": 1, "height": 3, "sections": 3}},
])
def test_primitives_are_closed_outward_solids(spec):
    mesh = make_primitive(spec, field="x")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    centre = mesh.vertices.mean(axis=0)
    outward = np.einsum("ij,ij->i", mesh.face_normals, mesh.triangles_center - centre)
    assert np.all(outward > 0)


def test_primitive_sizes():
    np.testing.assert_allclose(make_primitive({"box": [1, 2, 3]}, field="x").bounds,
                               [[-0.5, -1, -1.5], [0.5, 1, 1.5]])
    cylinder = make_primitive({"cylinder": {"radius": 2, "height": 6, "sections": 64}},
                              field="x")
    np.testing.assert_allclose(cylinder.bounds[:, 2], [-3, 3])
    radii = np.linalg.norm(cylinder.vertices[:, :2], axis=1)
    assert np.allclose(radii[radii > 0], 2) and (radii == 0).sum() == 2  # + cap centres
    sphere = make_primitive({"sphere": 1.5}, field="x")
    np.testing.assert_allclose(np.linalg.norm(sphere.vertices, axis=1), 1.5)


@pytest.mark.parametrize(("spec", "field"), [
    ({}, "o"),
    ({"box": [1, 1, 1], "sphere": 1}, "o"),
    ({"box": "big"}, "o.box"),
    ({"sphere": True}, "o.sphere"),
    ({"sphere": {"radius": 1, "subdivisions": 9}}, "o.sphere.subdivisions"),
    ({"cylinder": 3}, "o.cylinder"),
    ({"cylinder": {"radius": 1, "height": 1, "sides": 8}}, "o.cylinder.sides"),
    ({"cylinder": {"radius": float("nan"), "height": 1}}, "o.cylinder.radius"),
])
def test_primitive_errors(spec, field):
    with pytest.raises(ScenarioError) as info:
        make_primitive(spec, field="o")
    assert info.value.field == field
    assert str(info.value).startswith(f"{field}: ")


def test_missing_mesh_suggests_only_mesh_files(folder):
    # the scenario file itself sits beside the meshes: a near miss of its name is no mesh
    path = write(folder, scenario_text(robot="robot: {mesh: scenario.yml}"))
    assert path.suffix == ".yaml" and (path.parent / "scenario.yml").exists() is False
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert "not found" in str(info.value) and "did you mean" not in str(info.value)


def test_differing_orientations_are_held_when_asked(folder):
    text = scenario_text(
        start="start:\n  position: [0, 0, 60]\n  orientation: {rpy: [0, 0, 90]}",
        goal="goal:\n  position: [0, 0, 30]\n  orientation: {rpy: [0, 0, 0]}")
    (folder / "turn.yaml").write_text(text)
    with pytest.raises(ScenarioError, match="--hold-orientation start or goal"):
        load_scenario(folder / "turn.yaml")
    held = load_scenario(folder / "turn.yaml", hold_orientation="goal")
    np.testing.assert_allclose(held.orientation, np.eye(3), atol=1e-12)
    assert any("keeps the goal orientation throughout" in n for n in held.notes)
    np.testing.assert_allclose(load_scenario(folder / "turn.yaml", hold_orientation="start")
                               .orientation, rz(90), atol=1e-12)


def test_an_assembly_or_a_scenario_in_the_wrong_place_is_named():
    """A try-out: plan and view of an assembly said "parts: unknown key; did you mean
    'start'?", and planner.plan(assembly) raised an AttributeError."""
    import planner
    from planner.cli import _parser

    assembly_file = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies" / \
        "peg_in_block.yaml"
    with pytest.raises(ScenarioError, match="an assembly .* not a planning problem: use "
                       "minkplan assemble"):
        load_scenario(assembly_file)
    assembly = planner.load_assembly(assembly_file)
    with pytest.raises(InvalidParameterError, match="plan takes a Scenario .* not Assembly; "
                       "an assembly goes to planner.plan_assembly"):
        planner.plan(assembly)
    scenario = load_scenario(Path(__file__).resolve().parents[1] / "scenarios" /
                             "peg_in_hole.yaml")
    with pytest.raises(InvalidParameterError, match="plan_assembly takes an Assembly .* not "
                       "Scenario; a scenario goes to planner.plan"):
        planner.plan_assembly(scenario)
    # view takes --hold-orientation, as its advice for a turning problem says
    args = _parser().parse_args(["view", "x.cfg", "--hold-orientation", "goal"])
    assert args.hold_orientation == "goal"


def test_a_python_scenarios_goal_outside_its_bounds_is_refused_by_plan():
    """A try-out: a goal moved outside the bounds in Python (the reader refuses it in a
    file) gave not_found, "the goal is within the clearance margin of bounds"."""
    import dataclasses

    import planner

    scenario = load_scenario(Path(__file__).resolve().parents[1] / "scenarios" /
                             "peg_in_hole.yaml")
    moved = dataclasses.replace(scenario, goal=[500.0, 0.0, 0.0])
    with pytest.raises(InvalidParameterError, match=r"Scenario.goal: \[500.0, 0.0, 0.0\] is "
                       r"outside the bounds \(x = 500 not in"):
        planner.plan(moved)
