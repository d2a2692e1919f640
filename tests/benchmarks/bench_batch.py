"""Throughput of ``minkplan batch`` on Ray: tasks per minute with 1 and 2 local workers
on the bundled scenarios and assemblies plus the OMPL.app problems in
``../shared/assets/omplapp`` (translation-only with the start's orientation where it
turns), Ray's start-up time, and what N workers would do with the same tasks (by
simulation: this run's per-task times, scheduled greedily in submission order on N
workers, with the per-task overhead measured here).

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_batch.py [--task-timeout S] [--runs N] [--out DIR]

Writes ``DIR/<date>-batch.md`` (DIR defaults to ``tests/benchmarks/results``) and the
batches' own folders under ``DIR/<date>-batch/``.
"""

from __future__ import annotations

import argparse
import datetime
import heapq
import logging
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))

from planner.batch import BatchSettings, Limits, batch  # noqa: E402

SUITE = 100
"""The simulated large suite: this batch's tasks this many times over."""
OMPLAPP = ROOT.parent / "shared" / "assets" / "omplapp"


def makespan(seconds: list[float], workers: int, overhead: float) -> float:
    """Greedy list scheduling in submission order: each task to the first free worker."""
    free = [0.0] * workers
    for s in seconds:
        heapq.heappush(free, heapq.heappop(free) + s + overhead)
    return max(free)


def one(inputs: list[str], workers: int, out: Path, args) -> dict:
    shutil.rmtree(out, ignore_errors=True)
    settings = BatchSettings(out, workers=workers, progress=False,
                             limits=Limits(task_timeout=args.task_timeout))
    report = batch(inputs, settings, runs=args.runs, hold_orientation="start")
    seconds = [r["seconds"] for r in report.records]
    working = report.seconds - report.startup_seconds
    return {"workers": workers, "tasks": len(seconds), "wall": report.seconds,
            "startup": report.startup_seconds, "working": working,
            "per_minute": 60 * len(seconds) / working, "task_seconds": seconds,
            "failed": report.failed,
            "overhead": max(0.0, (working * workers - sum(seconds)) / len(seconds))}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--task-timeout", type=float, default=30.0)
    p.add_argument("--runs", type=int, default=1)
    p.add_argument("--out", default=str(HERE / "results"))
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    stamp = datetime.date.today().isoformat()
    out = Path(args.out)
    inputs = [str(ROOT / "scenarios"), *sorted(str(c) for c in OMPLAPP.glob("*.cfg"))]
    runs = [one(inputs, w, out / f"{stamp}-batch" / f"workers-{w}", args) for w in (1, 2)]
    base = runs[0]
    lines = [f"# minkplan batch throughput ({stamp})", "",
             f"{base['tasks']} tasks (bundled scenarios and assemblies, OMPL.app problems "
             f"held at the start's orientation), task timeout {args.task_timeout:g} s.", "",
             "| workers | tasks/min (after start-up) | wall s | Ray start-up s | failed | "
             "speed-up |", "|---|---|---|---|---|---|"]
    for run in runs:
        lines.append(f"| {run['workers']} | {run['per_minute']:.1f} | {run['wall']:.1f} | "
                     f"{run['startup']:.1f} | {run['failed']} | "
                     f"{run['per_minute'] / base['per_minute']:.2f} |")
    lines += ["", "Simulated on N workers (this run's task times from 1 worker, "
              f"{base['overhead']:.3f} s overhead per task):", "",
              f"| N | makespan s | speed-up over 1 | the tasks ×{SUITE} ({SUITE * base['tasks']}"
              " tasks): makespan s | speed-up over 1 |", "|---|---|---|---|---|"]
    serial = makespan(base["task_seconds"], 1, base["overhead"])
    suite = base["task_seconds"] * SUITE
    suite_serial = makespan(suite, 1, base["overhead"])
    for n in (1, 2, 4, 16, 100):
        span = makespan(base["task_seconds"], n, base["overhead"])
        big = makespan(suite, n, base["overhead"])
        lines.append(f"| {n} | {span:.1f} | {serial / span:.2f} | {big:.0f} | "
                     f"{suite_serial / big:.1f} |")
    lines += ["", f"The longest task takes {max(base['task_seconds']):.1f} s: no number of "
              "workers finishes the batch sooner than that, so 100 workers on "
              f"{base['tasks']} tasks gain little; on a suite of thousands the speed-up "
              "approaches N, bounded by the longest task and, on a real cluster, by the "
              "scheduler and the shared file system (not simulated)."]
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{stamp}-batch.md").write_text("\n".join(lines) + "\n")
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
