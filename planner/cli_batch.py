"""The ``minkplan batch`` command: its arguments, checked, and the run (see
:mod:`planner.batch`)."""

from __future__ import annotations

import sys
from pathlib import Path

from planner.cli import _fail, _unwritable_folder

__all__ = ["add_parser", "cmd_batch", "planner_names"]


def add_parser(sub, common) -> None:
    """The ``batch`` subcommand."""
    b = sub.add_parser(
        "batch", parents=[common],
        help="run many problems (files, folders, lists) with several planners on Ray",
        description="Run every problem found in the inputs (scenario or assembly YAML, "
        "OMPL.app .cfg; folders are searched; a .txt lists paths) with each planner, "
        "--runs times, one Ray task each, local or on a cluster. Writes DIR/results.jsonl "
        "(a line per task as it finishes), DIR/summary.md and DIR/<problem>.log in OMPL's "
        "benchmark log format. Exit 0: every task answered; 1: some tasks failed (error, "
        "timeout, memory limit, crash: see summary.md); 2: bad input.",
    )
    b.add_argument("inputs", nargs="+", help="problem files, folders or .txt lists of them")
    b.add_argument("--out", required=True, help="output directory (created if needed)")
    b.add_argument("--planners", default="minkplan",
                   help="comma-separated: minkplan, ompl:NAME (default minkplan; "
                   "assemblies run with minkplan only)")
    b.add_argument("--runs", type=int, default=1, help="runs per planning problem and "
                   "planner; run k uses the problem's seed + k (default 1; an assembly runs "
                   "once: its planner is deterministic)")
    b.add_argument("--time-limit", type=float, default=None,
                   help="planner seconds per run of a planning problem (default: each "
                   "problem's own; assemblies have none, see --task-timeout)")
    b.add_argument("--task-timeout", type=float, default=None,
                   help="wall-clock seconds after which a task is killed (default: "
                   "2 × --time-limit + 60, or 1800 without it)")
    b.add_argument("--memory-limit", type=float, default=None,
                   help="MB of resident memory after which a task is killed (default none)")
    b.add_argument("--workers", type=int, default=None,
                   help="local Ray workers (default: the machine's cores)")
    b.add_argument("--address", default=None,
                   help="an existing Ray cluster (auto, ray://head:10001, ...)")
    b.add_argument("--resume", action="store_true",
                   help="keep DIR/results.jsonl and run only the tasks it lacks")
    b.add_argument("--hold-orientation", choices=("start", "goal"), default=None,
                   help="read problems whose start and goal orientations differ "
                   "translation-only, with this orientation throughout")
    b.add_argument("--cache-dir", default=None, help="decomposition cache directory")
    b.add_argument("--no-progress", action="store_true", help="no progress bar")


def _batch_settings(args):
    import math

    from planner.batch import BatchSettings, Limits

    for flag, value in (("--runs", args.runs), ("--workers", args.workers)):
        if value is not None and value < 1:
            raise ValueError(f"{flag} {value}: must be at least 1")
    for flag, value in (("--time-limit", args.time_limit),
                        ("--task-timeout", args.task_timeout),
                        ("--memory-limit", args.memory_limit)):
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{flag} {value}: must be a positive finite number")
    timeout = args.task_timeout or (2 * args.time_limit + 60 if args.time_limit else 1800.0)
    return BatchSettings(Path(args.out), workers=args.workers, address=args.address,
                         resume=args.resume, limits=Limits(timeout, args.memory_limit),
                         progress=False if args.no_progress else None)


def planner_names(text: str) -> list[str]:
    from planner.validation import available_planners, ompl_missing

    names = [n.strip() for n in text.split(",") if n.strip()]
    known = {n.lower(): n for n in available_planners()}
    canonical: list[str] = []
    for name in names:
        if name.startswith("ompl:") and not known and ompl_missing() is not None:
            raise ValueError(f"--planners: {name!r}: {ompl_missing()}")
        if name != "minkplan" and not (name.startswith("ompl:")
                                       and name[5:].lower() in known):
            import difflib

            every = ["minkplan", *(f"ompl:{n}" for n in available_planners())]
            close = difflib.get_close_matches(name, every, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise ValueError(f"--planners: {name!r} is not minkplan or ompl:NAME; {hint}NAME "
                             f"is one of {', '.join(available_planners())}")
        spelled = name if name == "minkplan" else f"ompl:{known[name[5:].lower()]}"
        if spelled not in canonical:  # ompl:prm and ompl:PRM are one planner, run once
            canonical.append(spelled)
    names = canonical
    if not names:
        raise ValueError("--planners: no planner named")
    return names


def cmd_batch(args) -> int:
    out = Path(args.out)
    problem = _unwritable_folder(out)
    if problem:
        return _fail(f"--out {out}: {problem}")
    try:
        settings = _batch_settings(args)
        planners = planner_names(args.planners)
    except ValueError as exc:
        return _fail(str(exc))
    from planner.batch import batch

    try:
        report = batch(args.inputs, settings, planners=planners, runs=args.runs,
                       time_limit=args.time_limit, hold_orientation=args.hold_orientation,
                       cache_dir=None if args.cache_dir is None
                       else str(Path(args.cache_dir).resolve()))
    except FileExistsError as exc:
        return _fail(str(exc))
    answered = len(report.records) - report.failed
    sys.stdout.write(f"batch: {len(report.records)} tasks ({report.ran} run now, "
                     f"{report.skipped} done before): {answered} answered, {report.failed} "
                     f"failed; {report.seconds:.1f} s (Ray start-up "
                     f"{report.startup_seconds:.1f} s); wrote {out}/results.jsonl, "
                     f"summary.md and the OMPL logs\n")
    return 1 if report.failed else 0
