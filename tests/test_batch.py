"""``minkplan batch`` on a local Ray with 2 workers, as a user runs it: the bundled
scenarios and assemblies give the answers (and paths) of serial runs, a broken problem is
a clean error record, a worker killed mid-batch still leaves a complete
``results.jsonl``, ``--resume`` after an interrupt runs only what is missing, and the OMPL
logs read with the statistics script of the ``ompl`` wheel."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
from ompl import _benchmark_statistics as ompl_statistics

from planner.assembly import plan_assembly
from planner.io import load_assembly, load_scenario
from planner.planning import plan

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
PROBLEMS = sorted(p for p in SCENARIOS.rglob("*.yaml"))
FIVE_RUNS = sum(1 if "assemblies" in p.parts else 5 for p in PROBLEMS)
"""Tasks of ``--runs 5`` over the scenarios (an assembly runs once): about 15 s of work,
so an interrupt or a killed worker lands in the middle of the batch."""


def _interruptible() -> None:
    """In the child: SIGINT as a terminal delivers it, even when this test runs where it
    is ignored (a shell's background job), so Python turns it into KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _batch(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "planner", "batch", *args, "--workers",
                             "2", "--no-progress"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT,
                            preexec_fn=_interruptible, **kw)


def _records(out: Path) -> list[dict]:
    path = out / "results.jsonl"
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines()]


def _serial(path: Path) -> tuple[str, str, list | None]:
    if "assemblies" in path.parts:
        result = plan_assembly(load_assembly(path))
        return ("found" if result.found else "no_path" if result.proved else "not_found",
                result.status, None)
    outcome = plan(load_scenario(path), progress=False)
    return str(outcome.status), outcome.reason, (outcome.waypoints.tolist()
                                                 if outcome.found else None)


@pytest.fixture(scope="module")
def broken(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("broken")
    text = (SCENARIOS / "peg_in_hole.yaml").read_text()
    (folder / "missing_mesh.yaml").write_text(
        text.replace("peg_in_hole/block.stl", "nowhere/block.stl")
        .replace("peg_in_hole/peg.stl", str(SCENARIOS / "peg_in_hole" / "peg.stl")))
    return folder / "missing_mesh.yaml"


def test_a_local_batch_gives_the_serial_answers_and_records_a_broken_problem(
        tmp_path, broken, capsys):
    out = tmp_path / "out"
    done = _batch(str(SCENARIOS), str(broken), "--out", str(out)).communicate(timeout=600)
    records = {Path(r["problem"]): r for r in _records(out)}
    assert set(records) == {*PROBLEMS, broken}, done
    failed = records.pop(broken)
    assert failed["status"] == "error" and failed["reason"] == "input"
    assert "obstacles[0].mesh: file 'nowhere/block.stl' not found" in failed["message"]
    for path, record in records.items():
        status, reason, waypoints = _serial(path)
        assert (record["status"], record["reason"]) == (status, reason), path
        assert record.get("waypoints") == waypoints, path
    assert "1 failed" in done[0]
    summary = (out / "summary.md").read_text()
    assert "| peg_in_hole | minkplan | 1 | 1 | 0 |" in summary and "missing_mesh" in summary
    assert "| sealed_chamber | minkplan | 1 | 0 | 1 |" in summary
    database = tmp_path / "bench.db"
    logs = sorted(str(p) for p in out.glob("*.log"))
    assert len(logs) == sum("assemblies" not in p.parts for p in PROBLEMS) + 1
    ompl_statistics.readBenchmarkLog(str(database), logs, moveitformat=False)
    capsys.readouterr()
    with sqlite3.connect(database) as db:
        runs = db.execute("SELECT experiments.name, status, reason FROM runs JOIN "
                          "experiments ON runs.experimentid = experiments.id").fetchall()
    by_name = {name: (status, reason) for name, status, reason in runs}
    assert by_name["sealed_chamber"] == (1, "certificate")
    assert by_name["missing_mesh"] == (2, "error")


def test_the_exit_code_says_a_task_failed(tmp_path, broken):
    run = _batch(str(broken), "--out", str(tmp_path / "out"))
    run.communicate(timeout=300)
    assert run.returncode == 1


def _child_workers() -> set[int]:
    """The Ray worker processes whose task child runs now."""
    workers = set()
    for entry in Path("/proc").iterdir():
        try:
            cmdline = (entry / "cmdline").read_bytes()
            if b"planner.batch.child" in cmdline:
                stat = (entry / "stat").read_text()
                workers.add(int(stat.rsplit(")", 1)[1].split()[1]))
        except (OSError, ValueError, IndexError):
            continue
    return workers


def _wait_for(out: Path, count: int, run: subprocess.Popen) -> None:
    deadline = time.monotonic() + 300
    while len(_records(out)) < count:
        assert run.poll() is None and time.monotonic() < deadline, run.communicate()
        time.sleep(0.05)


def test_a_worker_killed_mid_batch_still_leaves_every_record(tmp_path):
    out = tmp_path / "out"
    total = FIVE_RUNS
    run = _batch(str(SCENARIOS), "--runs", "5", "--out", str(out))  # about 15 s
    _wait_for(out, 1, run)
    workers = _child_workers()
    assert workers, "no worker with a task child running"
    os.kill(min(workers), signal.SIGKILL)
    stdout, stderr = run.communicate(timeout=600)
    records = _records(out)
    keys = [r["key"] for r in records]
    assert run.returncode == 0, stderr
    assert len(keys) == len(set(keys)) == total
    assert not [r for r in records if r["status"] not in ("found", "no_path", "not_found")]


def test_resume_after_an_interrupt_runs_only_the_missing_tasks(tmp_path):
    out = tmp_path / "out"
    runs = ("--runs", "5")  # long enough (about 15 s) that the interrupt lands mid-batch
    total = FIVE_RUNS
    first = _batch(str(SCENARIOS), *runs, "--out", str(out))
    _wait_for(out, 1, first)
    first.send_signal(signal.SIGINT)
    first.communicate(timeout=120)
    assert first.returncode == 130
    before = _records(out)
    assert 1 <= len(before) < total
    again = _batch(str(SCENARIOS), *runs, "--out", str(out), "--resume")
    stdout, stderr = again.communicate(timeout=600)
    assert again.returncode == 0, stderr
    assert f"({total - len(before)} run now, {len(before)} done before)" in stdout
    keys = [r["key"] for r in _records(out)]
    assert len(keys) == len(set(keys)) == total
    assert [r["key"] for r in _records(out)[:len(before)]] == [r["key"] for r in before]


def test_a_source_tree_in_the_launch_folder_does_not_shadow_the_installed_planner(tmp_path):
    shadow = tmp_path / "planner"
    shadow.mkdir()
    (shadow / "__init__.py").write_text("raise ImportError('the shadowing source tree')\n")
    out = tmp_path / "out"
    run = subprocess.run([str(Path(sys.executable).parent / "minkplan"), "batch",
                          str(SCENARIOS / "bug_trap.yaml"), "--out", str(out), "--workers",
                          "1", "--no-progress"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert [r["status"] for r in _records(out)] == ["found"]
