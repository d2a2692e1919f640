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
        ScenarioError: an input that is not a problem, a folder or a list of them.
        FileExistsError: ``results.jsonl`` holds records and ``settings.resume`` is false.
    """
    from planner import __version__

    tasks = make_tasks(find_problems(inputs), planners, runs, time_limit=time_limit,
                       hold_orientation=hold_orientation, cache_dir=cache_dir)
    report = run_batch(tasks, settings)
    write_summary(settings.out / "summary.md", report.records,
                  title=f"minkplan batch: {len(tasks)} tasks")
    write_ompl_logs(settings.out, report.records, version=__version__)
    return report
