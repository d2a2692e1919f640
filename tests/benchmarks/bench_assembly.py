"""Side-by-side benchmark: per-step removal planning of the assembly demos, minkplan's
octree planner vs OMPL's RRTConnect (driven by the FCL checker), on the same problems.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_assembly.py [--quick] [--runs N] [--time-limit S]
        [--assemblies a,b] [--planners minkplan,ompl:RRTConnect] [--out DIR]

For every demo under ``scenarios/assemblies/`` (the burr puzzles included) and every real
assembly of ``../shared/assets/assemblies/`` (Factory's round and rectangular pegs and M12
nut on its bolt, IndustReal's gears; left out, saying so, when that folder is absent):

0. ``load_assembly`` and ``plan_assembly`` in a fresh interpreter (as ``minkplan
   assemble`` runs; cut off after ``--fresh-timeout`` seconds): seconds (loading,
   search, CPU), peak resident memory, and the steps by method (straight / planned /
   group, a group's own steps included), against the targets (:data:`TARGETS`: every
   real assembly under 60 s and 2 GB, the six-piece burr under 10 s, pegs and holes
   under 1 s);
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

The nut on the bolt is planned with the interference tolerance of :data:`INTERFERENCE`
(its assembled pose overlaps the bolt's thread; the result says so).

Writes ``DIR/<date>-assembly.json`` (every run) and ``DIR/<date>-assembly.md`` (the
tables); DIR defaults to ``tests/benchmarks/results``.
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

DEMOS = ("peg_in_block", "pegs_and_holes", "latched_box", "linked_rings",
         "six_piece_burr", "three_piece_burr")
REAL = ("factory_round_peg_8mm", "factory_rect_peg_8mm", "factory_nut_bolt_m12",
        "industreal_gears")
ASSEMBLIES = DEMOS + REAL
ASSETS = ROOT.parent / "shared" / "assets" / "assemblies"

INTERFERENCE = {"factory_nut_bolt_m12": 0.0016}
"""Interference tolerances (metres) the real assemblies are planned with: the nut sits on
the bolt's head 1.6 mm below a pose its thread fits (FCL finds it free only at
1.55-1.70 mm up, and every 1.75 mm pitch above)."""

TARGETS = {**{name: (60.0, 2048.0) for name in REAL},
           "six_piece_burr": (10.0, None), "pegs_and_holes": (1.0, None)}
"""``(seconds, peak MB)`` a fresh run should stay under (``None``: no target)."""

FRESH_TIMEOUT = 600.0
"""Seconds after which a fresh run is cut off (reported as such)."""


def assembly_path(name: str) -> Path:
    """The YAML of a demo or of a real assembly."""
    if name in REAL:
        return ASSETS / name / f"{name}.yaml"
    return ROOT / "scenarios" / "assemblies" / f"{name}.yaml"

# run in a fresh interpreter: one assembly's seconds and peak memory, as the CLI sees them
_FRESH = """
import json, sys, time
sys.path.insert(0, "tests/benchmarks")  # the child runs in the repository root
from benchlib import peak_mb
t0, c0 = time.perf_counter(), time.process_time()
from planner import load_assembly, plan_assembly
interference = float(sys.argv[3]) if len(sys.argv) > 3 else None
assembly = load_assembly(sys.argv[1], interference=interference)
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
                  "status": result.status, "proved": result.proved,
                  "message": result.message,
                  "peak_mb": peak_mb(),
                  "steps_by_method": counts}))
"""


def fresh_run(path: Path, cache_dir: Path, interference: float | None = None,
              timeout: float = FRESH_TIMEOUT) -> dict:
    """Load and plan ``path`` in a new interpreter (cold decomposition cache); a run cut
    off after ``timeout`` seconds or refused is reported as such."""
    command = [sys.executable, "-c", _FRESH, str(path), str(cache_dir)]
    if interference is not None:
        command.append(repr(interference))
    t0 = time.perf_counter()
    try:
        out = subprocess.run(command, check=False, capture_output=True, text=True, cwd=ROOT,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"status": "timeout", "total_seconds": time.perf_counter() - t0,
                "message": f"cut off after {timeout:g} s"}
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or ["(no message)"])[-1]
        return {"status": "error", "total_seconds": time.perf_counter() - t0,
                "message": last}
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
          cache_dir: Path, fresh_timeout: float = FRESH_TIMEOUT) -> dict:
    path = assembly_path(name)
    interference = INTERFERENCE.get(name)
    fresh = fresh_run(path, Path(tempfile.mkdtemp(prefix="minkplan-bench-fresh-")),
                      interference, fresh_timeout)
    entry = {"assembly": name, "interference": interference, "fresh": fresh}
    if fresh["status"] in ("timeout", "error"):
        log.info("%s: fresh run %s after %.1f s: %s", name, fresh["status"],
                 fresh["total_seconds"], fresh["message"])
        return {**entry, "status": fresh["status"], "message": fresh["message"],
                "problems": []}
    log.info("%s: fresh run %.2f s (load %.2f s), peak %.0f MB, steps %s", name,
             fresh["total_seconds"], fresh["load_seconds"], fresh["peak_mb"],
             fresh["steps_by_method"])
    assembly = load_assembly(path, interference=interference)
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
    return {**entry, "status": result.status, "message": result.message,
            "order": result.order, "interlocked": result.interlocked,
            "search_seconds": search_seconds, "reuse": result.reuse, "fresh": fresh,
            "steps": [{"part": s.part, "method": s.method, "direction": s.direction,
                       "seconds": s.seconds} for s in result.removal],
            "problems": problems}


def _verdict(name: str, fresh: dict) -> str:
    """Whether a fresh run met its target (:data:`TARGETS`)."""
    seconds, megabytes = TARGETS.get(name, (None, None))
    if seconds is None:
        return "-"
    if fresh["status"] in ("timeout", "error"):
        return "missed"
    ok = fresh["total_seconds"] < seconds and (megabytes is None
                                               or fresh["peak_mb"] < megabytes)
    target = f"< {seconds:g} s" + ("" if megabytes is None else f", < {megabytes / 1024:g} GB")
    return f"{'met' if ok else 'missed'} ({target})"


def fresh_table(results: list[dict]) -> list[str]:
    """Per assembly: the fresh run against its target."""
    lines = ["| assembly | answer | fresh run s | load s | cpu s | peak MB | "
             "steps straight/planned/group | target |", "|---|---|---|---|---|---|---|---|"]
    for entry in results:
        f = entry["fresh"]
        if f["status"] in ("timeout", "error"):
            lines.append(f"| {entry['assembly']} | {f['status']}: {f['message']} | "
                         f"{f['total_seconds']:.2f} | - | - | - | - | "
                         f"{_verdict(entry['assembly'], f)} |")
            continue
        c = f["steps_by_method"]
        answer = f["status"] + (" (proved)" if f.get("proved") else "")
        if entry.get("interference"):
            answer += f", interference {entry['interference']:g}"
        lines.append(f"| {entry['assembly']} | {answer} | {f['total_seconds']:.2f} | "
                     f"{f['load_seconds']:.2f} | {f['cpu_seconds']:.2f} | "
                     f"{f['peak_mb']:.0f} | {c['straight']}/{c['planned']}/{c['group']} | "
                     f"{_verdict(entry['assembly'], f)} |")
    return lines


def step_table(results: list[dict], planners: list[str]) -> list[str]:
    """Per removal problem and planner: answers, seconds, length, ratio to minkplan."""
    base = planners[0]
    lines = ["| assembly | part | method | side | expect | planner | answer | median s | "
             "max s | length | ratio |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for entry in results:
        for problem in entry["problems"]:
            ref = problem["summary"].get(base, {}).get("median_seconds")
            for planner in planners:
                s = problem["summary"].get(planner)
                if s is None:
                    continue
                ratio = s["median_seconds"] / ref if ref and planner != base else None
                lines.append(
                    f"| {entry['assembly']} | {problem['part']} | {problem['method']} | "
                    f"{problem['direction'][:8]} | {problem['expected']} | {planner} | "
                    f"{s['correct']}/{s['runs']} | {fmt(s['median_seconds'])} | "
                    f"{fmt(s['max_seconds'])} | {fmt(s['median_length'], '.4g')} | "
                    f"{fmt(ratio, '.1f')} |")
    return lines


def totals_table(results: list[dict], planners: list[str]) -> list[str]:
    """Per assembly: the search in this process, the planners' summed medians, reuse."""
    base, *others = planners
    lines = ["| assembly | search s | " + " | ".join(f"sum {p} s" for p in planners)
             + " | " + " | ".join(f"ratio {p}" for p in others)
             + " | sums built/reused | verdicts computed/reused | enclosures proved/tried |",
             "|---|---|" + "---|" * (len(planners) + len(others)) + "---|---|---|"]
    for entry in results:
        if "reuse" not in entry:
            continue
        sums = [sum(p["summary"][name]["median_seconds"] for p in entry["problems"]
                    if name in p["summary"]) if entry["problems"] else None
                for name in planners]
        ratios = [x / sums[0] if sums[0] and x else None for x in sums[1:]]
        r = entry["reuse"]
        lines.append(f"| {entry['assembly']} | {entry['search_seconds']:.3f} | "
                     + " | ".join(fmt(x) for x in sums) + " | "
                     + " | ".join(fmt(x, '.1f') for x in ratios)
                     + f" | {r['sums_computed']}/{r['sums_reused']} | "
                       f"{r['verdicts_computed']}/{r['verdicts_reused']} | "
                       f"{r.get('enclosures_proved', 0)}/{r.get('enclosures_tried', 0)} |")
    return lines


def table(results: list[dict], planners: list[str]) -> list[str]:
    """The three tables, as Markdown."""
    return [*fresh_table(results), "", *step_table(results, planners), "",
            *totals_table(results, planners)]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 runs, 5 s time limit")
    ap.add_argument("--runs", type=int, default=None, help="runs per pair (default 5)")
    ap.add_argument("--time-limit", type=float, default=None,
                    help="seconds per run (default 10, --quick 5)")
    ap.add_argument("--assemblies", default=None, help="comma-separated subset")
    ap.add_argument("--planners", default=None, help="comma-separated, minkplan first")
    ap.add_argument("--out", default=str(HERE / "results"), help="results directory")
    ap.add_argument("--fresh-timeout", type=float, default=FRESH_TIMEOUT,
                    help=f"seconds before a fresh run is cut off (default {FRESH_TIMEOUT:g})")
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
    if not ASSETS.is_dir() and any(n in REAL for n in names):
        log.info("%s is absent: the real assemblies are left out", ASSETS)
        names = [n for n in names if n not in REAL]

    results = [bench(name, planners, runs, time_limit, cache_dir, args.fresh_timeout)
               for name in names]
    lines = table(results, planners)
    date = time.strftime("%Y-%m-%d")
    meta = {"runs": runs, "time_limit": time_limit, "planners": planners,
            "python": platform.python_version(), "machine": platform.machine(),
            "cpus": os.cpu_count(), "rayon_threads": os.environ.get("RAYON_NUM_THREADS"),
            "date": time.strftime("%Y-%m-%d %H:%M:%S"),
            "load": " ".join(f"{x:.1f}" for x in os.getloadavg())}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{date}-assembly.json").write_text(
        json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
    head = [f"# Assembly benchmark, {meta['date']}", "",
            f"{runs} runs per problem and planner, {time_limit:g} s limit; Python "
            f"{meta['python']} on {meta['cpus']} {meta['machine']} cores (load average "
            f"{meta['load']}); fresh runs: a new interpreter, cold decomposition cache.", ""]
    text = "\n".join(head + lines) + "\n"
    (out / f"{date}-assembly.md").write_text(text)
    sys.stdout.write(text)
    log.info("wrote %s and %s", out / f"{date}-assembly.json", out / f"{date}-assembly.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
