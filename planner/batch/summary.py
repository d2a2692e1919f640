"""What a batch leaves besides ``results.jsonl``: ``summary.md`` (per problem and planner:
valid successes, answers, median and maximum seconds, failures) and one OMPL benchmark
log per planning problem (``<problem>.log``, see :mod:`planner.ompl_log`), so
``ompl_benchmark_statistics.py`` reads the batch into the database Planner Arena plots.

A task that gave no answer (error, timeout, memory limit, crash) is a ``not_found`` run
in the OMPL log, its reason saying which. Assemblies are not motion-planning
experiments: they are in ``summary.md`` only.

Entry points: :func:`write_summary`, :func:`write_ompl_logs`.
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from planner.ompl_log import Run, write_log
from planner.output import atomic_write

from .execute import FAILURES
from .tasks import PLAN

__all__ = ["experiment_names", "write_ompl_logs", "write_summary"]

Record = dict[str, Any]


def _groups(records: Sequence[Record]) -> dict[tuple[str, str], list[Record]]:
    """The records per (problem, planner), in the order of the records (the tasks'
    order: the inputs as given), each group by run."""
    groups: dict[tuple[str, str], list[Record]] = {}
    for record in records:
        groups.setdefault((record["problem"], record["planner"]), []).append(record)
    return {k: sorted(v, key=lambda r: r["run"]) for k, v in groups.items()}


def experiment_names(problems: Sequence[str]) -> dict[str, str]:
    """A name per problem file for its log: the file's stem, with its folder's name in
    front where two problems share a stem."""
    stems = Counter(Path(p).stem for p in problems)
    return {p: Path(p).stem if stems[Path(p).stem] == 1
            else f"{Path(p).parent.name}_{Path(p).stem}" for p in problems}


def _row(name: str, planner: str, runs: list[Record]) -> str:
    seconds = [r["seconds"] for r in runs]
    valid = sum(r["status"] == "found" and bool(r.get("valid")) for r in runs)
    proved = sum(r["status"] == "no_path" for r in runs)
    answers = Counter(f"{r['status']} ({r['reason']})" for r in runs)
    failed = sum(r["status"] in FAILURES for r in runs)
    said = ", ".join(f"{n}× {a}" for a, n in sorted(answers.items()))
    return (f"| {name} | {planner} | {len(runs)} | {valid} | {proved} | "
            f"{statistics.median(seconds):.3g} | {max(seconds):.3g} | {failed} | {said} |")


def write_summary(path: Path, records: Sequence[Record], *, title: str) -> None:
    """``summary.md``: a table with a row per (problem, planner), then each failure's
    message (one line per distinct message)."""
    names = experiment_names(sorted({r["problem"] for r in records}))
    lines = [f"# {title}", "", f"{len(records)} tasks.", "",
             "| problem | planner | runs | found (valid) | no path (proved) | median s | "
             "max s | failed | answers |", "|---|---|---|---|---|---|---|---|---|"]
    lines += [_row(names[problem], planner, runs)
              for (problem, planner), runs in _groups(records).items()]
    failures = sorted({(names[r["problem"]], r["planner"], r["status"], r["message"])
                       for r in records if r["status"] in FAILURES})
    if failures:
        lines += ["", "## Failures", ""]
        lines += [f"- {n} / {p}: {s}: {m}" for n, p, s, m in failures]
    lines += ["", "Seconds: each task's own time in its worker (reading the problem, "
              "planning, validating). 'found (valid)': paths (or assembly sequences) that "
              "passed the independent validation; 'no path (proved)': a certificate, a start "
              "or goal in collision, or a proved interlock."]
    text = "\n".join(lines) + "\n"
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def _run(record: Record) -> Run:
    """The record as an OMPL run; its time is the planner's (setup and solve, without
    reading the problem or validating the path), as OMPL's benchmarks time a run."""
    if record["status"] in FAILURES:
        return Run(record["seconds"], "not_found", reason=record["status"])
    def real(key: str) -> float:
        value = record.get(key)
        return math.nan if value is None else float(value)

    seconds = record.get("planner_seconds")
    return Run(record["seconds"] if seconds is None else seconds, record["status"],
               real("length"), real("clearance"),
               bool(record.get("valid")), record.get("reason") or "")


def write_ompl_logs(folder: Path, records: Sequence[Record], *, version: str) -> list[Path]:
    """One OMPL benchmark log per planning problem in ``folder``; the paths written."""
    plans = [r for r in records if r["kind"] == PLAN]
    names = experiment_names(sorted({r["problem"] for r in plans}))
    by_problem: dict[str, dict[str, list[Record]]] = {}
    for (problem, planner), runs in _groups(plans).items():
        by_problem.setdefault(problem, {})[planner] = runs
    written = []
    for problem, planners in by_problem.items():
        every = [r for runs in planners.values() for r in runs]
        limits = [float(r.get("effective_time_limit") or r.get("time_limit") or 0.0)
                  for r in every]
        seeds = [r["seed"] for r in every if r.get("seed") is not None]
        held = next((r.get("hold_orientation") for r in every), None)
        memory = [r["memory_limit_mb"] for r in every if r.get("memory_limit_mb")]
        log = folder / f"{names[problem]}.log"
        write_log(log, experiment=names[problem],
                  setup=f"{problem}\norientation held: {held or 'no'}",
                  runs={p: [_run(r) for r in runs] for p, runs in planners.items()},
                  time_limit=max(limits, default=0.0),
                  total_seconds=sum(r["seconds"] for r in every),
                  seed=min(seeds, default=0), version=version,
                  memory_limit_mb=max(memory, default=0.0))
        written.append(log)
    return written
