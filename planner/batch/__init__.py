"""Batch runs on Ray: every (problem, planner, run) one task, local or on a cluster.

``minkplan batch INPUTS --out DIR`` and :func:`batch` find the problems
(:mod:`.tasks`), run each task in a worker's child process under its time and memory
limits (:mod:`.worker`, :mod:`.child`, :mod:`.execute`) on Ray (:mod:`.driver`), stream
one record per task to ``DIR/results.jsonl`` (:mod:`.results`) and end with
``DIR/summary.md`` and one OMPL benchmark log per planning problem (:mod:`.summary`).

A task's record is what running the problem alone gives: the same answer and, for a
given seed (the problem's seed plus the run's index), the same path.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from planner.errors import ScenarioError

from .driver import BatchReport, BatchSettings, run_batch
from .execute import FAILURES
from .summary import write_ompl_logs, write_summary
from .tasks import Problem, Task, find_problems, make_tasks
from .worker import Limits

__all__ = ["FAILURES", "BatchReport", "BatchSettings", "Limits", "Problem", "Task", "batch",
           "find_problems", "make_tasks", "run_batch"]


def batch(inputs: Sequence[str | Path], settings: BatchSettings, *,
          planners: Sequence[str] = ("minkplan",), runs: int = 1,
          time_limit: float | None = None, hold_orientation: str | None = None,
          cache_dir: str | None = None) -> BatchReport:
    """Run every problem in ``inputs`` with each planner ``runs`` times and write
    ``results.jsonl``, ``summary.md`` and the OMPL logs into ``settings.out``.

    Raises:
        ScenarioError: an input that is not a problem, a folder or a list of them, or
            inputs with no problem in them.
        FileExistsError: ``results.jsonl`` holds records and ``settings.resume`` is false.
    """
    problems = find_problems(inputs)
    if not problems:
        raise ScenarioError(f"no problems (scenario or assembly YAML, OMPL.app .cfg) in "
                            f"{', '.join(str(i) for i in inputs)}")
    tasks = make_tasks(problems, planners, runs, time_limit=time_limit,
                       hold_orientation=hold_orientation, cache_dir=cache_dir)
    try:
        report = run_batch(tasks, settings)
    except KeyboardInterrupt:  # what was done is summed up, then the interrupt goes on
        _write_outputs(settings.out, tasks, _records_of(settings.out), interrupted=True)
        raise
    report.records = _write_outputs(settings.out, tasks, report.records, interrupted=False)
    return report


def _records_of(out: Path) -> list[dict]:
    from .results import read_records

    return read_records(out / "results.jsonl")


def _write_outputs(out: Path, tasks: Sequence[Task], records: Sequence[dict], *,
                   interrupted: bool) -> list[dict]:
    """``summary.md`` and the OMPL logs of this batch's tasks (``results.jsonl`` may hold
    others, from an earlier batch resumed with other inputs); the records summed up."""
    from planner import __version__

    keys = {t.key for t in tasks}
    if interrupted and not any(r["key"] in keys for r in records):
        return []  # nothing done: nothing to sum up
    order = {t.key: i for i, t in enumerate(tasks)}
    mine = sorted((r for r in records if r["key"] in keys), key=lambda r: order[r["key"]])
    title = (f"minkplan batch: {len(mine)} of {len(tasks)} tasks"
             + (" (interrupted: resume with --resume)" if interrupted else ""))
    write_summary(out / "summary.md", mine, title=title)
    write_ompl_logs(out, mine, version=__version__)
    return mine
