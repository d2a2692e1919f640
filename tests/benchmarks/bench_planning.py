"""Side-by-side benchmark: minkplan's octree planner vs OMPL's RRTConnect, PRM and BIT*
driven by the FCL checker, on every bundled scenario.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_planning.py [--quick] [--runs N] [--time-limit S]
        [--scenarios a,b] [--planners minkplan,ompl:RRTConnect] [--json out.json]

For every scenario and planner, N runs (default 10, ``--quick``: 3 runs and a 5 s
limit); OMPL runs use seeds 0..N-1 (minkplan is deterministic: its seed only seeds CoACD,
so it keeps the scenario's). Reported per pair:

* answer: how many runs gave the expected answer (``found`` for feasible scenarios,
  ``no_path`` for infeasible ones: minkplan proves it, OMPL can only time out unless the
  start collides);
* seconds: median and maximum planning time (validation excluded); for minkplan also the
  median C-space time (octree build + refinement) and search time (A* rounds) apart;
  decompositions are cached (one warm-up run first, its cold time reported separately);
* median path length of the found paths (all paths validated by FCL and OMPL on the
  original meshes, see ``planner.planning``).

Prints a table and writes everything to JSON (default
``tests/benchmarks/bench_planning.json``). Timings are wall-clock on whatever cores are
free.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))

from planner.io import load_scenario  # noqa: E402
from planner.planning import FOUND, NO_PATH, plan  # noqa: E402

EXPECTED = {
    "peg_in_hole": FOUND,
    "peg_in_hole_0.1": FOUND,
    "peg_in_hole_0.01": FOUND,
    "sealed_chamber_open": FOUND,
    "bug_trap": FOUND,
    "three_floor_maze": FOUND,
    "sealed_chamber": NO_PATH,
    "start_in_collision": NO_PATH,
}
PLANNERS = ("minkplan", "ompl:RRTConnect", "ompl:PRM", "ompl:BITstar")


def log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


def run_once(scenario, planner: str, seed: int, time_limit: float, cache_dir) -> dict:
    settings = dataclasses.replace(scenario.settings, seed=seed, time_limit=time_limit)
    t0 = time.perf_counter()
    outcome = plan(dataclasses.replace(scenario, settings=settings), planner=planner,
                   cache_dir=cache_dir, progress=False)
    wall = time.perf_counter() - t0
    t = outcome.timings
    planning = t.get("total", wall) - t.get("validate", 0.0)
    return {
        "status": outcome.status,
        "reason": outcome.reason,
        "seed": seed,
        "seconds": planning,
        "seconds_cspace": t.get("cspace"),
        "seconds_search": t.get("search"),
        "seconds_decompose": t.get("decompose"),
        "seconds_validate": t.get("validate"),
        "length": outcome.length if outcome.found else None,
        "clearance": outcome.clearance if outcome.found else None,
        "rounds": outcome.report.get("refinement", {}).get("rounds"),
        "leaves": outcome.report.get("cells", {}).get("leaves"),
        "message": outcome.message,
    }


def summarize(runs: list[dict], expected: str) -> dict:
    ok = [r for r in runs if r["status"] == expected]
    secs = [r["seconds"] for r in runs]
    lengths = [r["length"] for r in runs if r["length"] is not None]

    def med(key):
        vals = [r[key] for r in runs if r.get(key) is not None]
        return statistics.median(vals) if vals else None

    return {
        "expected": expected,
        "correct": len(ok),
        "runs": len(runs),
        "median_seconds": statistics.median(secs),
        "max_seconds": max(secs),
        "median_cspace": med("seconds_cspace"),
        "median_search": med("seconds_search"),
        "median_length": statistics.median(lengths) if lengths else None,
        "statuses": sorted({r["status"] for r in runs}),
    }


def fmt(x, spec=".3f") -> str:
    return "-" if x is None else format(x, spec)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 runs, 5 s time limit")
    ap.add_argument("--runs", type=int, default=None, help="runs per pair (default 10)")
    ap.add_argument("--time-limit", type=float, default=None,
                    help="seconds per run (default 10, --quick 5)")
    ap.add_argument("--scenarios", default=None, help="comma-separated subset")
    ap.add_argument("--planners", default=None, help="comma-separated subset")
    ap.add_argument("--json", default=str(HERE / "bench_planning.json"))
    args = ap.parse_args()
    runs = args.runs or (3 if args.quick else 10)
    time_limit = args.time_limit or (5.0 if args.quick else 10.0)
    names = args.scenarios.split(",") if args.scenarios else list(EXPECTED)
    planners = args.planners.split(",") if args.planners else list(PLANNERS)
    cache_dir = Path(tempfile.mkdtemp(prefix="minkplan-bench-cache-"))

    results = []
    for name in names:
        scenario = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
        expected = EXPECTED[name]
        for planner in planners:
            entry = {"scenario": name, "planner": planner}
            if planner == "minkplan":
                cold = run_once(scenario, planner, 0, time_limit, cache_dir)
                entry["cold_seconds"] = cold["seconds"]
                entry["cold_decompose_seconds"] = cold["seconds_decompose"]
            pair = []
            for k in range(runs):
                # minkplan is deterministic; its seed only seeds CoACD (cache key)
                seed = scenario.settings.seed if planner == "minkplan" else k
                r = run_once(scenario, planner, seed, time_limit, cache_dir)
                pair.append(r)
                log(f"{name:20s} {planner:16s} run {k}: {r['status']:9s} {r['seconds']:.3f} s")
            entry["runs"] = pair
            entry["summary"] = summarize(pair, expected)
            results.append(entry)

    header = (f"{'scenario':20s} {'planner':16s} {'answer':>8s} {'median s':>9s} "
              f"{'max s':>8s} {'cspace s':>9s} {'search s':>9s} {'length':>9s}  statuses")
    lines = [header, "-" * len(header)]
    for e in results:
        s = e["summary"]
        lines.append(
            f"{e['scenario']:20s} {e['planner']:16s} {s['correct']:>4d}/{s['runs']:<3d} "
            f"{fmt(s['median_seconds']):>9s} {fmt(s['max_seconds']):>8s} "
            f"{fmt(s['median_cspace']):>9s} {fmt(s['median_search']):>9s} "
            f"{fmt(s['median_length'], '.2f'):>9s}  {','.join(s['statuses'])}")
    sys.stdout.write("\n".join(lines) + "\n")
    meta = {
        "runs": runs,
        "time_limit": time_limit,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "rayon_threads": os.environ.get("RAYON_NUM_THREADS"),
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }
    Path(args.json).write_text(json.dumps({"meta": meta, "results": results}, indent=1))
    log(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
