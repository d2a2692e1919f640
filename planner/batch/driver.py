"""Running a batch's tasks on Ray: local by default, a cluster with ``address``.

Every task is one Ray task (one CPU), submitted at once and collected as each finishes:
its record goes to ``results.jsonl`` at that moment, so an interrupted batch keeps what
it did and ``resume`` does the rest. Ray retries a task whose worker process was lost
(``max_retries``); a task that still gets no record from Ray is recorded ``crashed``.
On a terminal a progress bar shows done, failed and pending tasks, the rate and the ETA.

Workers read the problem files and the decomposition cache by their paths: on a cluster,
put them on a file system every node mounts at the same path, with ``minkplan``
installed on every node.

Entry points: :class:`BatchSettings`, :func:`run_batch`.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from planner.errors import InvalidParameterError
from planner.output import schema_id
from planner.progress import bar as progress_bar
from planner.progress import shown

from .execute import FAILURES
from .results import ResultsFile
from .tasks import Task
from .worker import Limits, run_task

__all__ = ["BatchReport", "BatchSettings", "run_batch"]

log = logging.getLogger(__name__)

RETRIES = 2
"""Times Ray runs a task again after losing its worker process."""

_RESUME_SETTINGS = ("time_limit", "hold_orientation")
"""Task settings that change an answer: a resumed batch must ask the same."""


@dataclass(frozen=True)
class BatchSettings:
    """How a batch runs.

    Attributes:
        out: the output folder (``results.jsonl``, ``summary.md``, the OMPL logs).
        workers: local workers (``None``: the machine's cores); ignored with ``address``.
        address: an existing Ray cluster (``"auto"``, ``"ray://head:10001"``...).
        resume: skip the tasks ``results.jsonl`` already holds.
        limits: per-task wall-clock and memory limits.
        progress: the progress bar (``None``: only on a terminal).
    """

    out: Path
    workers: int | None = None
    address: str | None = None
    resume: bool = False
    limits: Limits = field(default_factory=Limits)
    progress: bool | None = None


@dataclass
class BatchReport:
    """What a batch did: every record in ``results.jsonl`` (earlier ones included),
    how many tasks this run did and skipped, and Ray's start-up seconds."""

    records: list[dict[str, Any]]
    ran: int
    skipped: int
    startup_seconds: float
    seconds: float

    @property
    def failed(self) -> int:
        return sum(r["status"] in FAILURES for r in self.records)


def _start_ray(settings: BatchSettings) -> float:
    """Start (or join) Ray; its start-up seconds.

    The workers get an empty working folder: by default Ray puts the driver's folder on
    their import path, where a source tree would shadow the installed planner.

    Raises:
        InvalidParameterError: the cluster at ``address`` cannot be reached (one line).
    """
    import ray

    where = f"the Ray cluster at {settings.address}" if settings.address else (
        f"a local Ray with {settings.workers or os.cpu_count() or 1} workers")
    if shown(settings.progress):
        sys.stderr.write(f"minkplan: starting {where}...\n")
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="minkplan-batch-") as empty:
        options: dict[str, Any] = {"logging_level": logging.WARNING, "log_to_driver": False,
                                   "runtime_env": {"working_dir": empty}}
        if not settings.address:
            options.update(num_cpus=settings.workers or os.cpu_count() or 1,
                           include_dashboard=False)
        try:
            ray.init(address=settings.address, **options)
        except (ConnectionError, RuntimeError, ValueError, ImportError) as exc:
            first = (str(exc).strip().splitlines() or [""])[0]
            raise InvalidParameterError(f"--address {settings.address}: cannot start or "
                                        f"join Ray: {first}") from None
    return time.perf_counter() - t0


def _check_resume(tasks: Sequence[Task], records: Sequence[dict[str, Any]]) -> None:
    """A resumed batch must ask what the records answered: the same time limit and
    orientation reading per task key.

    Raises:
        InvalidParameterError: a record made with other settings (one line naming it).
    """
    done = {r["key"]: r for r in records}
    for task in tasks:
        record = done.get(task.key)
        if record is None:
            continue
        for name in _RESUME_SETTINGS:
            if record.get(name) != getattr(task, name):
                raise InvalidParameterError(
                    f"--resume: results.jsonl ran {Path(task.problem).name} "
                    f"({task.planner}, run {task.run}) with {name} = {record.get(name)!r}, "
                    f"this batch asks {getattr(task, name)!r}; use another --out")


def _lost(task: Task, error: Exception) -> dict[str, Any]:
    """The record of a task Ray gave no result for: its worker raised (``cause``), or
    Ray lost the worker more times than it retries."""
    cause = getattr(error, "cause", None)
    if isinstance(cause, Exception):
        first = (str(cause).strip().splitlines() or [""])[0]
        message = f"the worker failed: {type(cause).__name__}: {first}"
    else:
        first = (str(error).strip().splitlines() or [""])[0]
        message = (f"Ray lost the task's worker {RETRIES + 1} times: "
                   f"{type(error).__name__}: {first}")
    return {"schema": schema_id("batch_record"), **task.to_json(), "key": task.key,
            "status": "crashed", "reason": "crashed",
            "message": message, "seconds": 0.0}


def _collect(pending: dict[Any, Task], results: ResultsFile, progress: bool | None) -> None:
    import ray

    failed = 0
    slots = int(ray.cluster_resources().get("CPU", 1))
    with progress_bar(total=len(pending), enabled=progress, unit="task",
                      dynamic_ncols=True) as bar:
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=0.25)
            for ref in ready:
                task = pending.pop(ref)
                try:
                    record = ray.get(ref)
                except ray.exceptions.RayError as error:
                    record = _lost(task, error)
                results.append(record)
                failed += record["status"] in FAILURES
                log.info("%s %s run %d: %s (%s) %.2f s", Path(task.problem).name,
                         task.planner, task.run, record["status"], record["reason"],
                         record["seconds"])
                bar.update(1)
            bar.set_postfix(failed=failed, running=min(slots, len(pending)),
                            queued=max(0, len(pending) - slots), refresh=False)


def run_batch(tasks: Sequence[Task], settings: BatchSettings) -> BatchReport:
    """Run ``tasks`` on Ray, each once, streaming records to ``OUT/results.jsonl``.

    Raises:
        FileExistsError: ``results.jsonl`` holds records and ``resume`` is false.
        InvalidParameterError: ``resume`` with records of other settings, or a cluster
            that cannot be reached.
    """
    import ray

    t0 = time.perf_counter()
    results = ResultsFile(settings.out / "results.jsonl", resume=settings.resume)
    try:
        _check_resume(tasks, results.records)
    except InvalidParameterError:
        results.close()
        raise
    done = results.done
    todo = [t for t in tasks if t.key not in done]
    skipped = len(tasks) - len(todo)
    if skipped:
        log.warning("resuming: %d of %d tasks are done already; running %d", skipped,
                    len(tasks), len(todo))
    startup = 0.0
    try:
        if todo:
            startup = _start_ray(settings)
            remote = ray.remote(run_task).options(num_cpus=1, max_retries=RETRIES)
            pending = {remote.remote(t.to_json(), settings.limits): t for t in todo}
            _collect(pending, results, settings.progress)
    finally:
        results.close()
        if ray.is_initialized():
            ray.shutdown()
    return BatchReport(results.records, len(todo), skipped, startup,
                       time.perf_counter() - t0)
