"""Side-by-side benchmark: OMPL.app's 3D problem files, minkplan against OMPL's
RRTConnect, PRM and BIT* driven by the same FCL checker, in one run.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_omplapp.py [FOLDER] [--runs N] [--time-limit S]
        [--planners minkplan,ompl:RRTConnect,ompl:PRM,ompl:BITstar] [--problems a,b]
        [--out DIR]

FOLDER defaults to ``../shared/assets/omplapp``. Every ``.cfg`` in it is read as
OMPL.app reads it; a problem whose start and goal orientations differ is read
translation-only with the start's orientation throughout (``--hold-orientation start``),
and the table says so. Each planner runs N times (default 10; OMPL run ``k`` with seed
``k``; minkplan is deterministic, its first run is cold, the others warm), each with the
time limit of the file's ``[benchmark]`` section unless ``--time-limit`` is given. A
found path counts only when it passed the independent validation (FCL and OMPL's path
check); a minkplan ``no_path`` that an OMPL run contradicts (a valid path found) is
flagged.

Writes ``DIR/<date>-omplapp.md`` (the table), ``DIR/<date>-omplapp.json`` (every run)
and, per problem, ``DIR/<date>-omplapp/<problem>.log`` in OMPL's benchmark log format
(``ompl_benchmark_statistics.py DIR/<date>-omplapp/*.log -d bench.db`` reads them; Planner
Arena plots the database). DIR defaults to ``tests/benchmarks/results``.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import logging
import math
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))

import planner  # noqa: E402
from planner.errors import MinkplanError, ScenarioError  # noqa: E402
from planner.io import load_scenario  # noqa: E402
from planner.ompl_log import Run, write_log  # noqa: E402
from planner.output import jsonable  # noqa: E402
from planner.planning import plan  # noqa: E402

log = logging.getLogger("bench_omplapp")

PLANNERS = ("minkplan", "ompl:RRTConnect", "ompl:PRM", "ompl:BITstar")


def read(cfg: Path):
    """The problem, translation-only with the start's orientation when it turns."""
    try:
        return load_scenario(cfg), None
    except ScenarioError as error:
        if "--hold-orientation" not in str(error):
            raise
        return load_scenario(cfg, hold_orientation="start"), "start"


def one_run(scenario, name: str, seed: int) -> tuple[Run, dict]:
    settings = dataclasses.replace(scenario.settings, seed=seed)
    t0 = time.perf_counter()
    try:
        outcome = plan(dataclasses.replace(scenario, settings=settings), planner=name,
                       progress=False)
    except MinkplanError as error:
        return refused(name, seed, time.perf_counter() - t0, error)
    seconds = time.perf_counter() - t0
    validation = outcome.validation or {}
    valid = bool(outcome.found and validation.get("valid"))
    run = Run(seconds, str(outcome.status), outcome.length, outcome.clearance, valid,
              outcome.reason)
    return run, {"planner": name, "seed": seed, "status": str(outcome.status),
                 "reason": outcome.reason, "seconds": seconds, "valid": valid,
                 "length": outcome.length, "message": outcome.message}


def refused(name: str, seed: int, seconds: float, error: MinkplanError) -> tuple[Run, dict]:
    """A run the planner refused (a memory or size limit): not found, with the refusal."""
    reason = f"refused: {type(error).__name__}"
    run = Run(seconds, "not_found", reason=reason)
    return run, {"planner": name, "seed": seed, "status": "not_found", "reason": reason,
                 "seconds": seconds, "valid": False, "length": math.nan,
                 "message": str(error)}


def bench_problem(cfg: Path, planners: list[str], runs: int, time_limit: float | None):
    scenario, held = read(cfg)
    if time_limit is not None:
        scenario = dataclasses.replace(scenario, settings=dataclasses.replace(
            scenario.settings, time_limit=time_limit))
    t0 = time.perf_counter()
    per_planner: dict[str, list[Run]] = {}
    rows = []
    for name in planners:
        for k in range(runs):
            run, row = one_run(scenario, name, k)
            per_planner.setdefault(name, []).append(run)
            rows.append({"problem": cfg.stem, **row})
            log.info("%-14s %-16s run %d: %-9s %-16s %.3f s", cfg.stem, name, k, run.status,
                     run.reason, run.seconds)
    return scenario, held, per_planner, rows, time.perf_counter() - t0


def summary(runs: list[Run]) -> dict:
    secs = [r.seconds for r in runs]
    return {"found": sum(r.status == "found" and r.valid for r in runs),
            "no_path": sum(r.status == "no_path" for r in runs),
            "runs": len(runs), "median": statistics.median(secs), "max": max(secs),
            "warm_median": statistics.median(secs[1:]) if len(secs) > 1 else secs[0],
            "answers": sorted({f"{r.status} ({r.reason})" for r in runs})}


def table(results: list[dict], planners: list[str]) -> list[str]:
    head = "| problem | reading | " + " | ".join(planners) + " | contradicted |"
    lines = [head, "|" + "---|" * (len(planners) + 3)]
    for res in results:
        cells = []
        for name in planners:
            s = res["summary"][name]
            answer = (f"{s['found']}/{s['runs']} found" if s["found"] else
                      f"{s['no_path']}/{s['runs']} no_path" if s["no_path"] else
                      f"0/{s['runs']}")
            median = s["warm_median"] if name == "minkplan" else s["median"]
            cells.append(f"{answer}, {median:.3g} s (max {s['max']:.3g})")
        lines.append(f"| {res['problem']} | {res['reading']} | " + " | ".join(cells)
                     + f" | {'YES' if res['contradicted'] else 'no'} |")
    lines += ["", "Cells: valid answers of the runs, median and maximum seconds per run "
              "(minkplan: median of the warm runs). 'contradicted': minkplan said no_path "
              "while an OMPL run found a valid path."]
    return lines


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folder", nargs="?", default=str(ROOT.parent / "shared" / "assets" / "omplapp"))
    p.add_argument("--runs", type=int, default=10)
    p.add_argument("--time-limit", type=float, default=None)
    p.add_argument("--planners", default=",".join(PLANNERS))
    p.add_argument("--problems", default=None, help="comma-separated problem names")
    p.add_argument("--out", default=str(HERE / "results"))
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    planners = args.planners.split(",")
    cfgs = sorted(Path(args.folder).glob("*.cfg"))
    if args.problems:
        wanted = set(args.problems.split(","))
        cfgs = [c for c in cfgs if c.stem in wanted]
    stamp = datetime.date.today().isoformat()
    out = Path(args.out)
    logs = out / f"{stamp}-omplapp"
    results, every_run = [], []
    for cfg in cfgs:
        scenario, held, per_planner, rows, total = bench_problem(
            cfg, planners, args.runs, args.time_limit)
        every_run += rows
        ours = per_planner.get("minkplan", [])
        contradicted = any(r.status == "no_path" for r in ours) and any(
            r.status == "found" and r.valid for n, rs in per_planner.items() if n != "minkplan"
            for r in rs)
        results.append({"problem": cfg.stem, "reading": f"orientation held: {held}" if held
                        else "as given", "contradicted": contradicted,
                        "summary": {n: summary(r) for n, r in per_planner.items()}})
        write_log(logs / f"{cfg.stem}.log", experiment=cfg.stem,
                  setup=f"{cfg}\norientation held: {held or 'no (the problem translates)'}",
                  runs=per_planner, time_limit=scenario.settings.time_limit,
                  total_seconds=total, version=planner.__version__)
    lines = [f"# OMPL.app problems: minkplan vs OMPL's planners ({stamp})", "",
             f"{args.runs} runs per planner; time limit per run: "
             f"{args.time_limit or 'the file’s [benchmark] time_limit'}.", "",
             *table(results, planners)]
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{stamp}-omplapp.md").write_text("\n".join(lines) + "\n")
    (out / f"{stamp}-omplapp.json").write_text(json.dumps(jsonable(
        {"results": results, "runs": every_run}), indent=1) + "\n")
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
