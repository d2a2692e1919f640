"""The batch's parts without Ray: finding problems, the tasks made of them,
``results.jsonl`` and a worker's limits on its child process (real planning runs)."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest
from conftest import SHARED_ASSETS

from planner.batch import Limits, find_problems, make_tasks, worker
from planner.batch.execute import execute
from planner.batch.results import ResultsFile
from planner.batch.summary import experiment_names, write_summary
from planner.batch.worker import run_task
from planner.errors import ScenarioError
from planner.io import load_scenario
from planner.planning import plan

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def test_a_folder_gives_its_scenarios_and_assemblies_and_passes_over_other_yaml(tmp_path):
    (tmp_path / "settings.yaml").write_text("colour: blue\n")
    (tmp_path / "notes.txt").write_text("not a list: it is inside a folder\n")
    problems = find_problems([SCENARIOS, tmp_path])
    names = {p.name: p.kind for p in problems}
    assert names["peg_in_hole"] == "plan" and names["pegs_and_holes"] == "assembly"
    assert "settings" not in names and "make_scenarios" not in names
    assert len(problems) == len({p.path for p in problems})


def test_a_list_file_reads_relative_paths_and_comments_and_names_a_missing_line(tmp_path):
    listing = tmp_path / "problems.txt"
    listing.write_text(f"# the suite\n{os.path.relpath(SCENARIOS / 'bug_trap.yaml', tmp_path)}"
                       f"  # trap\n\n{SCENARIOS / 'assemblies' / 'peg_in_block.yaml'}\n")
    assert [p.name for p in find_problems([listing])] == ["bug_trap", "peg_in_block"]
    listing.write_text("bug_trap.yaml\nnowhere.yaml\n")
    with pytest.raises(ScenarioError, match=r"problems.txt:1: 'bug_trap.yaml' not found"):
        find_problems([listing])


def test_an_input_that_is_no_problem_is_refused_by_name(tmp_path):
    other = tmp_path / "colours.yaml"
    other.write_text("colour: blue\n")
    with pytest.raises(ScenarioError, match="colours.yaml: neither a scenario"):
        find_problems([other])
    with pytest.raises(ScenarioError, match="nothing.cfg: not found"):
        find_problems([tmp_path / "nothing.cfg"])


def test_assemblies_run_with_minkplan_only_and_every_task_has_its_own_key():
    problems = find_problems([SCENARIOS / "bug_trap.yaml",
                              SCENARIOS / "assemblies" / "peg_in_block.yaml"])
    tasks = make_tasks(problems, ["minkplan", "ompl:RRTConnect"], 3)
    assert len(tasks) == 2 * 3 + 1  # an assembly runs once: its planner is deterministic
    assert {t.planner for t in tasks if t.kind == "assembly"} == {"minkplan"}
    assert len({t.key for t in tasks}) == len(tasks)


def test_two_problems_with_one_stem_get_distinct_log_names():
    names = experiment_names(["/a/x/easy.cfg", "/a/y/easy.cfg", "/a/y/hard.cfg"])
    assert names == {"/a/x/easy.cfg": "x_easy", "/a/y/easy.cfg": "y_easy",
                     "/a/y/hard.cfg": "hard"}


def test_a_failure_in_the_summary_advises_what_a_batch_reads(tmp_path):
    """An assembly whose parts overlap: summary.md advises the file's ``interference``
    (a batch reads it; ``--interference`` is an option of ``assemble``, not of batch)."""
    path = tmp_path / "press_fit.yaml"
    path.write_text("name: press_fit\nparts:\n  - {name: block, box: [2, 2, 2]}\n"
                    "  - {name: cap, box: [1, 1, 1], position: [0, 0, 1.48]}\n")
    (task,) = make_tasks(find_problems([path]), ["minkplan"], 1)
    record = execute(task)
    assert (record["status"], record["reason"]) == ("error", "input")
    write_summary(tmp_path / "summary.md", [record], title="press fit")
    failures = (tmp_path / "summary.md").read_text().split("## Failures")[1]
    assert "give interference: 0.021 or more in the assembly file" in failures
    assert "--interference" not in failures


def test_results_keep_whole_records_and_refuse_to_overwrite(tmp_path):
    path = tmp_path / "results.jsonl"
    results = ResultsFile(path, resume=False)
    results.append({"key": "a", "status": "found"})
    results.close()
    with path.open("a") as out:  # a driver killed in the middle of a line
        out.write('{"key": "b", "sta')
    with pytest.raises(FileExistsError, match="--resume"):
        ResultsFile(path, resume=False)
    resumed = ResultsFile(path, resume=True)
    assert resumed.done == {"a"}
    resumed.append({"key": "b", "status": "no_path"})
    resumed.close()
    assert [json.loads(line)["key"] for line in path.read_text().splitlines()] == ["a", "b"]


def _task(name: str, **kw):
    problems = find_problems([SCENARIOS / name])
    return make_tasks(problems, ["minkplan"], 1, **kw)[0].to_json()


def test_a_worker_answers_as_planning_alone_does_and_keeps_its_child():
    first = run_task(_task("peg_in_hole.yaml"), Limits())
    alone = plan(load_scenario(SCENARIOS / "peg_in_hole.yaml"), progress=False)
    assert (first["status"], first["reason"]) == (str(alone.status), alone.reason)
    assert first["waypoints"] == alone.waypoints.tolist() and first["valid"]
    second = run_task(_task("sealed_chamber.yaml"), Limits())
    assert (second["status"], second["reason"]) == ("no_path", "certificate")
    assert second["child_pid"] == first["child_pid"] and second["peak_mb"] > 10


def test_a_task_over_its_time_is_killed_and_the_next_gets_a_new_child():
    late = run_task(_task("three_floor_maze.yaml"), Limits(task_timeout=0.05))
    assert late["status"] == "timeout" and "0.05 s" in late["message"]
    with pytest.raises(ProcessLookupError):
        os.kill(late["child_pid"], 0)
    after = run_task(_task("bug_trap.yaml"), Limits(task_timeout=60))
    assert after["status"] == "found" and after["child_pid"] != late["child_pid"]


def test_a_task_over_its_memory_is_killed_with_its_peak_said(monkeypatch):
    # the task process's own budget (a share of the limit) is raised above the limit, so
    # the worker's watch, not the planner's refusal, is what stops it
    monkeypatch.setattr(worker, "CHILD_BUDGET_SHARE", 1000.0)
    big = run_task(_task("peg_in_hole.yaml"), Limits(memory_limit_mb=21))
    assert big["status"] == "memory_limit" and big["peak_mb"] > 21
    assert "over the limit of 21 MB" in big["message"]


@pytest.mark.assets
def test_a_child_killed_mid_task_is_recorded_as_crashed():
    warm = run_task(_task("bug_trap.yaml"), Limits())
    timer = threading.Timer(1.0, os.kill, (warm["child_pid"], signal.SIGKILL))
    timer.start()
    t0 = time.perf_counter()
    escape = make_tasks(find_problems([SHARED_ASSETS / "omplapp" / "escape.cfg"]),
                        ["minkplan"], 1, hold_orientation="start")[0]  # 20 s of work
    record = run_task(escape.to_json(), Limits())
    timer.join()
    assert record["status"] == "crashed" and "SIGKILL" in record["message"]
    assert time.perf_counter() - t0 < 30


def _batch_cli(args: list[str], capsys) -> tuple[int, str]:
    from planner.cli import main

    code = main(["batch", *args, "--no-progress"])
    return code, capsys.readouterr().err


def test_a_resume_with_other_settings_is_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "out"
    task = make_tasks(find_problems([SCENARIOS / "bug_trap.yaml"]), ["minkplan"], 1,
                      time_limit=3.0)[0]
    results = ResultsFile(out / "results.jsonl", resume=False)
    results.append({**task.to_json(), "key": task.key, "status": "found"})
    results.close()
    code, err = _batch_cli([str(SCENARIOS / "bug_trap.yaml"), "--out", str(out),
                            "--time-limit", "1", "--resume"], capsys)
    assert code == 2 and "time_limit = 3.0, this batch asks 1.0" in err


def test_inputs_without_problems_and_broken_yaml_are_refused_by_name(tmp_path, capsys):
    empty = tmp_path / "empty"
    empty.mkdir()
    code, err = _batch_cli([str(empty), "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and "no problems" in err and not (tmp_path / "out").exists()
    broken = tmp_path / "broken.yaml"
    broken.write_text("a: [1\n")  # not recognisable as a scenario: its syntax is the reason
    code, err = _batch_cli([str(broken), "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and "YAML syntax error at line 2" in err


def test_one_planner_named_twice_runs_once_and_limits_must_be_finite(tmp_path, capsys):
    from planner.cli_batch import planner_names as _planner_names

    assert _planner_names("minkplan,ompl:prm,ompl:PRM,minkplan") == ["minkplan", "ompl:PRM"]
    code, err = _batch_cli([str(SCENARIOS / "bug_trap.yaml"), "--out", str(tmp_path),
                            "--time-limit", "inf"], capsys)
    assert code == 2 and "--time-limit inf: must be a positive finite number" in err
