"""The memory budget (planner.budget, ``--memory-limit``): its default comes from the
machine, the API setting reaches the native budgets, and a too small limit is refused with
one line naming the input and ``--memory-limit``, exit 2, nothing written."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

import planner
from planner import _minkowski_core as core
from planner import budget
from planner.errors import InvalidMeshError, InvalidParameterError, ResourceLimitError
from planner.meshes import repair_mesh
from planner.planning import OctreeParams
from planner.planning.search import SearchResult, SearchRun, search_without_margin
from planner.roles import NO_PATH, NOT_FOUND

ROOT = Path(__file__).resolve().parents[1]


def _meminfo_total() -> int:
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemTotal:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no MemTotal")


def test_the_default_is_half_of_the_machine(monkeypatch):
    monkeypatch.delenv(budget.ENVIRONMENT, raising=False)
    total, available = budget.machine_memory()
    cgroup = budget._cgroup_limit()
    assert total == min(_meminfo_total(), cgroup if cgroup is not None else 1 << 62)
    limit, origin = budget.default_memory_limit()
    assert limit == max(min(total // 2, available), budget.MINIMUM_BYTES)
    assert "half of this machine's" in origin


def test_the_default_without_proc_falls_back(monkeypatch):
    monkeypatch.delenv(budget.ENVIRONMENT, raising=False)
    monkeypatch.setattr(budget, "_meminfo", dict)
    monkeypatch.setattr(budget, "_cgroup_limit", lambda: None)
    import os

    total, available = budget.machine_memory()
    assert total == os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    assert available == total


def test_the_environment_sets_the_default(monkeypatch):
    monkeypatch.setenv(budget.ENVIRONMENT, "0.5")
    assert budget.default_memory_limit()[0] == budget.GIB // 2
    monkeypatch.setenv(budget.ENVIRONMENT, "nan")
    with pytest.raises(InvalidParameterError, match=budget.ENVIRONMENT):
        budget.default_memory_limit()


@pytest.mark.parametrize("value", [0, -1, float("nan"), float("inf"), 1e30, "x", 1e-4])
def test_bad_limits_are_refused(value):
    with pytest.raises(InvalidParameterError):
        planner.set_memory_limit(value)


def test_budgets_follow_the_limit():
    small, large = budget.MemoryBudget(budget.GIB), budget.MemoryBudget(4 * budget.GIB)
    assert large.leaves() == 4 * small.leaves()
    assert 0 <= large.surface_cells() - 4 * small.surface_cells() < 4
    assert large.facets(512) == 4 * small.facets(512)
    assert small.record_bytes() == budget.GIB // 4
    assert budget.MemoryBudget(64 * budget.GIB).record_bytes() == budget.MAX_RECORD_BYTES
    # each share, at its bytes per unit, is within the limit
    assert (small.leaves() * budget.LEAF_BYTES + small.facets(512) * 512
            + small.record_bytes()) <= small.limit


def test_the_limit_reaches_the_record_budget():
    with planner.memory_limit(0.01):
        before = core.set_record_budget(1 << 20)  # what the limit set, swapped out
        core.set_record_budget(before)
        assert before == budget.MemoryBudget(int(0.01 * budget.GIB)).record_bytes() // 4 * 4
    after = core.set_record_budget(1 << 20)
    core.set_record_budget(after)
    assert after == budget.current().record_bytes() // 4 * 4


def _torus_and_bumps() -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=48, minor_sections=24)
    sphere = trimesh.creation.icosphere(3)
    sphere.vertices *= 1 + 0.1 * np.sin(7 * sphere.vertices[:, :1])
    return torus, sphere


def test_a_small_limit_refuses_the_exact_sum_that_the_default_computes():
    torus, bumps = _torus_and_bumps()
    with planner.memory_limit(0.002), pytest.raises(ResourceLimitError) as refused:
        planner.minkowski_sum(torus, bumps, exact=True, eps=0.2)
    message = str(refused.value)
    assert "boundary convolution needs more than" in message
    # the facets' part of the limit is named as such, beside the limit itself
    assert f"the {budget.FACET_SHARE:.0%} of the memory limit it may use" in message
    assert "--memory-limit" in message and "\n" not in message
    result = planner.minkowski_sum(torus, bumps, exact=True, eps=0.2)
    assert result.stats["facets"] > budget.MemoryBudget(int(0.002 * budget.GIB)).facets(
        budget.facet_bytes())


def test_a_small_limit_refuses_the_grid_an_explicit_budget_names_max_cells():
    # curved and not convex: the sum is sampled on a grid, whose leaves the core counts
    torus, bumps = _torus_and_bumps()
    with planner.memory_limit(0.05), pytest.raises(ResourceLimitError) as refused:
        planner.minkowski_sum(torus, bumps, exact=True, eps=0.003)
    message = str(refused.value)
    assert "octree needs more than" in message and "\n" not in message
    # (the cells weigh less than the limit: their share of it is what ran out)
    assert "the cells' share of the memory limit" in message
    assert "--memory-limit (now 0.05 GiB" in message
    with pytest.raises(ResourceLimitError, match="raise max_cells") as named:
        planner.minkowski_sum(torus, bumps, exact=True, eps=0.01, max_cells=1000)
    assert "memory" not in str(named.value)


def test_a_depth_over_the_limit_offers_no_decomposition_it_has_none():
    torus, bumps = _torus_and_bumps()
    with planner.memory_limit(0.002), pytest.raises(ResourceLimitError) as refused:
        planner.penetration_depth(torus, bumps)
    message = str(refused.value)
    assert message.startswith("penetration depth of a into b: the boundary convolution")
    assert "decomposition" not in message and "or use simpler meshes" in message


def test_a_polyhedral_sum_at_a_fine_eps_needs_no_more_cells():
    """Cells resolved by facet planes end above eps: an L-bracket ⊕ a cube at an eps
    a thousand times finer takes about as many cells, within the small limit that a
    grid over the box's area at that eps would be far past, and is the same solid."""
    from shapes import l_bracket

    bracket, box = l_bracket(), trimesh.creation.box((1, 1, 1))
    coarse = planner.minkowski_sum(bracket, box, eps=0.01)
    with planner.memory_limit(0.002):
        fine = planner.minkowski_sum(bracket, box, eps=1e-5)
    assert fine.stats["bound_by_region"] == {"planes": 0.0, "sampled": 0.0, "missed": 0.0}
    leaves = sum(fine.stats["cells"].values())
    assert leaves <= 2 * sum(coarse.stats["cells"].values())
    assert fine.mesh.is_watertight
    assert abs(fine.mesh.volume - coarse.mesh.volume) <= 1e-9 * coarse.mesh.volume


def test_a_small_limit_refuses_the_planners_cspace():
    scenario = planner.load_scenario(ROOT / "scenarios" / "peg_in_hole.yaml")
    with planner.memory_limit(0.002), pytest.raises(ResourceLimitError) as refused:
        planner.plan(scenario, progress=False)
    assert "peg_in_hole.yaml" in str(refused.value)
    assert "--memory-limit (now 0.002 GiB; planner.memory_limit)" in str(refused.value)


def test_a_leaf_budget_given_to_the_planner_is_named_not_the_memory_limit():
    scenario = planner.load_scenario(ROOT / "scenarios" / "peg_in_hole.yaml")
    with pytest.raises(ResourceLimitError) as refused:
        planner.plan(scenario, params=OctreeParams(max_leaves=100))
    message = str(refused.value)
    assert "octree needs more than 100 cells" in message and "\n" not in message
    assert "raise OctreeParams.max_leaves" in message
    assert "memory" not in message


def test_no_time_left_for_the_search_without_the_margin():
    def build(margin):
        raise AssertionError("the second C-space must not be built past the time limit")

    first = SearchResult(NO_PATH, "certificate", "walled off")
    run = SearchRun(params=None, clock=None, rounds=[], deadline=0.0, progress=None)
    result, space = search_without_margin(build, first, 0.1, {}, run)
    assert (result.status, result.reason, space) == (NOT_FOUND, "time_limit", None)


def _run(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "planner", *argv], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("command", [
    ("plan", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--out", "out", "--no-progress",
     "--memory-limit", "0.002"),
    ("--memory-limit", "0.002", "minkowski", str(ROOT / "scenarios/assemblies/meshes/ring_a.stl"),
     str(ROOT / "scenarios/assemblies/meshes/ring_b.stl"), "-o", "out/sum.stl", "--stats",
     "out/stats.json", "--no-progress"),
    ("assemble", str(ROOT / "scenarios/assemblies/linked_rings.yaml"), "--out", "out",
     "--memory-limit", "0.002", "--no-progress", "--html"),
])
def test_the_cli_refuses_a_too_small_limit(tmp_path, command):
    done = _run(tmp_path, *command)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("minkplan: error: "), done.stderr
    assert "--memory-limit" in lines[0] and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    assert done.stdout == ""


def test_batch_keeps_its_own_memory_limit(tmp_path):
    done = _run(tmp_path, "--memory-limit", "2", "batch", "x.txt", "--out", "out")
    assert done.returncode == 2
    assert "batch has its own --memory-limit MB" in done.stderr


def test_a_ball_offset_over_the_limit_offers_what_an_offset_has_in_mib():
    """Refused, the ball's sum names the cells (an offset has no decomposition source) and
    a need below 0.1 GiB in MiB (it read "0.00 GiB")."""
    torus, _ = _torus_and_bumps()
    with planner.memory_limit(0.001), pytest.raises(ResourceLimitError) as refused:
        planner.offset(torus, 0.05, eps=0.002, method="ball")
    message = str(refused.value)
    assert "boundary convolution needs more than" in message and " MiB, the 25%" in message
    assert "exact: false" not in message and "--method cells" in message


def test_a_repair_that_drops_nan_faces_says_so():
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    vertices = np.vstack([box.vertices, [[np.nan, 0.0, 0.0]]])
    flat = trimesh.Trimesh(vertices, np.vstack([box.faces[:2], [[0, 1, 8]]]), process=False)
    with pytest.raises(InvalidMeshError, match="after removing the 1 faces with NaN"):
        repair_mesh(flat, name="flat")


def test_a_limit_above_the_machines_memory_is_warned_of(monkeypatch, caplog):
    monkeypatch.setattr(budget, "machine_memory", lambda: (8 * budget.GIB, 6 * budget.GIB))
    with caplog.at_level("WARNING", logger="planner.budget"):
        with planner.memory_limit(4):
            pass
    assert caplog.text == ""
    with caplog.at_level("WARNING", logger="planner.budget"):
        with planner.memory_limit(16) as limit:
            assert limit.limit == 16 * budget.GIB  # taken, as asked
    assert "memory limit 16 GiB is more than this machine's memory (8 GiB" in caplog.text


def test_the_cli_warns_of_a_limit_above_the_machines_memory(tmp_path):
    total = budget.gib(budget.machine_memory()[0])
    done = _run(tmp_path, "--memory-limit", "1e6", "depth", str(ROOT / "scenarios/assemblies/"
                "meshes/ring_a.stl"), str(ROOT / "scenarios/assemblies/meshes/ring_a.stl"))
    assert done.returncode == 0, done.stderr
    assert (f"WARNING planner.budget: --memory-limit 1e6 GiB is more than this machine's "
            f"memory ({total}") in done.stderr
