"""Assembly sequencing (planner.assembly): the demos' outcomes, every path re-validated
by FCL at the assembly's contact tolerance, and one-line schema errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from planner.assembly import (
    assemble_command,
    load_assembly,
    parse_assembly,
    plan_assembly,
)
from planner.errors import ScenarioError
from planner.validation import FclChecker

DEMOS = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies"


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("MINKPLAN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "dec"))


def _revalidate(result) -> None:
    """Replay the removal: each path, checked by a fresh FclChecker against the parts
    still present, at the result's contact tolerance; insertion = removal reversed."""
    parts = {p.name: p for p in result.assembly.parts}
    present = set(parts)
    for step in result.removal:
        present.discard(step.part)
        assert sorted(step.obstacles) == sorted(present)
        checker = FclChecker(parts[step.part].mesh, [parts[n].mesh for n in step.obstacles],
                             contact_tolerance=result.contact_tolerance)
        assert checker.check_path(step.removal).valid, step.part
        assert checker.check_path(step.insertion).valid, step.part
        np.testing.assert_array_equal(step.removal[0], np.zeros(3))
        # the part ends outside the box of the remaining parts (its own included)
        if step.obstacles:
            names = [step.part, *step.obstacles]
            lo = np.min([parts[n].mesh.bounds[0] for n in names], axis=0)
            hi = np.max([parts[n].mesh.bounds[1] for n in names], axis=0)
            p_lo, p_hi = parts[step.part].mesh.bounds + step.removal[-1]
            assert np.any(p_lo > hi) or np.any(p_hi < lo), step.part


def test_peg_in_block():
    result = plan_assembly(load_assembly(DEMOS / "peg_in_block.yaml"))
    assert result.found and result.exit_code == 0
    assert result.order == ["block", "peg"]
    (step,) = result.removal
    assert (step.method, step.direction) == ("straight", "+z")
    _revalidate(result)


def test_pegs_and_holes_mate_along_z():
    result = plan_assembly(load_assembly(DEMOS / "pegs_and_holes.yaml"))
    assert result.order == ["lower", "upper"]
    (step,) = result.removal
    assert step.direction == "+z"
    _revalidate(result)


def test_latched_box_needs_a_planned_removal():
    result = plan_assembly(load_assembly(DEMOS / "latched_box.yaml"))
    assert result.found, result.message
    assert len(result.order) == 7 and result.order[0] == "floor"
    methods = {s.part: s.method for s in result.removal}
    assert "planned" in methods.values()
    assert result.order.index("lid") < result.order.index("latch")
    planned = next(s for s in result.removal if s.method == "planned")
    assert len(planned.removal) > 2  # not a straight line
    _revalidate(result)


def test_linked_rings_are_interlocked(tmp_path, capsys):
    code = assemble_command(DEMOS / "linked_rings.yaml", tmp_path / "out", progress=False)
    assert code == 1
    sequence = json.loads((tmp_path / "out" / "sequence.json").read_text())
    assert sequence["status"] == "interlocked"
    assert sequence["interlocked"] == ["ring_a", "ring_b"]
    assert sequence["parts"] == []
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert all(report["attempts"][n]["proved"] for n in ("ring_a", "ring_b"))
    assert "ring_a, ring_b" in capsys.readouterr().out


def test_cli_writes_sequence(tmp_path):
    code = assemble_command(DEMOS / "pegs_and_holes.yaml", tmp_path, progress=False)
    assert code == 0
    sequence = json.loads((tmp_path / "sequence.json").read_text())
    assert [p["part"] for p in sequence["parts"]] == ["lower", "upper"]
    upper = sequence["parts"][1]
    assert upper["insertion"][-1] == [0.0, 0.0, 0.0]
    assert upper["validation"]["valid"]
    assert sequence["contact_tolerance"] == pytest.approx(
        1e-4 * np.linalg.norm([2.0, 1.0, 0.9]))


def test_contact_tolerance_is_used_everywhere():
    text = (DEMOS / "peg_in_block.yaml").read_text() + "contact_tolerance: 0.001\n"
    assembly = parse_assembly(text, DEMOS)
    assert assembly.contact_tolerance == 0.001
    assert assembly.settings.contact_tolerance == 0.001
    result = plan_assembly(assembly)
    assert result.sequence_json()["contact_tolerance"] == 0.001
    assert result.removal[0].validation["contact_tolerance"] == 0.001


@pytest.mark.parametrize("text, expected", [
    ("parts: []\n", "<assembly>:1: parts: expected a non-empty list"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\nbase: b\n", "<assembly>:3: base: 'b' is not"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\nbsae: a\n", "<assembly>:3: bsae: unknown key; "
                                                         "did you mean 'base'?"),
    ("parts:\n  - {name: a, mesh: nope.stl}\n", "<assembly>:2: parts[0].mesh: file 'nope.stl'"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\n  - {name: b, box: [1, 1, 1]}\n",
     "<assembly>:2: parts[0]: part 'a' collides with 'b'"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\ncontact_tolerance: -1\n",
     "<assembly>:3: contact_tolerance: must be >= 0"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\ncontact_tolerance: 0.1\n"
     "planner: {contact_tolerance: 0.2}\n", "<assembly>:4: planner.contact_tolerance: "),
])
def test_schema_errors_are_one_line(text, expected):
    with pytest.raises(ScenarioError) as info:
        parse_assembly(text, DEMOS)
    message = str(info.value)
    assert message.startswith(expected), message
    assert "\n" not in message


def test_a_scenario_is_not_an_assembly():
    with pytest.raises(ScenarioError, match=r"peg_in_hole.yaml:6: robot: this looks like"):
        load_assembly(DEMOS.parent / "peg_in_hole.yaml")


def test_missing_file_is_a_scenario_error(tmp_path):
    with pytest.raises(ScenarioError, match="assembly file not found"):
        load_assembly(tmp_path / "none.yaml")


def test_positions_and_primitives():
    """Primitive parts with positions: a box on a box leaves straight up."""
    assembly = parse_assembly(
        "base: bottom\nparts:\n"
        "  - {name: bottom, box: [1, 1, 1]}\n"
        "  - {name: top, box: [0.5, 0.5, 0.5], position: [0, 0, 0.75]}\n", DEMOS)
    result = plan_assembly(assembly)
    assert result.order == ["bottom", "top"]
    assert result.removal[0].direction == "+z"
    _revalidate(result)


def _tilted_tube(tmp_path: Path) -> Path:
    """A peg resting on the cap of a closed-bottom tube (gap 0.05), both tilted 30° about
    y: only the tube's axis, a contact-normal direction, lets it out straight."""
    import trimesh

    def box(lo, hi):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        return trimesh.creation.box(extents=hi - lo,
                                    transform=trimesh.transformations.translation_matrix(
                                        (lo + hi) / 2))

    tube = trimesh.util.concatenate([
        box([-0.35, -0.35, -0.2], [0.35, 0.35, 0.0]),
        box([-0.35, -0.35, -0.1], [-0.25, 0.35, 2.0]),
        box([0.25, -0.35, -0.1], [0.35, 0.35, 2.0]),
        box([-0.3, -0.35, -0.1], [0.3, -0.25, 2.0]),
        box([-0.3, 0.25, -0.1], [0.3, 0.35, 2.0]),
    ])
    tube.export(tmp_path / "tube.stl")
    box([-0.2, -0.2, 0.0], [0.2, 0.2, 1.0]).export(tmp_path / "peg.stl")
    path = tmp_path / "tilted.yaml"
    path.write_text(
        "base: tube\nplanner: {time_limit: 10}\nparts:\n"
        "  - {name: tube, mesh: tube.stl, orientation: {axis: [0, 1, 0], angle_deg: 30}}\n"
        "  - {name: peg, mesh: peg.stl, orientation: {axis: [0, 1, 0], angle_deg: 30}}\n")
    return path


def test_contact_normal_direction(tmp_path):
    result = plan_assembly(load_assembly(_tilted_tube(tmp_path)), plan_parts=False)
    assert result.found, result.message
    (step,) = result.removal
    assert step.method == "straight" and step.direction.startswith("[")
    direction = step.removal[-1] / np.linalg.norm(step.removal[-1])
    np.testing.assert_allclose(direction, [0.5, 0.0, np.sqrt(3) / 2], atol=1e-6)
    _revalidate(result)


def test_html_animation_and_benchmark(tmp_path):
    from planner.assembly import benchmark_removals, scene_for_assembly

    result = plan_assembly(load_assembly(DEMOS / "peg_in_block.yaml"))
    scene = scene_for_assembly(result)
    assert {"assembly/block", "assembly/peg"} <= set(scene.paths())
    (track,) = scene.tracks
    assert track.path == "assembly/peg"
    np.testing.assert_array_equal(track.positions[-1], np.zeros(3))
    assert assemble_command(DEMOS / "peg_in_block.yaml", tmp_path, html=True) == 0
    assert (tmp_path / "assembly.html").stat().st_size > 10_000
    rows = benchmark_removals(result, planners=("minkplan", "ompl:RRTConnect"))
    assert [(r["planner"], r["status"], r["valid"]) for r in rows] == [
        ("minkplan", "found", True), ("ompl:RRTConnect", "found", True)]
