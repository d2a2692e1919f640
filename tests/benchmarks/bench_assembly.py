"""Side-by-side benchmark: per-step removal planning of the assembly demos, minkplan's
octree planner vs OMPL's RRTConnect (driven by the FCL checker), on the same problems.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_assembly.py [--quick] [--runs N] [--time-limit S]
        [--assemblies a,b] [--planners minkplan,ompl:RRTConnect] [--out DIR]

For every demo under ``scenarios/assemblies/`` (the burr puzzles included):

0. ``load_assembly`` and ``plan_assembly`` in a fresh interpreter (as ``minkplan
   assemble`` runs): seconds (loading, search), peak resident memory, and the steps by
   method (straight / planned / group, a group's own steps included);
1. ``plan_assembly`` once (cold decomposition cache): the sequence (or the interlocked
   set), the whole search's time and what its pair cache computed and reused;
2. its removal problems (``planner.assembly.removal_problems``): every removal step of
   the sequence, with the parts present at that step and the goal on the side the part
   left by (expected ``found``), and for an interlocked result each part of the
   interlocked set with the others present (expected ``no_path``: minkplan proves it,
   RRTConnect can only run out of time);
3. each problem with each planner, N runs (default 5; ``--quick``: 3 runs, 5 s limit);
   OMPL run k uses seed k; minkplan is deterministic (decompositions cached and warm).

A group's step is not planned by the planners (they move one part); its members' own
steps are. Reported per problem and planner: runs with the expected answer, median and maximum
planning seconds (``plan``'s total without its path validation, as in
bench_planning.py), and the ratio of RRTConnect's median to minkplan's. Every found path
is re-validated by FCL at the assembly's contact tolerance. Ratios, not absolute times,
are the point: timings are wall clock on whatever cores are free.

Writes ``DIR/<date>-assembly.json`` (every run) and ``DIR/<date>-assembly.txt`` (the
table); DIR defaults to ``tests/benchmarks/results``.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(ROOT))

from removals import benchmark_removals  # noqa: E402

from planner import load_assembly, plan_assembly  # noqa: E402

log = logging.getLogger("bench_assembly")

ASSEMBLIES = ("peg_in_block", "pegs_and_holes", "latched_box", "linked_rings",
              "six_piece_burr", "three_piece_burr")

# run in a fresh interpreter: one assembly's seconds and peak memory, as the CLI sees them
_FRESH = """
import json, resource, sys, time
t0, c0 = time.perf_counter(), time.process_time()
from planner import load_assembly, plan_assembly
assembly = load_assembly(sys.argv[1])
t1 = time.perf_counter()
result = plan_assembly(assembly, cache_dir=sys.argv[2])
t2 = time.perf_counter()
counts = {"straight": 0, "planned": 0, "group": 0}
def count(steps):
    for s in steps:
        counts[s.method] += 1
        count(s.inner)
count(result.removal)
print(json.dumps({"load_seconds": t1 - t0, "search_seconds": t2 - t1,
                  "total_seconds": t2 - t0, "cpu_seconds": time.process_time() - c0,
                  "status": result.status,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "steps_by_method": counts}))
"""


def fresh_run(path: Path, cache_dir: Path) -> dict:
    """Load and plan ``path`` in a new interpreter (cold decomposition cache)."""
    out = subprocess.run([sys.executable, "-c", _FRESH, str(path), str(cache_dir)],
                         check=True, capture_output=True, text=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])
PLANNERS = ("minkplan", "ompl:RRTConnect")


def summarize(rows: list[dict]) -> dict:
    secs = [r["planning_seconds"] for r in rows]
    correct = [r for r in rows if r["status"] == r["expected"]
               and (r["valid"] is not False)]
    lengths = [r["length"] for r in rows if r["status"] == "found"]
    return {
        "runs": len(rows),
        "correct": len(correct),
        "statuses": sorted({r["status"] for r in rows}),
        "all_valid": all(r["valid"] for r in rows if r["status"] == "found"),
        "median_seconds": statistics.median(secs),
        "max_seconds": max(secs),
        "median_length": statistics.median(lengths) if lengths else None,
    }


def fmt(x, spec=".3f") -> str:
    return "-" if x is None else format(x, spec)


def bench(name: str, planners: list[str], runs: int, time_limit: float,
          cache_dir: Path) -> dict:
    path = ROOT / "scenarios" / "assemblies" / f"{name}.yaml"
    fresh = fresh_run(path, Path(tempfile.mkdtemp(prefix="minkplan-bench-fresh-")))
    log.info("%s: fresh run %.2f s (load %.2f s), peak %.0f MB, steps %s", name,
             fresh["total_seconds"], fresh["load_seconds"], fresh["peak_mb"],
             fresh["steps_by_method"])
    assembly = load_assembly(path)
    t0 = time.perf_counter()
    result = plan_assembly(assembly, cache_dir=cache_dir)
    search_seconds = time.perf_counter() - t0
    log.info("%s: %s (search %.2f s, cold cache)", name, result.message, search_seconds)
    rows = benchmark_removals(result, planners=planners, cache_dir=cache_dir, runs=runs,
                              time_limit=time_limit)
    problems = []
    for row in rows:
        key = (row["part"], tuple(row["obstacles"]))
        if not problems or problems[-1]["key"] != key:
            problems.append({"key": key, "part": row["part"], "method": row["method"],
                             "direction": row["direction"], "expected": row["expected"],
                             "obstacles": row["obstacles"], "planners": {}})
        problems[-1]["planners"].setdefault(row["planner"], []).append(row)
        log.info("%-15s %-8s %-16s run %d: %-9s %.3f s", name, row["part"], row["planner"],
                 row["run"], row["status"], row["planning_seconds"])
    for problem in problems:
        del problem["key"]
        problem["summary"] = {p: summarize(r) for p, r in problem["planners"].items()}
    return {"assembly": name, "status": result.status, "message": result.message,
            "order": result.order, "interlocked": result.interlocked,
            "search_seconds": search_seconds, "reuse": result.reuse, "fresh": fresh,
            "steps": [{"part": s.part, "method": s.method, "direction": s.direction,
                       "seconds": s.seconds} for s in result.removal],
            "problems": problems}


def table(results: list[dict], planners: list[str]) -> list[str]:
    base, *others = planners
    header = (f"{'assembly':15s} {'part':8s} {'method':12s} {'side':5s} {'expect':8s} "
              f"{'planner':16s} {'answer':>7s} {'median s':>9s} {'max s':>8s} "
              f"{'length':>7s} {'ratio':>7s}")
    lines = [header, "-" * len(header)]
    totals: dict[tuple[str, str], float] = {}
    for entry in results:
        for problem in entry["problems"]:
            ref = problem["summary"].get(base, {}).get("median_seconds")
            for planner in planners:
                s = problem["summary"].get(planner)
                if s is None:
                    continue
                totals[entry["assembly"], planner] = (totals.get((entry["assembly"], planner),
                                                                 0.0) + s["median_seconds"])
                ratio = (s["median_seconds"] / ref if ref and planner != base else None)
                lines.append(
                    f"{entry['assembly']:15s} {problem['part']:8s} {problem['method']:12s} "
                    f"{problem['direction'][:5]:5s} {problem['expected']:8s} {planner:16s} "
                    f"{s['correct']:>3d}/{s['runs']:<3d} {fmt(s['median_seconds']):>9s} "
                    f"{fmt(s['max_seconds']):>8s} {fmt(s['median_length'], '.2f'):>7s} "
                    f"{fmt(ratio, '.1f'):>7s}")
    lines += ["", f"{'assembly':17s} {'fresh run s':>11s} {'load s':>7s} {'cpu s':>7s} "
              f"{'peak MB':>8s}  steps straight/planned/group"]
    for entry in results:
        f = entry["fresh"]
        c = f["steps_by_method"]
        lines.append(f"{entry['assembly']:17s} {f['total_seconds']:>11.2f} "
                     f"{f['load_seconds']:>7.2f} {f['cpu_seconds']:>7.2f} "
                     f"{f['peak_mb']:>8.0f}  "
                     f"{c['straight']}/{c['planned']}/{c['group']}")
    lines += ["", f"{'assembly':15s} {'search s':>9s} "
              + " ".join(f"{'sum ' + p:>22s}" for p in planners)
              + "  " + " ".join(f"{'ratio ' + p:>22s}" for p in others)
              + "  sums built/reused, verdicts computed/reused"]
    for entry in results:
        name = entry["assembly"]
        sums = [totals.get((name, p)) for p in planners]
        ratios = [totals.get((name, p)) / sums[0] if sums[0] and totals.get((name, p))
                  else None for p in others]
        r = entry["reuse"]
        lines.append(f"{name:15s} {entry['search_seconds']:>9.3f} "
                     + " ".join(f"{fmt(s):>22s}" for s in sums) + "  "
                     + " ".join(f"{fmt(x, '.1f'):>22s}" for x in ratios)
                     + f"  {r['sums_computed']}/{r['sums_reused']}, "
                       f"{r['verdicts_computed']}/{r['verdicts_reused']}")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 runs, 5 s time limit")
    ap.add_argument("--runs", type=int, default=None, help="runs per pair (default 5)")
    ap.add_argument("--time-limit", type=float, default=None,
                    help="seconds per run (default 10, --quick 5)")
    ap.add_argument("--assemblies", default=None, help="comma-separated subset")
    ap.add_argument("--planners", default=None, help="comma-separated, minkplan first")
    ap.add_argument("--out", default=str(HERE / "results"), help="results directory")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    logging.getLogger("planner").setLevel(logging.WARNING)
    runs = args.runs or (3 if args.quick else 5)
    time_limit = args.time_limit or (5.0 if args.quick else 10.0)
    names = args.assemblies.split(",") if args.assemblies else list(ASSEMBLIES)
    unknown = sorted(set(names) - set(ASSEMBLIES))
    if unknown:
        ap.error(f"--assemblies: unknown {', '.join(unknown)} (known: {', '.join(ASSEMBLIES)})")
    planners = args.planners.split(",") if args.planners else list(PLANNERS)
    cache_dir = Path(tempfile.mkdtemp(prefix="minkplan-bench-cache-"))

    results = [bench(name, planners, runs, time_limit, cache_dir) for name in names]
    lines = table(results, planners)
    date = time.strftime("%Y-%m-%d")
    meta = {"runs": runs, "time_limit": time_limit, "planners": planners,
            "python": platform.python_version(), "machine": platform.machine(),
            "cpus": os.cpu_count(), "rayon_threads": os.environ.get("RAYON_NUM_THREADS"),
            "date": time.strftime("%Y-%m-%d %H:%M:%S")}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{date}-assembly.json").write_text(
        json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
    text = "\n".join(lines) + "\n"
    (out / f"{date}-assembly.txt").write_text(text)
    sys.stdout.write(text)
    log.info("wrote %s and %s", out / f"{date}-assembly.json", out / f"{date}-assembly.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
