"""OMPL.app problem import, checked against OMPL.app's own reference solutions.

The ``.path`` files are 6-DOF solutions found by OMPL.app in its frame. If our frame
conversion (app = (x, z, -y) of the Z-up COLLADA files) and reference point (mean of the
robot's vertices) are right, every state of those paths is collision-free against the
imported world, inside the problem's volume, and the first and last states are the
``.cfg``'s start and goal. The negative controls show that the same checks fail in the
file's own frame and in the opposite rotation, so they can catch a wrong convention.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh
from trimesh.collision import CollisionManager

from planner.errors import ScenarioError
from planner.io import load_scenario
from planner.io.omplapp import (
    APP_FROM_ZUP,
    load_omplapp,
    path_state_transform,
    read_app_mesh,
    read_omplapp_path,
    robot_reference_point,
)
from planner.meshes import load_mesh

ASSETS = Path(__file__).resolve().parents[2] / "shared" / "assets" / "omplapp"
PROBLEMS = ["Easy", "cubicles"]

# the file frame (no conversion) and the opposite rotation, app = (x, -z, y)
WRONG_FRAMES = {"file": np.eye(3), "opposite": APP_FROM_ZUP.T}


@pytest.fixture(scope="module")
def scenarios():
    return {name: load_omplapp(ASSETS / f"{name}.cfg") for name in PROBLEMS}


def cfg_values(name: str) -> dict[str, float]:
    values = {}
    for line in (ASSETS / f"{name}.cfg").read_text().splitlines():
        key, sep, value = line.partition("=")
        if sep and "." in key:
            try:
                values[key.strip()] = float(value)
            except ValueError:
                pass
    return values


def volume(name: str) -> tuple[np.ndarray, np.ndarray]:
    v = cfg_values(name)
    return (np.array([v[f"volume.min.{a}"] for a in "xyz"]),
            np.array([v[f"volume.max.{a}"] for a in "xyz"]))


def surface_check(name: str, frame: np.ndarray) -> tuple[int, int]:
    """Reference path against the raw (as-shipped) meshes turned by ``frame``:
    ``(states in collision, states outside the world's box)``, FCL on the surfaces."""
    world = load_mesh(ASSETS / f"{name}_env.dae")
    world.vertices = world.vertices @ frame.T
    robot = load_mesh(ASSETS / f"{name}_robot.dae")
    robot.vertices = robot.vertices @ frame.T
    robot.vertices = robot.vertices - robot.vertices.mean(axis=0)
    manager = CollisionManager()
    manager.add_object("world", world)
    rows = read_omplapp_path(ASSETS / f"{name}.path")
    colliding = sum(manager.in_collision_single(robot, transform=path_state_transform(row))
                    for row in rows)
    lo, hi = world.bounds
    outside = int(np.sum(~np.all((rows[:, :3] >= lo) & (rows[:, :3] <= hi), axis=1)))
    return colliding, outside


# ------------------------------------------------------------------------------ import


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_problem_loads_as_translational_scenario(scenarios, name):
    scenario = scenarios[name]
    values = cfg_values(name)
    assert scenario.name == name
    assert scenario.units == "unitless"
    np.testing.assert_array_equal(scenario.start, [values[f"start.{a}"] for a in "xyz"])
    np.testing.assert_array_equal(scenario.goal, [values[f"goal.{a}"] for a in "xyz"])
    np.testing.assert_array_equal(scenario.orientation, np.eye(3))  # theta = 0
    lo, hi = volume(name)
    np.testing.assert_array_equal(scenario.bounds[0], lo)
    np.testing.assert_array_equal(scenario.bounds[1], hi)
    assert scenario.settings.time_limit == 20.0  # [benchmark] time_limit
    assert scenario.path == (ASSETS / f"{name}.cfg").resolve()
    for part in [scenario.robot, *scenario.obstacles]:
        if part.solid:
            mesh = part.mesh
            assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert load_scenario(ASSETS / f"{name}.cfg").start.tolist() == scenario.start.tolist()


@pytest.mark.assets
def test_what_the_import_changed_is_recorded(scenarios):
    easy, cubicles = scenarios["Easy"], scenarios["cubicles"]
    # Easy: a floor-and-side-wall frame that is closed but inside out in part (a surface),
    # two flat quads (surfaces: OMPL.app collides with them too) and a wall with a window
    assert [(b.name, b.solid) for b in easy.obstacles] == [
        ("Easy_env_0", False), ("Easy_env_1", False), ("Easy_env_2", False),
        ("Easy_env_3", True)]
    assert "winding number -1" in easy.obstacles[0].kind_reason
    assert sum("a surface" in note for note in easy.notes) == 3
    # cubicles: one connected solid once the walls of two floor openings are added
    assert [b.name for b in cubicles.obstacles] == ["cubicles_env_0"]
    assert any("2 pair(s) of facing openings" in note for note in cubicles.notes)
    for scenario in (easy, cubicles):
        assert any(note.startswith("robot: dropped") for note in scenario.notes)


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_shipped_meshes_are_double_sided_and_not_watertight(name):
    for part in ("robot", "env"):
        raw = load_mesh(ASSETS / f"{name}_{part}.dae")
        assert not raw.is_watertight
        # every triangle is there twice, once per side
        merged = trimesh.Trimesh(raw.vertices, raw.faces, process=False)
        merged.merge_vertices(merge_tex=True, merge_norm=True)
        _, counts = np.unique(np.sort(merged.faces, axis=1), axis=0, return_counts=True)
        assert np.all(counts == 2)


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_robot_is_relative_to_the_mean_of_its_vertices(scenarios, name):
    raw = read_app_mesh(ASSETS / f"{name}_robot.dae")
    centre = robot_reference_point(raw)
    np.testing.assert_allclose(centre, raw.vertices.mean(axis=0))
    np.testing.assert_allclose(scenarios[name].robot.mesh.bounds, raw.bounds - centre,
                               atol=1e-9)


# ----------------------------------------------------------------------- frame checks


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_volume_is_the_world_box_in_the_app_frame(name):
    lo, hi = volume(name)
    world = read_app_mesh(ASSETS / f"{name}_env.dae")
    np.testing.assert_allclose(world.bounds, [lo, hi], atol=0.01)  # cfg has 2 decimals
    raw = load_mesh(ASSETS / f"{name}_env.dae")
    for frame in WRONG_FRAMES.values():  # negative control
        assert not np.allclose(raw.bounds @ frame.T, [lo, hi], atol=1.0)


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_reference_path_starts_and_ends_at_the_cfg_poses(scenarios, name):
    rows = read_omplapp_path(ASSETS / f"{name}.path")
    assert rows.shape[1] == 7 and len(rows) > 10
    scenario = scenarios[name]
    np.testing.assert_allclose(rows[0, :3], scenario.start)
    np.testing.assert_allclose(rows[-1, :3], scenario.goal)
    for row in (rows[0], rows[-1]):
        np.testing.assert_allclose(path_state_transform(row)[:3, :3], scenario.orientation,
                                   atol=1e-12)
    lo, hi = scenario.bounds
    assert np.all((rows[:, :3] >= lo) & (rows[:, :3] <= hi))


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_reference_path_is_free_against_the_imported_solids(scenarios, name):
    """Every state of OMPL.app's solution, as solids: no surface contact (FCL), no robot
    inside an obstacle and no obstacle inside the robot."""
    scenario = scenarios[name]
    manager = CollisionManager()
    for body in scenario.obstacles:
        manager.add_object(body.name, body.mesh)
    robot = scenario.robot.mesh
    rows = read_omplapp_path(ASSETS / f"{name}.path")
    clearances = []
    for row in rows:
        transform = path_state_transform(row)
        assert not manager.in_collision_single(robot, transform=transform), row
        clearances.append(manager.min_distance_single(robot, transform=transform))
        placed = robot.copy()
        placed.apply_transform(transform)
        for body in scenario.obstacles:
            assert not body.mesh.contains(placed.vertices[:1])[0], (row, body.name)
            assert not placed.contains(body.mesh.vertices[:1])[0], (row, body.name)
    assert min(clearances) > 0.5  # cubicles' tightest state clears by ~0.9


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_translational_start_and_goal_are_free(scenarios, name):
    scenario = scenarios[name]
    manager = CollisionManager()
    for body in scenario.obstacles:
        manager.add_object(body.name, body.mesh)
    for point in (scenario.start, scenario.goal):
        placed = scenario.robot_at(point)
        assert not manager.in_collision_single(placed)
        for body in scenario.obstacles:
            assert not body.mesh.contains(placed.vertices[:1])[0]


@pytest.mark.assets
@pytest.mark.parametrize("name", PROBLEMS)
def test_reference_path_is_free_against_the_raw_surfaces_only_in_the_app_frame(name):
    assert surface_check(name, APP_FROM_ZUP) == (0, 0)
    for frame_name, frame in WRONG_FRAMES.items():  # negative control: the check can fail
        colliding, outside = surface_check(name, frame)
        assert colliding > 0 or outside > 0, frame_name


# ------------------------------------------------------------------------------ errors


def copy_problem(tmp_path: Path, name: str, edit=None) -> Path:
    for suffix in ("_robot.dae", "_env.dae"):
        shutil.copy(ASSETS / f"{name}{suffix}", tmp_path / f"{name}{suffix}")
    text = (ASSETS / f"{name}.cfg").read_text()
    if edit is not None:
        text = edit(text)
    path = tmp_path / f"{name}.cfg"
    path.write_text(text)
    return path


def line_of(path: Path, prefix: str) -> int:
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if line.startswith(prefix):
            return number
    raise AssertionError(prefix)


@pytest.mark.assets
def test_copied_problem_loads(tmp_path):
    scenario = load_omplapp(copy_problem(tmp_path, "Easy"))
    assert len(scenario.obstacles) == 4


@pytest.mark.assets
@pytest.mark.parametrize(("edit", "field", "line_prefix", "expected"), [
    (lambda t: t.replace("goal.z = -400.0\n", ""), "problem.goal.z", None,
     "missing required field"),
    (lambda t: t.replace("start.y = 160.0", "start.y = up"), "problem.start.y", "start.y",
     "expected a number, got 'up'"),
    (lambda t: t.replace("goal.theta = 0", "goal.theta = 1.5707963"), "problem.goal.theta",
     "goal.theta", "differs from the start's by 90 degrees"),
    (lambda t: t.replace("world = Easy_env.dae", "world = Easy_envv.dae"), "problem.world",
     "world", "file 'Easy_envv.dae' not found"),
    (lambda t: t.replace("start.z = -200.0", "start.z = 0"), "problem.start.z", "start.z",
     "outside the volume"),
    (lambda t: t.replace("start.z = -200.0\n", ""), "problem.start.z", None,
     "2D (SE(2)) problems are not supported"),
    (lambda t: t.replace("start.x = 270.0", "start.x = nan"), "problem.start.x", "start.x",
     "finite"),
])
def test_cfg_errors_name_key_and_line(tmp_path, edit, field, line_prefix, expected):
    path = copy_problem(tmp_path, "Easy", edit)
    with pytest.raises(ScenarioError) as info:
        load_omplapp(path)
    error = info.value
    assert error.field == field
    line = None if line_prefix is None else line_of(path, line_prefix)
    assert error.line == line
    where = f"{path}:{line}: " if line is not None else f"{path}: "
    assert str(error).startswith(f"{where}{field}: "), str(error)
    assert expected in str(error)


@pytest.mark.assets
def test_unusable_robot_mesh_is_reported(tmp_path):
    path = copy_problem(tmp_path, "Easy")
    (tmp_path / "Easy_robot.dae").write_text("<COLLADA></COLLADA>")
    with pytest.raises(ScenarioError) as info:
        load_omplapp(path)
    assert info.value.field == "problem.robot"
    assert info.value.line == line_of(path, "robot")


def test_missing_cfg(tmp_path):
    with pytest.raises(ScenarioError, match="not found"):
        load_omplapp(tmp_path / "none.cfg")


def test_path_file_errors(tmp_path):
    path = tmp_path / "bad.path"
    path.write_text("1 2 3 0 0 0 1\n1 2 3 0 0 1\n")
    with pytest.raises(ScenarioError, match=r"bad.path:2: expected 7 numbers"):
        read_omplapp_path(path)


def test_path_state_transform_is_scalar_last():
    half = math.sqrt(0.5)
    transform = path_state_transform([1, 2, 3, 0, 0, half, half])  # 90 degrees about z
    np.testing.assert_allclose(transform[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(transform[:3, 3], [1, 2, 3])


@pytest.mark.assets
def test_repeated_keys_are_read_as_omplapp_reads_them():
    # cubicles_opt.cfg lists "aps=" twice under [planner], as OMPL.app's own files do
    scenario = load_omplapp(ASSETS / "cubicles_opt.cfg")
    assert scenario.path.name == "cubicles_opt.cfg"
    assert len(scenario.obstacles) == len(load_omplapp(ASSETS / "cubicles.cfg").obstacles)


@pytest.mark.assets
@pytest.mark.parametrize("hold", ["start", "goal"])
def test_a_turning_problem_is_read_translation_only_when_asked(hold):
    with pytest.raises(ScenarioError, match=r"differs from the start's by 90 degrees.*"
                                            r"--hold-orientation start \(or goal\)"):
        load_omplapp(ASSETS / "Abstract.cfg")
    scenario = load_omplapp(ASSETS / "Abstract.cfg", hold_orientation=hold)
    turned = np.allclose(scenario.orientation, np.eye(3))
    assert turned == (hold == "start")  # the start's theta is 0, the goal's 90 degrees
    assert any(f"keeps the {hold} orientation throughout" in n for n in scenario.notes)
    assert load_scenario(ASSETS / "Abstract.cfg", hold_orientation=hold).start.tolist() == \
        scenario.start.tolist()


@pytest.mark.assets
def test_orientations_within_the_tolerance_are_equal(tmp_path):
    # OMPL.app's Apartment differs by 1.2e-6 degrees: the same orientation
    path = copy_problem(tmp_path, "Easy",
                        lambda t: t.replace("goal.theta = 0", "goal.theta = 2.1e-8"))
    scenario = load_omplapp(path)
    assert not any("translation-only" in n for n in scenario.notes)
    np.testing.assert_array_equal(scenario.orientation, np.eye(3))


@pytest.mark.assets
def test_easy_frame_is_the_only_closed_piece_that_is_no_solid():
    """The search over the OMPL.app set: every connected piece of every robot and world
    that is closed and consistently wound, and whether its winding number goes negative
    (in front of a face, or where faces cross). Only Easy's frame does."""
    from planner._minkowski_core import crossing_windings, front_windings
    from planner.errors import InvalidMeshError
    from planner.io.omplapp_meshes import single_sided
    from planner.meshes.solids import clean, orient_shells
    from planner.meshes.topology import checked_arrays, compact

    found = []
    for dae in sorted(ASSETS.glob("*.dae")):
        mesh, _ = single_sided(read_app_mesh(dae))
        labels = trimesh.graph.connected_component_labels(mesh.face_adjacency,
                                                          node_count=len(mesh.faces))
        for k in np.unique(labels):
            piece = trimesh.Trimesh(mesh.vertices, mesh.faces[labels == k], process=False)
            v, f = compact(*checked_arrays(piece, "piece"))
            try:
                (v, f), report = clean(v, f, "piece")
                if report["edge_stats"] != (0, 0):
                    continue  # open: a surface anyway
                f = orient_shells(v, f, "piece", report["scale"], report)
            except InvalidMeshError:
                continue
            windings = np.concatenate([front_windings(v, f), crossing_windings(v, f)])
            if (windings < 0).any():
                found.append((dae.name, len(f)))
    assert found == [("Easy_env.dae", 52)]


# ------------------------------------------------------- a problem authored in the format

WINDOW = Path(__file__).resolve().parent / "data" / "omplapp_format" / "window.cfg"
"""OMPL.app's format on files written in tests/data (OMPL.app's own may not be shared)."""


def test_a_problem_in_omplapp_format_imports_in_omplapps_frame():
    scenario = load_omplapp(WINDOW)
    assert scenario.name == "window"
    np.testing.assert_array_equal(scenario.start, [20, 10, -20])
    np.testing.assert_array_equal(scenario.goal, [20, 10, -80])
    # the file's wall box x in [0, 40], y in [45, 55], z in [0, 60] is app (x, z, -y)
    world = read_app_mesh(WINDOW.with_name("window_env.dae"))
    np.testing.assert_allclose(world.bounds, [[-20, 0, -120], [120, 60, 20]])
    kinds = sorted((len(b.mesh.faces), b.solid) for b in scenario.obstacles)
    assert kinds == [(2, False)] + [(12, True)] * 4   # the floor's doubled quad, 4 boxes
    assert robot_reference_point(read_app_mesh(WINDOW.with_name("window_robot.dae"))) \
        == pytest.approx([0, 0, 0])


def window_copy(tmp_path: Path, edit) -> Path:
    for source in WINDOW.parent.glob("window*"):
        (tmp_path / source.name).write_bytes(source.read_bytes())
    path = tmp_path / "window.cfg"
    path.write_text(edit(path.read_text()))
    return path


@pytest.mark.parametrize(("edit", "field", "hint"), [
    (lambda t: t.replace("volume.max.z", "volume.mx.z"), "problem.volume.mx.z",
     "did you mean 'volume.max.z'?"),
    (lambda t: t.replace("time_limit", "time_limt"), "benchmark.time_limt",
     "did you mean 'time_limit'?"),
    (lambda t: t.replace("goal.axis.y", "goal.axis.yy"), "problem.goal.axis.yy",
     "did you mean 'goal.axis.y'?"),
])
def test_a_key_that_looks_like_a_typo_is_refused(tmp_path, edit, field, hint):
    path = window_copy(tmp_path, edit)
    with pytest.raises(ScenarioError) as info:
        load_omplapp(path)
    assert info.value.field == field
    assert str(info.value).startswith(f"{path}:") and hint in str(info.value)


def test_a_key_omplapp_does_not_define_is_noted_as_ignored(tmp_path):
    path = window_copy(tmp_path, lambda t: t.replace("[benchmark]",
                                                     "colour = blue\n\n[benchmark]"))
    notes = load_omplapp(path).notes
    assert "sections and keys OMPL.app does not define, ignored: problem.colour" in notes
    assert not any("ignored" in note for note in load_omplapp(WINDOW).notes)
    # OMPL.app's benchmark options are known keys, not noted
    path = window_copy(tmp_path, lambda t: t.replace(
        "[benchmark]", "threshold = 0.1\nsolution_length = 10\n\n[extra]\na = 1\n\n[benchmark]"))
    assert load_omplapp(path).notes[0] == ("sections and keys OMPL.app does not define, "
                                           "ignored: [extra]")


def test_a_misspelled_section_is_refused_and_a_repeated_key_noted(tmp_path):
    path = window_copy(tmp_path, lambda t: t.replace("[benchmark]", "[benchmrk]"))
    with pytest.raises(ScenarioError, match=r"window.cfg:\d+: \[benchmrk\]: unknown "
                                            r"section; did you mean \[benchmark\]\?"):
        load_omplapp(path)
    path = window_copy(tmp_path, lambda t: t.replace("goal.z = -80", "goal.z = -70\ngoal.z = -80"))
    scenario = load_omplapp(path)
    assert scenario.goal[2] == -80  # the last one counts
    assert any("more than once in [problem]" in n and "goal.z" in n for n in scenario.notes)


def test_a_kinodynamic_problem_is_refused(tmp_path):
    path = window_copy(tmp_path, lambda t: t.replace("[benchmark]",
                                                     "control = blimp\n\n[benchmark]"))
    with pytest.raises(ScenarioError, match=r"problem.control: 'blimp': kinodynamic"):
        load_omplapp(path)
