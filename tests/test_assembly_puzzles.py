"""Interlocking puzzles and interference fits (planner.assembly): the six-piece burr
(a key piece first, a planned step, every step replayed by FCL; with the key held fixed
the rest is proved interlocked), the three-piece burr whose first move is a pair, and
assembled parts that overlap a little, refused unless an interference tolerance at least
that deep is asked for (in the file or with ``assemble --interference``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from shapes import roofed_channel
from test_assembly import _box, _revalidate

from planner.assembly import plan_assembly, removal_problems
from planner.cli import main
from planner.errors import ScenarioError
from planner.io import load_assembly
from planner.validation import FclChecker

DEMOS = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies"


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("MINKPLAN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "dec"))


# ---------------------------------------------------------------- burrs


def test_six_piece_burr_comes_apart_key_first():
    assembly = load_assembly(DEMOS / "six_piece_burr.yaml")
    assert len(assembly.parts) == 6
    for part in assembly.parts:  # one closed solid per stick, about 200-350 triangles
        assert part.solid and part.mesh.is_watertight and 200 <= len(part.mesh.faces) <= 400
    result = plan_assembly(assembly)
    assert result.found, result.message
    assert len(result.removal) == 5 and not any(s.members for s in result.removal)
    first, second = result.removal[:2]
    assert (first.part, first.method, first.direction) == ("x1", "straight", "+x")
    assert (second.part, second.method) == ("z1", "planned") and len(second.removal) > 2
    assert result.source["used"] == "exact" and result.reuse["decompositions"] == 0
    # z1's planned removal took the reduced convolutions of its four pairs from the cache
    assert len(second.obstacles) == 4 and result.reuse["cspace_pairs_reused"] == 4
    _revalidate(result)


def test_a_cspace_takes_a_pair_sum_only_of_the_same_meshes():
    """Reusing a pair's reduced convolution gives the C-space computed afresh, leaf for
    leaf; a sum of other meshes is not taken."""
    from planner.sources import ExactSource, SourceSettings  # noqa: PLC0415

    assembly = load_assembly(DEMOS / "six_piece_burr.yaml")
    parts = {p.name: p for p in assembly.parts}
    robot, obstacles = parts["z1"], [parts["x0"], parts["y0"]]
    lo = np.min([o.mesh.bounds[0] for o in obstacles], axis=0) - robot.mesh.bounds[1]
    hi = np.max([o.mesh.bounds[1] for o in obstacles], axis=0) - robot.mesh.bounds[0]
    bounds = np.stack([lo, hi])
    side = float(np.max(hi - lo))
    settings = SourceSettings(exact=True)
    fresh = ExactSource(settings, "test").cspace(obstacles, robot, bounds, side / 512,
                                                 side / 32)
    source = ExactSource(settings, "test")
    source.pair(parts["x0"], robot)  # the pair in the C-space
    source.pair(parts["y0"], parts["x1"])  # another robot: not the C-space's pair
    reusing = source.cspace(obstacles, robot, bounds, side / 512, side / 32)
    assert reusing.reused == [True, False] and source.pairs_reused == 1
    a, b = fresh.leaves(), reusing.leaves()
    assert set(a) == set(b)
    for key in a:
        assert np.array_equal(np.asarray(a[key]), np.asarray(b[key])), key


def test_six_piece_burr_is_interlocked_while_the_key_is_in():
    """With the key x1 held fixed, no other piece can leave: each proved by a
    certificate (so the puzzle is a genuine interlock, not a loose pile)."""
    assembly = load_assembly(DEMOS / "six_piece_burr.yaml")
    held = dataclasses.replace(assembly, base="x1")
    result = plan_assembly(held, groups=False, minimize=False)
    assert not result.found
    assert result.stuck == ["x0", "y0", "y1", "z0", "z1"]
    assert result.proved
    for name in result.stuck:
        assert result.attempts[name]["status"] == "no_path", name


def test_three_piece_burr_first_move_is_a_pair():
    result = plan_assembly(load_assembly(DEMOS / "three_piece_burr.yaml"))
    assert result.found, result.message
    first = result.removal[0]
    assert first.method == "group" and first.members == ("x", "y")
    assert first.obstacles == ["z"]
    assert len(first.inner) == 1  # and the pair comes apart on its own
    assert result.order[0] == "z"
    _revalidate(result)
    # the benchmark's problems: the group's step, then its own step among its members
    (inner,) = first.inner
    assert [(p["part"], p["method"], p["obstacles"]) for p in removal_problems(result)] == [
        ("[x + y]", "group", ["z"]), (inner.part, inner.method, list(inner.obstacles))]
    # one part at a time, neither x nor y can leave (x proved by a certificate; y's
    # play is walled by C-obstacles of x and z that meet face to face, seams the octree
    # leaves MIXED down to its floor, so y's is not proved)
    alone = plan_assembly(load_assembly(DEMOS / "three_piece_burr.yaml"), groups=False,
                          minimize=False)
    assert not alone.found and alone.stuck == ["x", "y"]
    assert alone.attempts["x"]["status"] == "no_path" and alone.attempts["x"]["proved"]
    assert alone.attempts["y"]["status"] in ("no_path", "not_found")


# ---------------------------------------------------------------- interference


def _press_fit(tmp_path: Path, interference: float | None = None) -> Path:
    """A cap pressed 0.02 deep into a block (an interference fit)."""
    path = tmp_path / "press_fit.yaml"
    text = "name: press_fit\n"
    if interference is not None:
        text += f"interference: {interference}\n"
    path.write_text(text + "parts:\n  - {name: block, box: [2, 2, 2]}\n"
                    "  - {name: cap, box: [1, 1, 1], position: [0, 0, 1.48]}\n")
    return path


def test_an_overlap_is_refused_without_an_interference_tolerance(tmp_path):
    with pytest.raises(ScenarioError) as info:
        load_assembly(_press_fit(tmp_path))
    message = str(info.value)
    assert "part 'cap' collides with 'block'" in message
    assert "penetration depth in [0.02" in message and "along (0, 0, 1)" in message
    # the depth's upper bound less what the contact tolerance already allows, rounded up;
    # and that interference accepts the pose
    suggested = info.value.details["overlap"]["suggested_interference"]
    assert "interference: 0.021 or more" in message and suggested == 0.021
    assert load_assembly(_press_fit(tmp_path, suggested)).overlaps


def test_an_interference_tolerance_short_of_the_overlap_still_refuses(tmp_path):
    with pytest.raises(ScenarioError) as info:
        load_assembly(_press_fit(tmp_path, 0.01))
    message = str(info.value)
    assert "+ interference 0.01" in message and "penetration depth in [0.02" in message
    assert info.value.details["overlap"]["interference"] == 0.01


def test_an_interference_tolerance_plans_the_overlapping_pair(tmp_path):
    assembly = load_assembly(_press_fit(tmp_path, 0.03))
    assert assembly.interference == 0.03
    assert assembly.tolerance == pytest.approx(assembly.contact_tolerance + 0.03)
    assert assembly.settings.contact_tolerance == pytest.approx(assembly.tolerance)
    (overlap,) = assembly.overlaps
    assert (overlap["part"], overlap["other"]) == ("cap", "block")  # the cap moves
    assert overlap["penetration_depth"]["lower"] == pytest.approx(0.02, abs=1e-6)
    assert overlap["penetration_depth"]["direction"] == pytest.approx([0.0, 0.0, 1.0])
    result = plan_assembly(assembly)
    assert result.found and result.order == ["block", "cap"]
    (step,) = result.removal
    assert step.direction == "+z"
    assert step.validation["tolerance"] == pytest.approx(assembly.tolerance)
    _revalidate(result)  # FCL, allowing the contact plus the interference tolerance
    # ... and no more: the start is invalid at the contact tolerance alone
    parts = {p.name: p for p in assembly.parts}
    strict = FclChecker(parts["cap"].mesh, [parts["block"].mesh],
                        contact_tolerance=assembly.contact_tolerance)
    assert not strict.is_valid(np.zeros(3))
    report = result.report_json()
    assert report["interference"] == 0.03 and len(report["overlaps"]) == 1
    assert result.sequence_json()["tolerance"] == pytest.approx(assembly.tolerance)


def test_an_interfering_slider_is_planned_out_of_its_channel(tmp_path):
    """The planner starts from an overlapping pose: a slider pressed 0.02 into the floor
    of a roofed channel must climb over a low stop (no straight exit)."""
    roofed_channel().export(tmp_path / "tunnel.stl")
    _box([-0.6, -0.25, 0.18], [0.2, 0.25, 0.33]).export(tmp_path / "slider.stl")
    path = tmp_path / "tunnel.yaml"
    path.write_text("base: tunnel\ninterference: 0.025\nplanner: {time_limit: 20}\n"
                    "parts:\n  - {name: tunnel, mesh: tunnel.stl}\n"
                    "  - {name: slider, mesh: slider.stl}\n")
    result = plan_assembly(load_assembly(path))
    assert result.found, result.message
    (step,) = result.removal
    assert step.method == "planned" and len(step.removal) > 2
    _revalidate(result)


def test_cli_interference_option(tmp_path, capsys):
    path = _press_fit(tmp_path)
    assert main(["assemble", str(path), "--out", str(tmp_path / "no"), "--no-progress"]) == 2
    refused = json.loads((tmp_path / "no" / "report.json").read_text())
    assert refused["overlap"]["penetration_depth"]["lower"] == pytest.approx(0.02, abs=1e-6)
    capsys.readouterr()
    assert main(["assemble", str(path), "--out", str(tmp_path / "yes"), "--no-progress",
                 "--interference", "0.03"]) == 0
    out = capsys.readouterr().out
    assert "interference 0.03: 1 overlapping pair(s) accepted" in out
    report = json.loads((tmp_path / "yes" / "report.json").read_text())
    assert report["interference"] == 0.03 and report["overlaps"][0]["part"] == "cap"
    # the option replaces the file's value
    assert main(["assemble", str(_press_fit(tmp_path, 0.03)), "--out",
                 str(tmp_path / "less"), "--no-progress", "--interference", "0.01"]) == 2
    assert main(["assemble", str(path), "--out", str(tmp_path / "bad"), "--no-progress",
                 "--interference", "-1"]) == 2
    assert "--interference: must be a finite number >= 0" in capsys.readouterr().err


def test_the_advice_names_where_the_interference_is_set(tmp_path, capsys):
    """The suggested tolerance is advised where the one in force was set: the file's
    field (which ``minkplan batch`` reads too: it has no ``--interference``), or the
    option when the command line gave it (it replaces the file's)."""
    path = _press_fit(tmp_path, 0.01)
    assert main(["assemble", str(path), "--out", str(tmp_path / "file"),
                 "--no-progress"]) == 2
    in_file = capsys.readouterr().err
    assert "give interference: 0.021 or more in the assembly file" in in_file
    assert "--interference" not in in_file
    assert main(["assemble", str(path), "--out", str(tmp_path / "option"), "--no-progress",
                 "--interference", "0.01"]) == 2
    on_line = capsys.readouterr().err
    assert "give --interference 0.021 or more" in on_line
    assert "assembly file" not in on_line
