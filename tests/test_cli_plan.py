"""``minkplan plan``: outputs per the contract, exit codes, one-line input errors, and the
Python API giving the same answer."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.cli import main
from planner.io import load_scenario
from planner.planning import plan

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
PATH_KEYS = {"status", "waypoints", "length", "clearance", "timings", "validation"}


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("cli-decompositions")


def run(args, capsys):
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_found_path_exit_0_and_files(tmp_path, capsys, cache_dir):
    out = tmp_path / "peg"
    code, stdout, err = run(["plan", str(SCENARIOS / "peg_in_hole_0.1.yaml"), "--out", str(out),
                             "--cache-dir", str(cache_dir), "--no-progress"], capsys)
    assert code == 0, err
    assert "found" in stdout
    doc = json.loads((out / "path.json").read_text())
    assert PATH_KEYS <= set(doc)
    assert doc["status"] == "found"
    assert doc["validation"]["fcl"]["valid"] and doc["validation"]["ompl"]["valid"]
    wp = np.array(doc["waypoints"])
    assert wp.shape[1] == 3 and len(wp) >= 2
    assert doc["length"] == pytest.approx(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum())
    assert doc["clearance"] > 0
    report = json.loads((out / "report.json").read_text())
    for key in ("cells", "graph", "refinement", "seconds", "certificate", "decomposition"):
        assert key in report
    assert report["cells"]["per_level"] and report["graph"]["nodes"] > 0
    assert {"empty", "full", "mixed", "level", "size"} <= set(report["cells"]["per_level"][0])
    assert not (out / "certificate.json").exists()
    assert not list(out.glob(".*")), "no temporary files left behind"
    # the Python API gives the same result
    outcome = plan(load_scenario(SCENARIOS / "peg_in_hole_0.1.yaml"), cache_dir=cache_dir,
                   progress=False)
    np.testing.assert_allclose(outcome.waypoints, wp, rtol=0, atol=1e-12)


def test_no_path_exit_1_with_certificate(tmp_path, capsys, cache_dir):
    out = tmp_path / "seal"
    code, stdout, err = run(["plan", str(SCENARIOS / "sealed_chamber.yaml"), "--out", str(out),
                             "--cache-dir", str(cache_dir)], capsys)
    assert code == 1, err
    assert "no_path" in stdout
    doc = json.loads((out / "path.json").read_text())
    assert doc["status"] == "no_path" and doc["waypoints"] == [] and doc["length"] is None
    report = json.loads((out / "report.json").read_text())
    assert report["certificate"]["exact"] is True
    assert report["certificate"]["wall_cells"] > 0
    cert = json.loads((out / "certificate.json").read_text())
    assert len(cert["walls"]) == report["certificate"]["wall_cells"]


def test_start_in_collision_exit_1(tmp_path, capsys, cache_dir):
    out = tmp_path / "hit"
    code, stdout, _ = run(["plan", str(SCENARIOS / "start_in_collision.yaml"), "--out",
                           str(out), "--cache-dir", str(cache_dir)], capsys)
    assert code == 1
    doc = json.loads((out / "path.json").read_text())
    assert doc["status"] == "no_path" and doc["reason"] == "start_in_collision"
    assert "block" in doc["message"]
    assert json.loads((out / "report.json").read_text())["collision"]["obstacle"] == "block"


def test_ompl_planner_same_outputs(tmp_path, capsys, cache_dir):
    out = tmp_path / "rrt"
    code, _, err = run(["plan", str(SCENARIOS / "peg_in_hole.yaml"), "--out", str(out),
                        "--planner", "ompl:RRTConnect", "--time-limit", "10", "--seed", "1"],
                       capsys)
    assert code == 0, err
    doc = json.loads((out / "path.json").read_text())
    assert PATH_KEYS <= set(doc)
    assert doc["planner"] == "ompl:RRTConnect" and doc["status"] == "found"
    assert doc["validation"]["fcl"]["valid"] and doc["validation"]["ompl"]["valid"]


def write(tmp_path, text: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return path


PEG = str((SCENARIOS / "peg_in_hole" / "peg.stl").resolve())


@pytest.mark.parametrize(
    "text, expected",
    [
        (f"robot: {{mesh: {PEG}}}\nstrat: [0, 0, 0]\ngoal: [1, 0, 0]\n", "strat"),
        (f"robot: {{mesh: {PEG}}}\nstart: [0, 0]\ngoal: [1, 0, 0]\n", "start"),
        ("robot: {mesh: missing.stl}\nstart: [0, 0, 0]\ngoal: [1, 0, 0]\n", "missing.stl"),
        (f"robot: {{mesh: {PEG}}}\nstart: [0, 0, 0]\ngoal: [1, 0, 0]\n"
         "planner: {time_limit: -1}\n", "planner.time_limit"),
    ],
)
def test_schema_errors_one_line_exit_2(tmp_path, capsys, text, expected):
    path = write(tmp_path, text)
    code, stdout, err = run(["plan", str(path), "--out", str(tmp_path / "o")], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("minkplan: error: ")
    assert expected in lines[0] and "bad.yaml" in lines[0]
    assert not (tmp_path / "o" / "path.json").exists()


@pytest.mark.parametrize(
    "extra, expected",
    [
        (["--planner", "dijkstra"], "--planner"),
        (["--planner", "ompl:Nope"], "unknown OMPL planner"),
        (["--time-limit", "0"], "--time-limit"),
    ],
)
def test_bad_options_exit_2(tmp_path, capsys, extra, expected):
    code, _, err = run(["plan", str(SCENARIOS / "bug_trap.yaml"), "--out", str(tmp_path / "o"),
                        *extra], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and expected in err


def test_the_exact_option_is_named_where_its_value_came_from(tmp_path, capsys, cache_dir):
    """``--exact false`` on a surface is refused as the option's, not as the scenario's
    ``planner.exact`` (which is named when the file set it); the source chosen by the
    option says so in report.json."""
    text = (SCENARIOS / "sealed_chamber_open.yaml").read_text().replace(
        "mesh: sealed_chamber/chamber_open.stl",
        f"mesh: {SCENARIOS / 'sealed_chamber' / 'chamber_open.stl'}, kind: surface")
    surface = write(tmp_path, text)
    code, _, err = run(["plan", str(surface), "--out", str(tmp_path / "o"), "--exact", "false",
                        "--no-progress"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--exact false: chamber is a surface" in err and "use --exact auto" in err
    assert "planner.exact" not in err
    surface.write_text(text + "planner: {exact: false}\n")
    code, _, err = run(["plan", str(surface), "--out", str(tmp_path / "o"), "--no-progress"],
                       capsys)
    assert code == 2 and "planner.exact: false: chamber is a surface" in err
    assert "use planner.exact: auto" in err
    out = tmp_path / "peg"
    code, _, err = run(["plan", str(SCENARIOS / "peg_in_hole_0.1.yaml"), "--out", str(out),
                        "--exact", "true", "--cache-dir", str(cache_dir), "--no-progress"],
                       capsys)
    assert code == 0, err
    report = json.loads((out / "report.json").read_text())
    assert (report["source"]["used"], report["source"]["why"]) == ("exact", "--exact true")


def test_missing_scenario_and_bad_out(tmp_path, capsys):
    code, _, err = run(["plan", str(tmp_path / "none.yaml"), "--out", str(tmp_path)], capsys)
    assert code == 2 and "none.yaml" in err and len(err.strip().splitlines()) == 1
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = run(["plan", str(SCENARIOS / "bug_trap.yaml"), "--out", str(blocker)], capsys)
    assert code == 2 and "--out" in err


def test_installed_entry_point(tmp_path, cache_dir):
    out = tmp_path / "trap"
    proc = subprocess.run(
        [sys.executable, "-m", "planner", "plan", str(SCENARIOS / "bug_trap.yaml"), "--out",
         str(out), "--cache-dir", str(cache_dir)],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert json.loads((out / "path.json").read_text())["status"] == "found"


OMPLAPP = Path(__file__).resolve().parents[2] / "shared" / "assets" / "omplapp" / "Easy.cfg"


@pytest.mark.assets
def test_omplapp_problem_file(tmp_path, capsys, cache_dir):
    out = tmp_path / "easy"
    code, stdout, err = run(["plan", str(OMPLAPP), "--out", str(out), "--cache-dir",
                             str(cache_dir)], capsys)
    assert code == 0, err
    doc = json.loads((out / "path.json").read_text())
    assert doc["status"] == "found"
    assert doc["validation"]["fcl"]["valid"] and doc["validation"]["ompl"]["valid"]
    report = json.loads((out / "report.json").read_text())
    # the Easy world is not convex: auto takes the exact source, no CoACD
    assert report["source"]["used"] == "exact" and report["decomposition"]["exact"] is True


WINDOW = Path(__file__).resolve().parent / "data" / "omplapp_format" / "window.cfg"
"""A problem in OMPL.app's file format authored in tests/data (it runs in every clone)."""


def test_a_problem_in_omplapp_format_is_planned_end_to_end(tmp_path, capsys, cache_dir):
    """``window.cfg``: Z-up COLLADA, a double-sided floor (a surface) and a wall of four
    boxes with a 20 x 20 window; the 10-cube robot must pass it (the straight line hits
    the wall, the volume leaves no way around or over)."""
    from planner.validation import FclChecker

    out = tmp_path / "window"
    code, stdout, err = run(["plan", str(WINDOW), "--out", str(out), "--cache-dir",
                             str(cache_dir), "--no-progress"], capsys)
    assert code == 0, err
    doc = json.loads((out / "path.json").read_text())
    assert doc["status"] == "found"
    assert doc["validation"]["fcl"]["valid"] and doc["validation"]["ompl"]["valid"]
    report = json.loads((out / "report.json").read_text())
    assert report["source"]["used"] == "exact"        # the floor is no solid
    scenario = load_scenario(WINDOW)
    meshes = [b.mesh for b in scenario.obstacles]
    straight = FclChecker(scenario.robot.mesh, meshes, solid=[b.solid for b in
                                                              scenario.obstacles])
    assert not straight.check_path(np.stack([scenario.start, scenario.goal])).valid
    # app frame: the wall is z in [-55, -45]; the window x in [40, 60], y in [20, 40]
    points = np.array(doc["waypoints"])
    dense = np.concatenate([np.linspace(a, b, 50) for a, b in zip(points, points[1:])])
    in_wall = dense[(dense[:, 2] > -55 - 5) & (dense[:, 2] < -45 + 5)]
    assert len(in_wall) and np.all((in_wall[:, 0] >= 45) & (in_wall[:, 0] <= 55))
    assert np.all((in_wall[:, 1] >= 25) & (in_wall[:, 1] <= 35))


def test_an_internal_error_is_exit_3_and_one_line(tmp_path, capsys, monkeypatch):
    """A bug (anything but an input or resource error) never exits 0 or 1, whose meanings
    are answers; -vv shows the traceback."""
    import planner.planning

    def broken(*args, **kwargs):
        raise RuntimeError("a bug\nwith two lines")

    monkeypatch.setattr(planner.planning, "plan", broken)
    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "peg_in_hole.yaml"
    code = main(["plan", str(scenario), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 3
    assert err.splitlines() == ["minkplan: internal error in plan: RuntimeError: a bug; please "
                                "report it (-vv shows the traceback)"]
    assert main(["plan", str(scenario), "--out", str(tmp_path / "o"), "-vv"]) == 3
    assert "Traceback" in capsys.readouterr().err
    assert not (tmp_path / "o" / "path.json").exists()


def test_a_found_path_exports_in_ompls_se3_format(tmp_path, capsys, cache_dir):
    from trimesh import transformations as tf

    from planner.io.omplapp import read_omplapp_path

    folder = SCENARIOS / "_schema_examples"
    text = (folder / "full.yaml").read_text().replace("mesh: block.stl",
                                                      f"mesh: {folder / 'block.stl'}")
    text = text.replace("mesh: peg.stl", f"mesh: {folder / 'peg.stl'}")
    text = text.replace("orientation: {rpy: [0, 0, 0]}", "orientation: {rpy: [0, 0, 30]}")
    scenario_file = tmp_path / "turned.yaml"
    scenario_file.write_text(text)
    exported = tmp_path / "turned.path"
    code, out, _ = run(["plan", str(scenario_file), "--out", str(tmp_path / "out"),
                        "--cache-dir", str(cache_dir), "--export-path", str(exported)], capsys)
    assert code == 0 and "OMPL's SE(3) path format" in out
    rows = read_omplapp_path(exported)
    waypoints = json.loads((tmp_path / "out" / "path.json").read_text())["waypoints"]
    np.testing.assert_array_equal(rows[:, :3], waypoints)
    scenario = load_scenario(scenario_file)
    for row in rows:  # every state holds the robot's one orientation, 30° about z
        x, y, z, w = row[3:]
        np.testing.assert_allclose(tf.quaternion_matrix([w, x, y, z])[:3, :3],
                                   scenario.orientation, atol=1e-12)
    assert np.isclose(rows[0, 6], np.cos(np.radians(15)))


def test_no_path_exports_nothing_and_a_bad_export_path_is_refused(tmp_path, capsys,
                                                                   cache_dir):
    exported = tmp_path / "none.path"
    code, out, _ = run(["plan", str(SCENARIOS / "sealed_chamber.yaml"), "--out",
                        str(tmp_path / "out"), "--cache-dir", str(cache_dir),
                        "--export-path", str(exported)], capsys)
    assert code == 1 and not exported.exists()
    (tmp_path / "file").write_text("")
    code, _, err = run(["plan", str(SCENARIOS / "peg_in_hole.yaml"), "--out",
                        str(tmp_path / "out2"), "--export-path",
                        str(tmp_path / "file" / "x.path")], capsys)
    assert code == 2 and "--export-path" in err and "is a file" in err
    assert not (tmp_path / "out2" / "path.json").exists()


@pytest.mark.parametrize("args, hint", [
    (["plam", "x.yaml"], "did you mean 'plan'?"),
    (["plan", "x.yaml", "--out", "o", "--tme-limit", "3"], "did you mean '--time-limit'"),
    (["batch", "x.yaml", "--out", "o", "--planners", "ompl:RRTConect"],
     "did you mean 'ompl:RRTConnect'?"),
    # a misspelled option that leaves a required one missing: argparse says the latter
    (["plan", "x.yaml", "--outt", "o"], "did you mean '--out' (for '--outt')?"),
    (["plan", str(SCENARIOS / "peg_in_hole.yaml"), "--out", "o", "--planner",
      "ompl:RRTConect"], "did you mean 'RRTConnect'?"),
    (["plan", str(SCENARIOS / "peg_in_hole.yaml"), "--out", "o", "--planner", "minkpln"],
     "did you mean 'minkplan'?"),
    (["plan", str(SCENARIOS / "peg_in_hole.yaml"), "--out", "o", "--planner",
      "omp:PRM"], "did you mean 'ompl:PRM'?"),
])
def test_a_misspelling_gets_a_did_you_mean(tmp_path, capsys, monkeypatch, args, hint):
    monkeypatch.chdir(tmp_path)
    try:
        code = main(args)
    except SystemExit as exit_:  # argparse's own errors leave through SystemExit
        code = exit_.code
    err = capsys.readouterr().err
    assert code == 2 and hint in err and len(err.strip().splitlines()) == 1, err


def test_an_output_folder_that_cannot_be_created_is_the_one_named(tmp_path, capsys,
                                                                   monkeypatch):
    """``--out /proc/nope/run``: /proc exists and takes no new folder; the message names the
    folder that does not exist (was: "folder /proc is not writable")."""
    import errno
    import tempfile
    import types

    import planner.output

    def refused(dir=None):  # noqa: A002 (tempfile's own keyword)
        raise FileNotFoundError(errno.ENOENT, "No such file or directory")

    monkeypatch.setattr(planner.output, "tempfile",
                        types.SimpleNamespace(TemporaryFile=refused, mkstemp=tempfile.mkstemp))
    code, _, err = run(["plan", str(SCENARIOS / "bug_trap.yaml"), "--out",
                        str(tmp_path / "nope" / "run")], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert (f"--out {tmp_path}/nope/run: folder {tmp_path}/nope does not exist and cannot be "
            f"created in {tmp_path} (creating a file there failed: No such file or directory)"
            ) in err
    code, _, err = run(["plan", str(SCENARIOS / "bug_trap.yaml"), "--out", str(tmp_path)],
                       capsys)
    assert code == 2 and (f"folder {tmp_path} is not writable (creating a file there failed: "
                          f"No such file") in err
    assert not (tmp_path / "nope").exists()
