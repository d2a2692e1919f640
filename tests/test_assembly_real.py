"""Real assemblies (../shared/assets/assemblies, NVIDIA Factory) and the local enclosure
proof (planner.assembly.enclosure): Factory's M12 nut on its threaded bolt cannot be
undone by translations, and that is proved, not timed out; a part shut in a closed box
is proved enclosed without a search of the whole exit box."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from shapes import box

from planner.assembly import plan_assembly
from planner.assembly.enclosure import prove_enclosed
from planner.cli import main
from planner.errors import ScenarioError
from planner.io import load_assembly
from planner.sources import choose_for
from planner.validation import FclChecker

ASSETS = Path(__file__).resolve().parents[1].parent / "shared" / "assets" / "assemblies"
NUT_BOLT = ASSETS / "factory_nut_bolt_m12" / "factory_nut_bolt_m12.yaml"
NUT_INTERFERENCE = 0.0016
"""The nut rests on the bolt's head 1.55-1.70 mm below a pose its thread fits (FCL); an
interference tolerance of 1.6 mm accepts that assembled pose."""

needs_assets = pytest.mark.skipif(not ASSETS.is_dir(),
                                  reason=f"{ASSETS} is absent (the shared real assets)")


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("MINKPLAN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "dec"))


@needs_assets
def test_the_nut_pose_overlaps_the_thread_and_is_refused_without_a_tolerance():
    with pytest.raises(ScenarioError) as info:
        load_assembly(NUT_BOLT)
    message = str(info.value)
    assert "\n" not in message and "factory_nut_bolt_m12.yaml" in message
    assert "part 'nut' collides with 'bolt'" in message  # the bolt is the base
    # the nut is a surface (no penetration depth): the smallest tolerance FCL's check
    # accepts is searched for and suggested, and that tolerance loads the assembly
    assert "no penetration depth (a surface has no inside)" in message
    suggested = info.value.details["overlap"]["suggested_interference"]
    assert f"give interference: {suggested:g} " in message
    assert 0.0015 <= suggested <= 0.0017
    assert load_assembly(NUT_BOLT, interference=suggested).overlaps


@needs_assets
def test_the_nut_comes_off_within_the_interference_it_was_given(tmp_path, capsys):
    """With the interference tolerance that accepts the assembled pose, a penetration up
    to it counts as contact everywhere: the nut lifts straight off its thread (every pose
    of the lift lies within 1.6 mm of a free one, one every 1.75 mm pitch), each pose
    validated by FCL with a witness no longer than the tolerance."""
    assembly = load_assembly(NUT_BOLT, interference=NUT_INTERFERENCE)
    assert [(o["part"], o["other"]) for o in assembly.overlaps] == [("nut", "bolt")]
    result = plan_assembly(assembly)
    assert result.found and result.order == ["bolt", "nut"], result.message
    (step,) = result.removal
    assert step.part == "nut" and step.validation["valid"]
    assert step.validation["tolerance"] == pytest.approx(assembly.tolerance)
    sequence = result.sequence_json()
    assert sequence["interference"] == NUT_INTERFERENCE
    assert sequence["overlaps"][0]["part"] == "nut"
    # a larger allowance accepts what a smaller one did
    assert load_assembly(NUT_BOLT, interference=2 * NUT_INTERFERENCE).overlaps
    # the command line says the same, with exit code 0
    code = main(["assemble", str(NUT_BOLT), "--out", str(tmp_path), "--no-progress",
                 "--interference", str(NUT_INTERFERENCE)])
    assert code == 0
    out = capsys.readouterr().out
    assert "assembly order: bolt -> nut" in out and "interference 0.0016" in out


@needs_assets
def test_the_nut_on_the_bolt_is_proved_stuck_without_penetration():
    """Without penetration the nut cannot leave its thread by translation: stepped out of
    its overlap to a free pose up the thread, its free component is walled off by
    verified FULL cells of the bolt's C-obstacle within a fraction of a millimetre."""
    assembly = load_assembly(NUT_BOLT, interference=NUT_INTERFERENCE)
    parts = {p.name: p for p in assembly.parts}
    source = choose_for(assembly.parts, assembly.settings)
    proof = prove_enclosed(source, parts["nut"], [parts["bolt"]], delta=assembly.tolerance,
                           diagonal=assembly.diagonal, deadline=time.perf_counter() + 120)
    assert proof is not None and proof["exact"]
    assert set(proof["wall_cells_by_obstacle"]) == {"bolt"}
    # the proof starts at a pose that is free, no farther than the tolerance from the
    # assembled one
    start = np.asarray(proof["start"])
    assert 0 < np.linalg.norm(start) <= assembly.tolerance
    assert not FclChecker.for_parts(parts["nut"], [parts["bolt"]]).collides(start)
    assert "no penetration on the way" in proof["claim"] and "not covered" in proof["claim"]
    assert proof["half_size"] < 0.01 * assembly.diagonal


@needs_assets
def test_industreal_gears_come_off_the_base_each_step_validated():
    """IndustReal's gear base with three gears (5k and 21k-51k triangles a part): each
    gear lifts off its shaft, every step validated by FCL at the contact tolerance; and
    the planner, asked for one gear's removal alone, finds it as a direct motion (its
    whole-bounds C-space would pass the facet budget)."""
    from planner.assembly import removal_scenario  # noqa: PLC0415
    from planner.planning import plan  # noqa: PLC0415

    assembly = load_assembly(ASSETS / "industreal_gears" / "industreal_gears.yaml")
    result = plan_assembly(assembly)
    assert result.found, result.message
    assert sorted(s.part for s in result.removal) == ["gear_large", "gear_medium",
                                                       "gear_small"]
    for step in result.removal:
        assert step.validation["valid"], step
        checker = FclChecker.for_parts(
            {p.name: p for p in assembly.parts}[step.part],
            [p for p in assembly.parts if p.name in step.obstacles],
            contact_tolerance=assembly.tolerance)
        assert checker.check_path(np.asarray(step.removal)).valid
    scenario = removal_scenario(assembly, "gear_medium", ["gear_base"], "+z")
    outcome = plan(scenario, progress=False)
    assert outcome.status == "found" and outcome.reason == "direct", outcome.message
    assert outcome.validation["valid"]


def _shut_box(tmp_path: Path, slot: float) -> Path:
    """A cube of 1.9 in a closed box (the base: six walls 0.2 thick around a hollow of 2,
    one part), free to move by 0.05 or so either way but not out; ``slot``: a slot of that
    width across the roof (0: none)."""
    walls = [((-1.2, -1.2, -1.2), (1.2, 1.2, -1.0)), ((-1.2, -1.2, -1.0), (-1.0, 1.2, 1.0)),
             ((1.0, -1.2, -1.0), (1.2, 1.2, 1.0)), ((-1.0, -1.2, -1.0), (1.0, -1.0, 1.0)),
             ((-1.0, 1.0, -1.0), (1.0, 1.2, 1.0))]
    if slot:
        walls += [((-1.2, -1.2, 1.0), (-slot / 2, 1.2, 1.2)),
                  ((slot / 2, -1.2, 1.0), (1.2, 1.2, 1.2))]
    else:
        walls += [((-1.2, -1.2, 1.0), (1.2, 1.2, 1.2))]
    shell = trimesh.util.concatenate([box(np.subtract(hi, lo), np.add(hi, lo) / 2)
                                      for lo, hi in walls])
    shell.export(tmp_path / f"shell_{slot}.stl")
    path = tmp_path / f"shut_{slot}.yaml"
    path.write_text(f"base: shell\nplanner: {{time_limit: 20}}\nparts:\n"
                    f"  - {{name: shell, mesh: shell_{slot}.stl}}\n"
                    f"  - {{name: cube, box: [1.9, 1.9, 1.9], position: [0, 0, -0.04]}}\n")
    return path


def test_a_cube_shut_in_a_box_is_proved_enclosed(tmp_path):
    assembly = load_assembly(_shut_box(tmp_path, 0.0))
    parts = {p.name: p for p in assembly.parts}
    source = choose_for(assembly.parts, assembly.settings)
    proof = prove_enclosed(source, parts["cube"], [parts["shell"]], delta=assembly.tolerance,
                           diagonal=assembly.diagonal, deadline=time.perf_counter() + 60)
    assert proof is not None and proof["exact"]
    assert proof["start"] == [0.0, 0.0, 0.0]  # free as assembled
    # walled by the shell alone, none of the cells a wall of the proof's box
    assert proof["wall_cells"] > 0 and set(proof["wall_cells_by_obstacle"]) == {"shell"}
    assert proof["half_size"] >= 0.05  # the cube's play fits in the proof's box
    result = plan_assembly(assembly)
    assert not result.found and result.proved
    assert result.interlocked == ["cube", "shell"]
    assert result.core_attempts["cube"]["reason"] == "enclosure"
    assert result.reuse["planner_runs"] == 0


def test_a_cube_under_a_slotted_roof_is_not_claimed_enclosed(tmp_path):
    """With a slot in the roof wider than the cube, it can leave: no enclosure is
    claimed, and it is taken out."""
    assembly = load_assembly(_shut_box(tmp_path, 2.0))
    parts = {p.name: p for p in assembly.parts}
    source = choose_for(assembly.parts, assembly.settings)
    assert prove_enclosed(source, parts["cube"], [parts["shell"]], delta=assembly.tolerance,
                          diagonal=assembly.diagonal,
                          deadline=time.perf_counter() + 60) is None
    result = plan_assembly(assembly)
    assert result.found and result.order == ["shell", "cube"], result.message


def test_a_peg_pushed_aslant_into_its_bore_is_accepted_within_its_depth(tmp_path):
    """Factory's round peg moved (0.3, 0.2) mm into the wall of its hole: the way out
    is aslant, along no contact normal FCL gives and no axis, so FCL's tolerance check
    found no witness at any interference. The penetration depth's direction is now tried
    first: the pose is refused with the depth's bound as the suggestion, and that
    interference accepts it and plans the peg out."""
    from conftest import asset

    folder = "assemblies/factory_round_peg_8mm/meshes/"
    path = tmp_path / "aslant.yaml"
    path.write_text(
        "name: aslant\nunits: m\nbase: hole\nparts:\n"
        f"  - {{name: hole, mesh: {asset(folder + 'factory_round_hole_8mm_subdiv_3x.obj')}}}\n"
        f"  - {{name: peg, mesh: {asset(folder + 'factory_round_peg_8mm_loose.obj')}, "
        "position: [0.0003, 0.0002, 0]}\n")
    with pytest.raises(ScenarioError) as info:
        load_assembly(path)
    overlap = info.value.details["overlap"]
    depth = overlap["penetration_depth"]
    assert 0.00025 < depth["lower"] <= depth["upper"] < 0.00035
    suggested = overlap["suggested_interference"]
    assert suggested is not None and depth["upper"] <= suggested < 1.1 * depth["upper"]
    assembly = load_assembly(path, interference=suggested)
    result = plan_assembly(assembly)
    assert result.found and result.order == ["hole", "peg"], result.message
    # a tolerance inside the depth's interval: the depth is found again finer, and its
    # direction frees the peg within that tolerance (the first interval was too coarse)
    between = 0.0003
    assert depth["lower"] < between + assembly.contact_tolerance < depth["upper"]
    tight = load_assembly(path, interference=between)
    (fit,) = tight.overlaps
    assert fit["penetration_depth"]["upper"] < tight.tolerance
    assert fit["penetration_depth"]["lower"] >= depth["lower"]
