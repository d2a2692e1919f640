"""Assembly sequencing (planner.assembly): the demos' outcomes, every path re-validated
by FCL at the assembly's contact tolerance, one-line schema errors, per-pair C-obstacle
reuse, irreducible interlocked sets and planned removals towards any side."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from benchmarks.removals import benchmark_removals
from shapes import roofed_channel

import planner.sources as sources_module
from planner.assembly import (
    DIRECTIONS,
    PairCache,
    plan_assembly,
    removal_problems,
    removal_scenario,
)
from planner.cli import main
from planner.errors import InvalidParameterError, ScenarioError
from planner.io import load_assembly, parse_assembly
from planner.validation import FclChecker

DEMOS = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies"


@pytest.fixture(autouse=True)
def _cache(tmp_path_factory, monkeypatch):
    monkeypatch.setenv("MINKPLAN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "dec"))


def _revalidate(result) -> None:
    """Replay the removal: each path, checked by a fresh FclChecker against the parts
    still present, at the result's contact tolerance (plus its interference tolerance,
    if one was given); insertion = removal reversed."""
    parts = {p.name: p for p in result.assembly.parts}
    _replay(result.removal, parts, set(parts), result.assembly.tolerance)


def _replay(steps, parts, present: set[str], delta: float) -> None:
    """Each step's moving parts (one, or a group's members moving as one) checked by FCL
    against the parts still present; a group's own steps replayed among its members."""
    for step in steps:
        present -= set(step.parts)
        assert sorted(step.obstacles) == sorted(present)
        for name in step.parts:
            checker = FclChecker(parts[name].mesh, [parts[n].mesh for n in step.obstacles],
                                 contact_tolerance=delta)
            assert checker.check_path(step.removal).valid, name
            assert checker.check_path(step.insertion).valid, name
        np.testing.assert_array_equal(step.removal[0], np.zeros(3))
        # the moving parts end outside the box of the remaining parts (theirs included)
        if step.obstacles:
            names = [*step.parts, *step.obstacles]
            lo = np.min([parts[n].mesh.bounds[0] for n in names], axis=0)
            hi = np.max([parts[n].mesh.bounds[1] for n in names], axis=0)
            p_lo = np.min([parts[n].mesh.bounds[0] for n in step.parts], axis=0)
            p_hi = np.max([parts[n].mesh.bounds[1] for n in step.parts], axis=0)
            p_lo, p_hi = p_lo + step.removal[-1], p_hi + step.removal[-1]
            assert np.any(p_lo > hi) or np.any(p_hi < lo), step.part
        if step.members:
            _replay(step.inner, parts, set(step.members), delta)


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
    code = main(["assemble", str(DEMOS / "linked_rings.yaml"), "--out", str(tmp_path / "out"),
                 "--no-progress"])
    assert code == 1
    sequence = json.loads((tmp_path / "out" / "sequence.json").read_text())
    assert sequence["status"] == "interlocked"
    assert sequence["interlocked"] == ["ring_a", "ring_b"]
    assert sequence["stuck"] == ["ring_a", "ring_b"]
    assert sequence["parts"] == [] and sequence["proved"]
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert all(report["attempts"][n]["proved"] for n in ("ring_a", "ring_b"))
    assert report["interlocked_attempts"]["ring_a"]["obstacles"] == ["ring_b"]
    assert "ring_a, ring_b" in capsys.readouterr().out


def test_a_pair_that_no_part_of_can_leave_alone_leaves_as_a_subassembly(tmp_path):
    assembly = load_assembly(DEMOS / "hooked_pair.yaml")
    alone = plan_assembly(assembly, groups=False)
    # one part at a time, the cup takes part in the lock: without it the hooks come apart
    assert not alone.found and alone.proved
    assert alone.interlocked == ["cup", "hook_a", "hook_b"]
    result = plan_assembly(assembly)
    assert result.found, result.message
    (step,) = result.removal
    assert (step.method, step.direction, step.members) == ("group", "+z",
                                                           ("hook_a", "hook_b"))
    assert step.obstacles == ["cup"] and len(step.inner) == 1
    assert result.order == ["cup", "[hook_a + hook_b]"]
    assert "put together first: hook_a -> hook_b" in result.message
    _revalidate(result)
    main(["assemble", str(DEMOS / "hooked_pair.yaml"), "--out", str(tmp_path),
          "--no-progress"])
    group = json.loads((tmp_path / "sequence.json").read_text())["parts"][1]
    assert group["group"] == ["hook_a", "hook_b"]
    assert [p["part"] for p in group["subassembly"]] == ["hook_a", "hook_b"]


def test_rings_leave_the_tray_together_and_are_interlocked_with_each_other():
    result = plan_assembly(load_assembly(DEMOS / "rings_in_tray.yaml"))
    assert not result.found and result.proved
    assert result.interlocked == ["ring_a", "ring_b"]
    (step,) = result.removal
    assert step.members == ("ring_a", "ring_b") and step.obstacles == ["tray"]
    assert step.inner == [] and "they leave the rest together" in result.message
    _replay(result.removal, {p.name: p for p in result.assembly.parts},
            {p.name for p in result.assembly.parts}, result.contact_tolerance)


def test_cli_writes_sequence(tmp_path):
    code = main(["assemble", str(DEMOS / "pegs_and_holes.yaml"), "--out", str(tmp_path),
                 "--no-progress"])
    assert code == 0
    sequence = json.loads((tmp_path / "sequence.json").read_text())
    assert [p["part"] for p in sequence["parts"]] == ["lower", "upper"]
    upper = sequence["parts"][1]
    assert upper["insertion"][-1] == [0.0, 0.0, 0.0]
    assert upper["validation"]["valid"]
    assert sequence["contact_tolerance"] == pytest.approx(
        1e-4 * np.linalg.norm([2.0, 1.0, 0.9]))


def _frame_with_peg(tmp_path: Path, peg_lines: str, header: str = "") -> Path:
    """A square frame of four boxes (a 1.02 x 1.02 hole) and the given pegs."""
    import trimesh

    walls = [((0.49, 2.0, 1.0), (0.755, 0, 0)), ((0.49, 2.0, 1.0), (-0.755, 0, 0)),
             ((1.02, 0.49, 1.0), (0, 0.755, 0)), ((1.02, 0.49, 1.0), (0, -0.755, 0))]
    frame = trimesh.util.concatenate([trimesh.creation.box(e).apply_translation(c)
                                      for e, c in walls])
    frame.export(tmp_path / "frame.stl")
    path = tmp_path / "frame.yaml"
    path.write_text(f"{header}parts:\n  - {{name: frame, mesh: frame.stl}}\n{peg_lines}")
    return path


def test_an_overlap_within_the_tolerance_whose_way_out_is_aslant_is_accepted(tmp_path):
    """A peg pushed 0.006 into the corner of its frame overlaps two walls: along no axis
    and no contact normal does 0.01 free it, diagonally 0.0085 does (its penetration
    depth). Within a contact tolerance of 0.01 the pose is valid: the depth's direction
    is tried, accepts it, and stays with both parts as their escape hint."""
    path = _frame_with_peg(tmp_path, "  - {name: peg, box: [1, 1, 1], "
                                     "position: [0.016, 0.016, 0]}\n",
                           header="contact_tolerance: 0.01\n")
    assembly = load_assembly(path)
    frame, peg = assembly.parts
    (hint,) = peg.escape_hints
    assert hint == pytest.approx((-2 ** -0.5, -2 ** -0.5, 0.0), abs=1e-3)
    assert frame.escape_hints == (tuple(-x for x in hint),)
    without = FclChecker(peg.mesh, [frame.mesh], contact_tolerance=0.01)
    assert not without.is_valid(np.zeros(3))  # the axes and normals alone: refused


def test_each_pair_is_checked_on_its_own_in_the_assembled_pose(tmp_path):
    """A key pushed 0.01 sideways into two stacked blocks that touch face to face: each
    pair overlaps within the interference, but no one translation frees the lower
    block from the upper (it touches) and from the key at once. The pose is valid pair
    by pair (it was refused: the lower block was checked against both at once)."""
    path = tmp_path / "stack.yaml"
    path.write_text("parts:\n  - {name: lower, box: [2, 2, 1]}\n"
                    "  - {name: upper, box: [2, 2, 1], position: [0, 0, 1]}\n"
                    "  - {name: key, box: [0.5, 0.5, 2], position: [1.24, 0, 0.5]}\n")
    assembly = load_assembly(path, interference=0.02)
    assert sorted((o["part"], o["other"]) for o in assembly.overlaps) == [
        ("key", "lower"), ("key", "upper")]
    lower, upper, key = assembly.parts
    assert not FclChecker.for_parts(lower, [upper, key],
                                    contact_tolerance=assembly.tolerance).is_valid(np.zeros(3))
    with pytest.raises(ScenarioError, match="part 'key' collides with 'lower'"):
        load_assembly(path, interference=0.005)


def test_contact_tolerance_is_used_everywhere():
    text = (DEMOS / "peg_in_block.yaml").read_text() + "contact_tolerance: 0.001\n"
    assembly = parse_assembly(text, DEMOS)
    assert assembly.contact_tolerance == 0.001
    assert assembly.settings.contact_tolerance == 0.001
    result = plan_assembly(assembly)
    assert result.sequence_json()["contact_tolerance"] == 0.001
    assert result.removal[0].validation["tolerance"] == 0.001


@pytest.mark.parametrize("text, expected", [
    ("parts: []\n", "<assembly>:1: parts: expected a non-empty list"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\nbase: b\n", "<assembly>:3: base: 'b' is not"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\nbsae: a\n", "<assembly>:3: bsae: unknown key; "
                                                         "did you mean 'base'?"),
    ("parts:\n  - {name: a, mesh: nope.stl}\n", "<assembly>:2: parts[0].mesh: file 'nope.stl'"),
    ("parts:\n  - {name: a, box: [1, 1, 1]}\n  - {name: b, box: [1, 1, 1]}\n",
     "<assembly>:3: parts[1]: part 'b' collides with 'a'"),
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
    with pytest.raises(ScenarioError, match=r"peg_in_hole.yaml:7: robot: this looks like"):
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
    from planner.viz import scene_for_assembly

    result = plan_assembly(load_assembly(DEMOS / "peg_in_block.yaml"))
    scene = scene_for_assembly(result)
    assert {"assembly/block", "assembly/peg"} <= set(scene.paths())
    (track,) = scene.tracks
    assert track.path == "assembly/peg"
    np.testing.assert_array_equal(track.positions[-1], np.zeros(3))
    assert main(["assemble", str(DEMOS / "peg_in_block.yaml"), "--out", str(tmp_path),
                 "--html", "--no-progress"]) == 0
    assert (tmp_path / "assembly.html").stat().st_size > 10_000
    rows = benchmark_removals(result, planners=("minkplan", "ompl:RRTConnect"))
    assert [(r["planner"], r["status"], r["valid"]) for r in rows] == [
        ("minkplan", "found", True), ("ompl:RRTConnect", "found", True)]


# ---------------------------------------------------------------- per-pair reuse


def test_pair_c_obstacles_are_built_once_and_reused(monkeypatch):
    """The C-obstacle of part j for moving part i does not change when other parts leave:
    over the 6 removal steps of the latched box, each ordered pair's C-obstacle is built
    once (counted where the source builds it), and later steps reuse them."""
    built: list[tuple[str, str]] = []
    for kind in (sources_module.ExactSource, sources_module.DecompositionSource):
        def counting(self, a, b, *, mirror_b=True, real=kind.pair):
            assert mirror_b
            built.append((a.name, b.name))
            return real(self, a, b, mirror_b=mirror_b)

        monkeypatch.setattr(kind, "pair", counting)
    result = plan_assembly(load_assembly(DEMOS / "latched_box.yaml"))
    assert result.found
    reuse = result.reuse
    n = len(result.assembly.parts)
    assert reuse["steps"] == len(result.removal) == n - 1
    assert len(built) == reuse["sums_computed"] == reuse["pairs"] <= n * (n - 1)
    assert len(set(built)) == len(built)  # no pair built twice
    assert reuse["pairs_reused_across_steps"] >= 5
    assert reuse["sums_reused"] > 2 * reuse["sums_computed"]
    assert reuse["verdicts_reused"] > reuse["verdicts_computed"]
    _revalidate(result)


def test_pair_verdicts_agree_with_fcl():
    """Where the pair's primitives decide a straight line (blocked: a sampled depth beyond
    the tolerance; free: it misses them), FCL on the two parts alone agrees."""
    assembly = load_assembly(DEMOS / "latched_box.yaml")
    cache = PairCache(assembly)
    decided = {True: 0, False: 0}
    for moving in ("latch", "lid", "wall_e"):
        for obstacle in (p.name for p in assembly.parts if p.name != moving):
            for dname, vec in DIRECTIONS.items():
                verdict = cache.verdict(moving, obstacle, dname, vec, fcl=False)
                if verdict is None:
                    continue  # grazing: FCL decides those
                far = cache.far_point(moving, dname, vec)
                seg = cache.checker(moving, obstacle).check_segment(np.zeros(3), far)
                assert seg.valid != verdict.blocked, (moving, obstacle, dname)
                decided[verdict.blocked] += 1
    assert decided[True] >= 10 and decided[False] >= 30, decided
    assert cache.stats["sums_computed"] == 3 * 6 and cache.stats["fcl_pair_checks"] == 0


# ---------------------------------------------------------------- interlocked sets


def _box(lo, hi):
    import trimesh

    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return trimesh.creation.box(extents=hi - lo,
                                transform=trimesh.transformations.translation_matrix(
                                    (lo + hi) / 2))


def _union(*boxes):
    import trimesh

    return trimesh.util.concatenate([_box(lo, hi) for lo, hi in boxes])


def _trapped_post(tmp_path: Path, parts=("base", "post", "ring_a", "ring_b")) -> Path:
    """The linked rings above a base (fixed) with a pocket in which a post stands, its
    top 0.05 under ring_a's west bar: the post is stuck while ring_a is there, ring_a
    while ring_b is; only the two rings are interlocked."""
    _union(([-1.6, -1.6, -1.4], [1.6, 1.6, -1.0]),
           ([-1.6, -1.6, -1.1], [-1.0, 1.6, -0.7]),
           ([-0.8, -1.6, -1.1], [1.6, 1.6, -0.7]),
           ([-1.05, -1.6, -1.1], [-0.75, -0.1, -0.7]),
           ([-1.05, 0.1, -1.1], [-0.75, 1.6, -0.7])).export(tmp_path / "base.stl")
    _union(([-0.95, -0.05, -1.0], [-0.85, 0.05, -0.15])).export(tmp_path / "post.stl")
    meshes = {"base": tmp_path / "base.stl", "post": tmp_path / "post.stl",
              "ring_a": DEMOS / "meshes" / "ring_a.stl",
              "ring_b": DEMOS / "meshes" / "ring_b.stl"}
    path = tmp_path / ("trapped_" + "_".join(parts) + ".yaml")
    text = "planner: {time_limit: 20}\n"
    if "base" in parts:
        text += "base: base\n"
    text += "parts:\n" + "".join(f"  - {{name: {n}, mesh: {meshes[n]}}}\n" for n in parts)
    path.write_text(text)
    return path


def test_interlocked_set_is_irreducible(tmp_path):
    # one part at a time (no groups), the post is stuck too, but not needed in the lock
    result = plan_assembly(load_assembly(_trapped_post(tmp_path)), groups=False)
    assert not result.found and result.exit_code == 1
    assert result.stuck == ["post", "ring_a", "ring_b"]
    assert result.interlocked == ["ring_a", "ring_b"]
    assert result.proved
    assert result.message.endswith("(proved); also stuck: post"), result.message
    assert set(result.core_attempts) == {"ring_a", "ring_b"}
    assert result.core_attempts["ring_a"]["obstacles"] == ["ring_b"]
    # the post could not leave with everything else present (proved), but is not needed
    assert result.attempts["post"]["proved"]
    assert sorted(result.attempts["post"]["obstacles"]) == ["base", "ring_a", "ring_b"]
    # irreducible: leaving out either ring, everything else comes apart
    for keep in (("base", "post", "ring_b"), ("base", "post", "ring_a")):
        sub = plan_assembly(load_assembly(_trapped_post(tmp_path, keep)))
        assert sub.found, (keep, sub.message)
        _revalidate(sub)


def test_interlocked_set_without_minimizing(tmp_path):
    result = plan_assembly(load_assembly(_trapped_post(tmp_path)), minimize=False,
                           groups=False)
    assert result.interlocked == result.stuck == ["post", "ring_a", "ring_b"]
    assert result.proved  # each of them was proved stuck with the others present


def test_with_groups_the_rings_leave_the_post_together_and_only_they_are_stuck(tmp_path):
    result = plan_assembly(load_assembly(_trapped_post(tmp_path)))
    assert result.stuck == result.interlocked == ["ring_a", "ring_b"] and result.proved
    (step,) = result.removal
    assert step.members == ("ring_a", "ring_b") and sorted(step.obstacles) == ["base", "post"]
    _replay(result.removal, {p.name: p for p in result.assembly.parts},
            {p.name for p in result.assembly.parts}, result.contact_tolerance)


# ---------------------------------------------------------------- goal sides


def _tunnel(tmp_path: Path) -> Path:
    """A slider on the floor of a roofed channel (the base, :func:`shapes.roofed_channel`):
    +z is blocked by a thick roof, +x by an end wall, -x by a low stop it must climb over
    (no straight exit)."""
    roofed_channel().export(tmp_path / "tunnel.stl")
    _union(([-0.6, -0.25, 0.2], [0.2, 0.25, 0.35])).export(tmp_path / "slider.stl")
    path = tmp_path / "tunnel.yaml"
    path.write_text("base: tunnel\nplanner: {time_limit: 20}\nparts:\n"
                    "  - {name: tunnel, mesh: tunnel.stl}\n"
                    "  - {name: slider, mesh: slider.stl}\n")
    return path


def test_planned_removal_leaves_by_the_open_side(tmp_path):
    """+z is blocked (roof): the planner's goal is put on the open -x side, tried first,
    and the removal ends there (not around the roof)."""
    result = plan_assembly(load_assembly(_tunnel(tmp_path)))
    assert result.found, result.message
    (step,) = result.removal
    assert (step.method, step.direction) == ("planned", "-x")
    assert len(step.removal) > 2
    assert result.reuse["planner_runs"] == 1  # stopped at the first side
    parts = {p.name: p for p in result.assembly.parts}
    lo, hi = parts["tunnel"].mesh.bounds
    p_lo, p_hi = parts["slider"].mesh.bounds + step.removal[-1]
    assert p_hi[0] < lo[0]                       # out on the -x side ...
    assert np.all(p_lo[1:] < hi[1:]) and np.all(p_hi[1:] > lo[1:])  # ... only there
    assert np.max(step.removal[:, 2]) < hi[2] - parts["slider"].mesh.bounds[0][2]
    _revalidate(result)


def test_removal_scenario_directions():
    assembly = load_assembly(DEMOS / "peg_in_block.yaml")
    for dname, vec in DIRECTIONS.items():
        scenario = removal_scenario(assembly, "peg", ["block"], dname)
        lo, hi = scenario.bounds
        goal = np.asarray(scenario.goal)
        assert np.all(goal > lo) and np.all(goal < hi)
        np.testing.assert_allclose(goal / np.linalg.norm(goal), vec, atol=1e-12)
    tilted = removal_scenario(assembly, "peg", ["block"], [1.0, 0.0, 1.0])
    np.testing.assert_allclose(tilted.goal[0], tilted.goal[2])
    for bad, message in [("up", r"^direction 'up': use one of \+z, -z"),
                         ([0, 0, 0], r"^direction \[0, 0, 0\]: expected a non-zero"),
                         ([1, 0], r"^direction \[1, 0\]: expected a non-zero")]:
        with pytest.raises(InvalidParameterError, match=message):
            removal_scenario(assembly, "peg", ["block"], bad)
    with pytest.raises(InvalidParameterError, match=r"^'pin': not a part of peg_in_block"):
        removal_scenario(assembly, "peg", ["pin"])


def test_benchmark_problems_of_an_interlocked_result():
    result = plan_assembly(load_assembly(DEMOS / "linked_rings.yaml"))
    problems = removal_problems(result)
    assert [(p["part"], p["obstacles"], p["expected"]) for p in problems] == [
        ("ring_a", ["ring_b"], "no_path"), ("ring_b", ["ring_a"], "no_path")]
    rows = benchmark_removals(result, planners=("minkplan",), runs=2)
    assert [(r["part"], r["run"], r["status"]) for r in rows] == [
        ("ring_a", 0, "no_path"), ("ring_a", 1, "no_path"),
        ("ring_b", 0, "no_path"), ("ring_b", 1, "no_path")]
    assert all(0 < r["planning_seconds"] <= r["seconds"] for r in rows)


def test_an_exact_assembly_runs_no_coacd_and_says_what_it_used(tmp_path, monkeypatch):
    """planner.exact: true on an assembly: every pair and every planned removal on the
    exact source (no decomposition at all, so no CoACD), and the reports say so."""
    import coacd

    def no_coacd(*args, **kwargs):
        raise AssertionError("CoACD ran")

    monkeypatch.setattr(coacd, "run_coacd", no_coacd)
    text = (DEMOS / "latched_box.yaml").read_text()
    assert "planner: {time_limit: 30}" in text
    assembly = parse_assembly(text.replace("planner: {time_limit: 30}",
                                           "planner: {time_limit: 30, exact: true}"), DEMOS)
    assert assembly.settings.exact is True
    result = plan_assembly(assembly, cache_dir=tmp_path / "cache")
    assert result.found
    report = result.report_json()
    assert report["source"] == {"used": "exact", "why": "planner.exact: true"}
    assert report["reuse"]["decompositions"] == 0
    assert not (tmp_path / "cache").exists()  # nothing was decomposed, nothing cached
    _revalidate(result)


def test_stuck_parts_without_planning_say_that_planning_was_off():
    """A try-out: with plan_parts=False the interlocked verdict said "some planner gave
    up", though none ran."""
    rings = Path(__file__).resolve().parents[1] / "scenarios" / "assemblies" / \
        "linked_rings.yaml"
    result = plan_assembly(load_assembly(rings), plan_parts=False, minimize=False)
    assert not result.found
    assert "not proved: no straight removal, and planning was not asked for" in \
        result.message, result.message
