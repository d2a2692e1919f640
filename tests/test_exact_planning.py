"""Planning on the exact source (issue 6): a 10-wide peg and a plate whose square hole is
0.02 smaller (no path, exact certificate for the meshes) or 0.02 larger (a path, valid by
FCL and OMPL); planning from a tolerated contact; the CLI's --exact."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from planner.io import load_scenario
from planner.planning import plan


def plate_with_hole(hole: float, half: float = 40.0, thickness: float = 2.0) -> trimesh.Trimesh:
    """A ``2 half`` square plate (z in [0, thickness]) with a centred square through-hole
    of side ``hole``, as one closed non-convex mesh (the faces between the 8 filled cells
    of a 3 x 3 grid and the empty ones)."""
    xs = [-half, -hole / 2, hole / 2, half]
    zs = [0.0, thickness]
    full = {(i, j) for i in range(3) for j in range(3)} - {(1, 1)}
    verts: dict[tuple, int] = {}
    faces = []

    def vid(p):
        return verts.setdefault(p, len(verts))

    for (i, j) in full:
        box = [(xs[i], xs[i + 1]), (xs[j], xs[j + 1]), (zs[0], zs[1])]
        for axis in range(3):
            for side in (0, 1):
                if axis < 2:
                    n = [i, j]
                    n[axis] += 1 if side else -1
                    if tuple(n) in full:
                        continue
                u, w = (axis + 1) % 3, (axis + 2) % 3
                quad = []
                for du, dw in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = [0.0, 0.0, 0.0]
                    p[axis] = box[axis][side]
                    p[u] = box[u][du]
                    p[w] = box[w][dw]
                    quad.append(vid(tuple(p)))
                if side == 0:
                    quad.reverse()
                faces += [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]]
    mesh = trimesh.Trimesh(np.array(list(verts)), np.array(faces), process=True)
    return mesh


def write_scenario(tmp_path, hole: float, exact="true") -> object:
    plate = plate_with_hole(hole)
    assert plate.is_watertight and plate.volume > 0 and not plate.is_convex
    plate.export(tmp_path / "plate.stl")
    trimesh.creation.box([10.0, 10.0, 10.0]).export(tmp_path / "peg.stl")
    (tmp_path / "s.yaml").write_text(
        "name: plate\n"
        "robot: {name: peg, mesh: peg.stl}\n"
        "obstacles:\n  - {name: plate, mesh: plate.stl}\n"
        "start: [0, 0, 10]\ngoal: [0, 0, -10]\n"
        "bounds: {min: [-20, -20, -15], max: [20, 20, 15]}\n"
        f"planner: {{exact: {exact}, time_limit: 60}}\n")
    return load_scenario(tmp_path / "s.yaml")


def test_hole_smaller_than_the_peg_has_no_path_with_an_exact_certificate(tmp_path):
    outcome = plan(write_scenario(tmp_path, 9.98), progress=False)
    assert outcome.report["source"]["used"] == "exact"
    assert outcome.status == "no_path", outcome.message
    cert = outcome.certificate
    assert cert["exact"] is True and cert["source"] == "exact"
    assert "meshes as given" in cert["relative_to"]
    assert cert["wall_cells"] > 0 and cert["wall_cells_by_obstacle"].get("plate", 0) > 0


def test_hole_larger_than_the_peg_gives_a_valid_path(tmp_path):
    outcome = plan(write_scenario(tmp_path, 10.02), progress=False)
    assert outcome.report["source"]["used"] == "exact"
    assert outcome.status == "found", outcome.message
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]
    wp = outcome.waypoints
    # it goes through the hole: where it crosses the plate, |x|, |y| <= 0.01
    z = wp[:, 2]
    k = int(np.argmax(z < 1.0))
    a, b = wp[k - 1], wp[k]
    cross = a + (b - a) * (a[2] - 1.0) / (a[2] - b[2])
    assert np.all(np.abs(cross[:2]) <= 0.01 + 1e-5)
    # STL stores float32: the 0.01 gap is exact to about 1e-6
    assert 0.0 <= outcome.clearance <= 0.01 + 1e-5


def test_auto_takes_the_exact_source_for_a_non_convex_part(tmp_path):
    scenario = write_scenario(tmp_path, 10.02, exact="auto")
    outcome = plan(scenario, progress=False)
    assert outcome.report["source"] == {"used": "exact", "why": "auto: plate not convex",
                                        "triangles": outcome.report["source"]["triangles"]}
    assert outcome.report["source"]["triangles"]["robot"] == 12
    assert outcome.status == "found"


def test_exact_plans_from_a_tolerated_contact(tmp_path):
    """The peg resting on the plate (touching) starts in tolerated contact: the planner
    steps out without convex primitives to follow, and lifts it away."""
    scenario = write_scenario(tmp_path, 9.98)
    import dataclasses

    scenario = dataclasses.replace(scenario, start=np.array([0.0, 0.0, 7.0]),
                                   goal=np.array([0.0, 0.0, 14.0]))
    outcome = plan(scenario, progress=False)
    assert outcome.status == "found", outcome.message
    assert outcome.validation["fcl"]["valid"]


@pytest.mark.parametrize("flag", ["true", "false"])
def test_cli_exact_flag_is_reported(tmp_path, flag):
    write_scenario(tmp_path, 12.0, exact="auto")
    out = tmp_path / f"out_{flag}"
    r = subprocess.run([sys.executable, "-m", "planner", "plan", str(tmp_path / "s.yaml"),
                        "--out", str(out), "--exact", flag, "--no-progress",
                        "--cache-dir", str(tmp_path / "cache")],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["source"]["used"] == ("exact" if flag == "true" else "decomposition")


def test_cli_exact_with_an_open_mesh_is_one_line(tmp_path):
    """An open plate asked to be a solid (kind: solid) is one line of error; by default
    (kind: auto) it is a surface, planned as FCL sees it."""
    write_scenario(tmp_path, 12.0)
    open_plate = plate_with_hole(12.0)
    open_plate.faces = open_plate.faces[:-1]
    open_plate.export(tmp_path / "plate.stl")
    as_surface = plan(load_scenario(tmp_path / "s.yaml"), progress=False)
    assert as_surface.found and not as_surface.report["scenario"]["obstacles"][0]["kind"] \
        == "solid"
    text = (tmp_path / "s.yaml").read_text()
    (tmp_path / "s.yaml").write_text(text.replace("mesh: plate.stl}",
                                                  "mesh: plate.stl, kind: solid}"))
    r = subprocess.run([sys.executable, "-m", "planner", "plan", str(tmp_path / "s.yaml"),
                        "--out", str(tmp_path / "o"), "--exact", "true"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "plate" in r.stderr
    assert not (tmp_path / "o" / "path.json").exists()
