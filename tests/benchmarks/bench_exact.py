"""Side-by-side benchmark: the exact C-obstacle source (boundary convolution, no
decomposition) against the decomposition source (CoACD cold and cached), issue 6.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_exact.py [--quick] [--runs N] [--cold-runs N]
        [--cases peg_in_hole,sum:torus+ball@1%,...] [--samples N] [--out DIR]

Cases, all in this one process:

1. planning: ``scenarios/peg_in_hole.yaml`` (CoACD block), ``peg_in_hole_0.1`` and
   ``peg_in_hole_0.01`` (blocks of convex bars: no CoACD, so "cold" only adds the
   trivial exact decomposition);
2. planning: the removal problems of ``scenarios/assemblies/pegs_and_holes.yaml``
   (``planner.assembly.removal_problems`` of a ``plan_assembly`` run made beforehand in a
   throw-away cache, each as a ``removal_scenario``: start in the assembled pose, in
   contact), plus the upper plate's removal from a start lifted out of contact, along
   +z and along -x;
3. Minkowski sums of tests/test_minkowski.py's ``l_bracket+icosphere`` and ``torus+ball``
   at eps 1 % and 0.5 % of the sum's bounding-box diagonal;
4. planning: OMPL.app's Easy (``../shared/assets/omplapp/Easy.cfg``, via
   ``planner.io.load_omplapp``).

Each case is run three ways: ``exact=True``; ``exact=False`` cold (a fresh, empty
decomposition cache directory: CoACD runs for non-convex bodies); ``exact=False`` cached
(the last cold run's directory again). Cold runs ``--cold-runs`` times (default 3, each in
its own fresh directory; only once when a cold run takes over ``--cold-budget`` seconds);
exact and cached ``--runs`` times (default 3), alternated so that drift on a shared
machine hits both alike; medians are reported. Planning seconds are
``plan``'s total without its path validation (as in bench_planning.py); sum seconds are
the wall clock of ``minkowski_sum``.

Reported per case: the three medians, exact/cached and exact/cold, cells (the octree's
leaves by label from ``report["cells"]`` or ``stats["cells"]``), and the answers:
planning status, reason, whether a no-path certificate is exact, FCL validity of found
paths; for sums the error bound, its kind and whether it is proved, the triangle count,
an FCL-oracle Hausdorff estimate of the exact result (``--samples``, 0 to skip) and the
sampled Hausdorff distance between the two sources' surfaces. Answers "agree" when the
planning status is the same (and found paths are FCL-valid), or for sums when the two
surfaces are within the sum of their error bounds of each other.

The issue's target, checked per case: exact <= 2x the cached decomposition time, and
faster than a cold CoACD run. Ratios, not absolute times, are the point: timings are
wall clock on whatever cores are free (RAYON_NUM_THREADS is recorded).

Writes ``DIR/<date>-exact.json`` (every run) and ``DIR/<date>-exact.md`` (the table);
DIR defaults to tests/benchmarks/results, the date to 2026-11-22 (``--date``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import math
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE.parent))     # tests/: shapes, oracle
sys.path.insert(0, str(ROOT))            # repository root: planner

from benchlib import jsonable  # noqa: E402

import planner  # noqa: E402
from planner.assembly import plan_assembly, removal_problems, removal_scenario  # noqa: E402
from planner.io import load_assembly, load_omplapp, load_scenario  # noqa: E402
from planner.planning import FOUND, NO_PATH, plan  # noqa: E402

log = logging.getLogger("bench_exact")

OMPLAPP_EASY = ROOT.parent / "shared" / "assets" / "omplapp" / "Easy.cfg"
SUM_PAIRS = ("l_bracket+icosphere", "torus+ball")
SUM_EPS = (0.01, 0.005)
TARGET_CACHED_RATIO = 2.0
LIFT = 0.01     # pegs_and_holes variants: upper plate lifted out of contact (diagonal 2.4)

_TEMP_DIRS: list[str] = []


def fresh_dir(tag: str) -> str:
    d = tempfile.mkdtemp(prefix=f"minkplan-bench-exact-{tag}-")
    _TEMP_DIRS.append(d)
    return d


def dir_entries(path: str) -> int:
    return sum(len(files) for _, _, files in os.walk(path))


# --------------------------------------------------------------------------------------
# cases
# --------------------------------------------------------------------------------------

def sum_pair(name: str):
    import shapes  # noqa: PLC0415 (tests/shapes.py, as in tests/test_minkowski.py)
    return {
        "l_bracket+icosphere": lambda: (shapes.l_bracket(), shapes.icosphere(2, 0.5)),
        "torus+ball": lambda: (shapes.torus(10.0, 3.0, 32, 16), shapes.icosphere(2, 0.9)),
    }[name]()


def assembly_cases() -> list[dict]:
    """The removal problems of pegs_and_holes, from a plan_assembly run in a throw-away
    cache (so the benchmark's cold runs stay cold)."""
    assembly = load_assembly(ROOT / "scenarios" / "assemblies" / "pegs_and_holes.yaml")
    t0 = time.perf_counter()
    try:
        result = plan_assembly(assembly, cache_dir=fresh_dir("assembly-setup"))
        problems = removal_problems(result)
        log.info("pegs_and_holes: plan_assembly %.2fs, %d removal problem(s)",
                 time.perf_counter() - t0, len(problems))
    except Exception as exc:  # noqa: BLE001 - fall back to the obvious problem
        log.warning("pegs_and_holes: plan_assembly failed (%s: %s); using upper out along "
                    "+z", type(exc).__name__, exc)
        problems = [{"part": "upper", "obstacles": ["lower"], "direction": "+z",
                     "expected": FOUND, "method": "fallback"}]
    cases = []
    for p in problems:
        direction = p["direction"] if isinstance(p["direction"], str) else "vector"
        scenario = removal_scenario(assembly, p["part"], p["obstacles"], p["direction"])
        cases.append({"name": f"pegs_and_holes: remove {p['part']} {direction}",
                      "kind": "plan", "expected": p["expected"],
                      "make": (lambda s=scenario: s)})
    # The removal problems start in the assembled pose, in (tolerated) contact. The same
    # question with the upper plate lifted by LIFT out of contact (pegs still in the
    # holes), straight up and out sideways (-x: up first, then across; the roadmap is
    # needed), so the two sources are also compared where the planner does not have to
    # step out of contact first.
    for direction in ("+z", "-x"):
        scenario = removal_scenario(assembly, "upper", ["lower"], direction)
        lifted = dataclasses.replace(scenario, start=np.array([0.0, 0.0, LIFT]))
        cases.append({"name": f"pegs_and_holes: upper lifted {LIFT:g}, out {direction}",
                      "kind": "plan", "expected": FOUND, "make": (lambda s=lifted: s)})
    return cases


def all_cases() -> list[dict]:
    cases = []
    for name in ("peg_in_hole", "peg_in_hole_0.1", "peg_in_hole_0.01"):
        path = ROOT / "scenarios" / f"{name}.yaml"
        cases.append({"name": name, "kind": "plan", "expected": FOUND,
                      "make": (lambda p=path: load_scenario(p))})
    cases.append({"name": "pegs_and_holes", "kind": "assembly"})  # expanded lazily
    for pair in SUM_PAIRS:
        for rel in SUM_EPS:
            cases.append({"name": f"sum:{pair}@{100 * rel:g}%", "kind": "sum",
                          "pair": pair, "rel_eps": rel})
    cases.append({"name": "omplapp:Easy", "kind": "plan", "expected": FOUND,
                  "make": (lambda: load_omplapp(OMPLAPP_EASY)),
                  "available": OMPLAPP_EASY.is_file()})
    return cases


# --------------------------------------------------------------------------------------
# one run
# --------------------------------------------------------------------------------------

def run_plan(scenario, exact: bool, cache_dir: str) -> dict:
    settings = dataclasses.replace(scenario.settings, exact=exact)
    t0 = time.perf_counter()
    outcome = plan(dataclasses.replace(scenario, settings=settings), cache_dir=cache_dir,
                   progress=False)
    wall = time.perf_counter() - t0
    t = outcome.timings
    report = outcome.report
    cert = outcome.certificate
    fcl = outcome.validation.get("fcl") or {}
    return {
        "status": outcome.status,
        "reason": outcome.reason,
        "seconds": t.get("total", wall) - t.get("validate", 0.0),
        "wall": wall,
        "timings": dict(t),
        "source": (report.get("source") or {}).get("used"),
        "source_why": (report.get("source") or {}).get("why"),
        "cells": (report.get("cells") or {}).get("total"),
        "leaves": (report.get("cells") or {}).get("leaves"),
        "decomposition": report.get("decomposition"),
        "certificate_exact": None if cert is None else cert.get("exact"),
        "certificate_relative_to": None if cert is None else cert.get("relative_to"),
        "fcl_valid": fcl.get("valid") if outcome.found else None,
        "length": outcome.length if outcome.found else None,
        "message": outcome.message,
    }


def run_sum(a, b, eps: float, exact: bool, cache_dir: str) -> tuple[dict, object]:
    t0 = time.perf_counter()
    r = planner.minkowski_sum(a, b, eps=eps, exact=exact, cache_dir=cache_dir,
                              progress=False)
    wall = time.perf_counter() - t0
    s = r.stats
    dec = s.get("decomposition") or {}
    return {
        "seconds": wall,
        "stats_seconds": s.get("seconds"),
        "source": s.get("source"),
        "cells": s.get("cells"),
        "leaves": int(sum((s.get("cells") or {}).values())),
        "error_bound": r.error_bound,
        "bound_kind": r.bound_kind,
        "bound_guaranteed": r.bound_guaranteed,
        "exact": r.exact,
        "triangles": len(r.mesh.faces),
        "complex_cells": s.get("complex_cells"),
        "decomposition": {k: {kk: v.get(kk) for kk in ("method", "pieces", "exact", "excess",
                                                          "cache_hit", "seconds")}
                          for k, v in dec.items()} if dec else None,
    }, r


# --------------------------------------------------------------------------------------
# one case
# --------------------------------------------------------------------------------------

def _med(runs: list[dict]) -> float | None:
    secs = [r["seconds"] for r in runs if "seconds" in r]
    return statistics.median(secs) if secs else None


def _attempt(fn, what: str) -> dict:
    """A failure (exception) is data: recorded with its traceback, the case goes on."""
    try:
        return fn()
    except Exception as exc:  # noqa: BLE001
        log.error("%s failed: %s: %s", what, type(exc).__name__, exc)
        return {"error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc(limit=8)}


def measure(case: dict, runs: int, cold_runs: int, cold_budget: float, samples: int,
            seed: int) -> dict:
    name, kind = case["name"], case["kind"]
    row: dict = {"case": name, "kind": kind}
    log.info("[%s]", name)
    exact_dir = fresh_dir("exact")          # the exact source should not need it
    results = {}

    if kind == "plan":
        scenario = case["make"]()
        row["expected"] = case["expected"]
        row["triangles"] = {"robot": len(scenario.robot.mesh.faces),
                            "obstacles": [len(b.mesh.faces) for b in scenario.obstacles]}

        def one(exact, cache_dir):
            return run_plan(scenario, exact, cache_dir)
    else:
        a, b = sum_pair(case["pair"])
        lo = a.bounds[0] + b.bounds[0]
        hi = a.bounds[1] + b.bounds[1]
        diag = float(np.linalg.norm(hi - lo))
        eps = case["rel_eps"] * diag
        row.update(rel_eps=case["rel_eps"], eps=eps, diagonal=diag,
                   triangles={"a": len(a.faces), "b": len(b.faces)})

        def one(exact, cache_dir):
            d, r = run_sum(a, b, eps, exact, cache_dir)
            results[exact] = r          # the last result of each source, for comparison
            return d

    cold, cached, exact_runs = [], [], []
    cache_dir = None
    for k in range(cold_runs):
        cache_dir = fresh_dir("cold")
        r = _attempt(lambda: one(False, cache_dir), f"{name} decomposition cold")
        r["cache_entries_after"] = dir_entries(cache_dir)
        cold.append(r)
        log.info("  cold   %d: %s", k, _brief(r))
        if r.get("seconds", math.inf) > cold_budget:   # not cheap: one cold run only
            break
    for k in range(runs):
        r = _attempt(lambda: one(True, exact_dir), f"{name} exact")
        exact_runs.append(r)
        log.info("  exact  %d: %s", k, _brief(r))
        r = _attempt(lambda: one(False, cache_dir), f"{name} decomposition cached")
        cached.append(r)
        log.info("  cached %d: %s", k, _brief(r))
    row["exact_cache_entries"] = dir_entries(exact_dir)   # 0: nothing decomposed
    row["runs"] = {"exact": exact_runs, "cold": cold, "cached": cached}
    row["seconds"] = {"exact": _med(exact_runs), "cold": _med(cold), "cached": _med(cached)}
    se, sc, so = row["seconds"]["exact"], row["seconds"]["cached"], row["seconds"]["cold"]
    row["ratio_exact_cached"] = se / sc if se is not None and sc else None
    row["ratio_exact_cold"] = se / so if se is not None and so else None
    row["meets_2x_cached"] = (row["ratio_exact_cached"] is not None
                              and row["ratio_exact_cached"] <= TARGET_CACHED_RATIO)
    row["faster_than_cold"] = row["ratio_exact_cold"] is not None and row["ratio_exact_cold"] < 1
    row["coacd_ran_cold"] = _coacd_ran(cold[0]) if cold else None

    e = next((r for r in reversed(exact_runs) if "error" not in r), None)
    d = next((r for r in reversed(cached) if "error" not in r), None)
    row["answer"] = {"exact": e, "decomposition": d}
    if kind == "plan":
        row["agree"], row["agree_note"] = _plan_agreement(e, d, case["expected"],
                                                          exact_runs, cached)
    else:
        row["agree"], row["agree_note"] = _sum_agreement(row, results, a, b, samples, seed)
    return row


def _coacd_ran(run: dict) -> bool | None:
    dec = run.get("decomposition")
    if not dec:
        return None
    text = json.dumps(jsonable(dec)).lower()
    return "coacd" in text


def _brief(r: dict) -> str:
    if "error" in r:
        return "ERROR " + r["error"]
    ans = r.get("status") or f"bound {r.get('error_bound', float('nan')):.4g}"
    return f"{r['seconds']:.3f}s {r.get('source')} {ans} leaves {r.get('leaves')}"


def _plan_agreement(e, d, expected, exact_runs, cached) -> tuple[bool | None, str]:
    if e is None or d is None:
        return None, "a source failed"
    notes = []
    statuses_e = {r.get("status") for r in exact_runs if "error" not in r}
    statuses_d = {r.get("status") for r in cached if "error" not in r}
    if len(statuses_e) > 1 or len(statuses_d) > 1:
        notes.append(f"answers vary between runs (exact {sorted(statuses_e)}, "
                     f"decomposition {sorted(statuses_d)})")
    if e["status"] != expected:
        notes.append(f"EXACT answered {e['status']} ({e['reason']}), expected {expected}")
    if d["status"] != expected:
        notes.append(f"decomposition answered {d['status']} ({d['reason']}), expected "
                     f"{expected}")
    for tag, r in (("exact", e), ("decomposition", d)):
        if r["status"] == FOUND and r.get("fcl_valid") is False:
            notes.append(f"{tag} path NOT FCL-valid")
        if r["status"] == NO_PATH and r.get("certificate_exact") is not True:
            notes.append(f"{tag} no-path certificate not exact")
    agree = (e["status"] == d["status"]
             and not any(r["status"] == FOUND and r.get("fcl_valid") is False for r in (e, d)))
    return agree, "; ".join(notes)


def _sum_agreement(row, results, a, b, samples, seed) -> tuple[bool | None, str]:
    import oracle  # noqa: PLC0415 (tests/oracle.py)
    re_, rd = results.get(True), results.get(False)
    if re_ is None or rd is None:
        return None, "a source failed"
    notes = []
    d_ed, d_de = oracle.sampled_hausdorff(re_.mesh, rd.mesh, n=max(samples, 1) * 20,
                                          seed=seed)
    row["hausdorff_exact_to_dec"], row["hausdorff_dec_to_exact"] = d_ed, d_de
    allowed = re_.error_bound + rd.error_bound
    agree = max(d_ed, d_de) <= allowed
    if not agree:
        notes.append(f"surfaces {max(d_ed, d_de):.3g} apart > bounds' sum {allowed:.3g}")
    if samples > 0:   # the exact result against the independent FCL oracle
        t0 = time.perf_counter()
        t2r, r2t = oracle.hausdorff_estimate(re_.mesh, a, b, n=samples, seed=seed)
        row["oracle_exact"] = {"true_to_result": t2r, "result_to_true": r2t,
                               "samples": samples, "seconds": time.perf_counter() - t0}
        if max(t2r, r2t) > re_.error_bound:
            notes.append(f"EXACT result outside its bound by the oracle: "
                         f"{max(t2r, r2t):.3g} > {re_.error_bound:.3g}")
        oracle.clear_caches()
    if re_.bound_kind != "two-sided" or not re_.bound_guaranteed:
        notes.append(f"exact bound {re_.bound_kind}, guaranteed={re_.bound_guaranteed}")
    return agree, "; ".join(notes)


# --------------------------------------------------------------------------------------
# table
# --------------------------------------------------------------------------------------

def fmt(x, spec=".3f") -> str:
    if x is None:
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec)


def _stage_seconds(r, kind) -> float | None:
    """The stage the two sources differ in: the C-space build (octree, and refinement) of
    a plan; a sum's octree, surface extraction and (decomposition) pairwise sums."""
    if r is None:
        return None
    if kind == "plan":
        return (r.get("timings") or {}).get("cspace")
    st = r.get("stats_seconds") or {}
    return sum(st.get(k, 0.0) for k in ("source", "pairwise", "octree", "surface"))


def _stage_ratio(e, d, kind) -> float | None:
    se, sd = _stage_seconds(e, kind), _stage_seconds(d, kind)
    return se / sd if se is not None and sd else None


def _cells(r) -> str:
    if not r or not r.get("cells"):
        return "-"
    c = r["cells"]
    return f"{r['leaves']} ({c.get('mixed', 0)} mixed)"


def _answer(r, kind) -> str:
    if r is None:
        return "ERROR"
    if kind == "plan":
        s = r["status"]
        if s == FOUND:
            s += ", FCL ok" if r.get("fcl_valid") else ", FCL FAIL"
        elif s == NO_PATH:
            s += ", cert exact" if r.get("certificate_exact") else ", cert not exact"
        else:
            s += f" ({r['reason']})"
        return s
    g = "" if r.get("bound_guaranteed") else ", not proved"
    return f"{fmt(r['error_bound'], '.3g')} {r['bound_kind']}{g}"


COLUMNS = ("case", "exact s", "dec cold s", "dec cached s", "exact/cached", "exact/cold",
           "stage exact/cached", "target", "cells exact", "cells dec", "answer exact",
           "answer dec", "agree")


def _cold_ok(row: dict) -> bool:
    """The second half of the target: faster than a cold CoACD run. When the cold run ran
    no CoACD (every body convex), there is nothing to beat: only "<= 2x cached" counts."""
    return bool(row.get("faster_than_cold")) or row.get("coacd_ran_cold") is False


def table(rows: list[dict]) -> str:
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "|".join("---" for _ in COLUMNS) + "|"]
    notes = []
    for row in rows:
        if "skipped" in row:
            notes.append(f"{row['case']}: skipped ({row['skipped']})")
            continue
        s, kind = row["seconds"], row["kind"]
        e, d = row["answer"]["exact"], row["answer"]["decomposition"]
        failed = e is None or d is None
        cold_ok = _cold_ok(row)
        target = ("ERROR" if failed else
                  "yes" if row["meets_2x_cached"] and cold_ok else
                  "no: " + ", ".join(t for t, ok in (("> 2x cached", row["meets_2x_cached"]),
                                                      ("slower than cold", cold_ok)) if not ok))
        if row.get("coacd_ran_cold") is False and not failed:
            target += " (no CoACD run to beat)"
        lines.append("| " + " | ".join([
            row["case"], fmt(s["exact"]),
            fmt(s["cold"]) + ("" if len(row["runs"]["cold"]) == len(row["runs"]["exact"])
                              else f" (n={len(row['runs']['cold'])})"),
            fmt(s["cached"]),
            fmt(row["ratio_exact_cached"], ".2f"), fmt(row["ratio_exact_cold"], ".2f"),
            fmt(_stage_ratio(e, d, kind), ".1f"), target, _cells(e), _cells(d),
            _answer(e, kind), _answer(d, kind),
            {True: "yes", False: "**no**", None: "-"}[row["agree"]],
        ]) + " |")
        if row.get("agree_note"):
            notes.append(f"{row['case']}: {row['agree_note']}")
        for tag in ("exact", "cold", "cached"):
            errs = [r["error"] for r in row["runs"][tag] if "error" in r]
            if errs:
                notes.append(f"{row['case']}: {tag} failed {len(errs)}x: {errs[0]}")
        if row.get("exact_cache_entries"):
            notes.append(f"{row['case']}: the exact source wrote {row['exact_cache_entries']} "
                         f"file(s) into its cache directory")
        if "oracle_exact" in row:
            o = row["oracle_exact"]
            notes.append(f"{row['case']}: exact vs FCL oracle: Hausdorff true→result "
                         f"{o['true_to_result']:.3g}, result→true {o['result_to_true']:.3g} "
                         f"(bound {e['error_bound']:.3g}); exact↔dec surfaces "
                         f"{row['hausdorff_exact_to_dec']:.3g} / "
                         f"{row['hausdorff_dec_to_exact']:.3g}")
    return "\n".join(lines + [""] + [f"- {n}" for n in notes])


LEGEND = """\
Seconds: medians (exact and cached: --runs runs, alternated; cold: --cold-runs runs, each
in a fresh empty decomposition cache, one run when it is expensive). Planning: `plan`'s
total without path validation; sums: wall clock of `minkowski_sum`. stage exact/cached:
the stage the sources differ in, last run of each (planning: the C-space build,
`timings["cspace"]`; sums: octree + surface extraction, + pairwise sums for the
decomposition; without decomposition, graph, search, simplification). target: the issue's
"exact <= 2x cached decomposition, and faster than cold CoACD"; "(no CoACD run to beat)":
every body was convex or a union of convex bodies, so the cold run ran no CoACD and only
the first half applies (`exact: auto` picks the decomposition for such inputs anyway).
cells: octree leaves (mixed leaves). answer: planning status (FCL validity of the path /
exactness of the no-path certificate); sums: error bound, its kind and whether it is
proved. agree: same planning status (valid paths), or sum surfaces within the sum of
their bounds.
"""


# --------------------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------------------

def limit_memory(gigabytes: float) -> None:
    """Cap the address space so a runaway case fails here, not in the OOM killer."""
    if gigabytes <= 0:
        return
    import resource  # noqa: PLC0415
    limit = int(gigabytes * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 run each, no oracle")
    ap.add_argument("--runs", type=int, default=None,
                    help="exact and cached runs per case (default 3, --quick 1)")
    ap.add_argument("--cold-runs", type=int, default=None,
                    help="cold decomposition runs per case, each in a fresh cache (default "
                         "3, --quick 1)")
    ap.add_argument("--cold-budget", type=float, default=10.0,
                    help="repeat cold runs only while one takes at most this many seconds")
    ap.add_argument("--cases", default=None,
                    help="comma-separated subset of case names (pegs_and_holes for all its "
                         "removal problems)")
    ap.add_argument("--samples", type=int, default=None,
                    help="FCL-oracle samples for the exact sums (default 200, --quick 0)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-memory-gb", type=float, default=8.0,
                    help="address-space cap for this process (0: none)")
    ap.add_argument("--out", type=Path, default=HERE / "results")
    ap.add_argument("--date", default="2026-11-22")
    ap.add_argument("--from-json", type=Path, default=None,
                    help="measure nothing: rewrite the markdown table of this JSON")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    for noisy in ("planner", "trimesh"):
        logging.getLogger(noisy).setLevel(logging.WARNING)
    limit_memory(args.max_memory_gb)
    try:
        return _run(args)
    finally:
        for d in _TEMP_DIRS:
            shutil.rmtree(d, ignore_errors=True)


def markdown(meta: dict, rows: list[dict], date: str) -> str:
    return (f"# Exact source vs decomposition ({date})\n\n"
            f"`python tests/benchmarks/bench_exact.py` — {meta['runs']} run(s) exact and "
            f"cached, up to {meta['cold_runs']} cold (one when over "
            f"{meta.get('cold_budget', 10.0):g} s); {meta['cpus']} CPUs, native threads "
            f"{meta['native_threads']}; started {meta['started']}, total "
            f"{meta['elapsed_seconds']:.0f} s.\n\n" + table(rows) + "\n\n" + LEGEND)


def _rerender(args) -> int:
    doc = json.loads(args.from_json.read_text())
    md_path = args.from_json.with_suffix(".md")
    md_path.write_text(markdown(doc["meta"], doc["rows"], args.date))
    sys.stdout.write(table(doc["rows"]) + "\n")
    log.info("wrote %s", md_path)
    return 0


def _run(args) -> int:
    if args.from_json is not None:
        return _rerender(args)
    runs = args.runs or (1 if args.quick else 3)
    args.cold_runs = args.cold_runs or (1 if args.quick else 3)
    samples = args.samples if args.samples is not None else (0 if args.quick else 200)
    wanted = set(args.cases.split(",")) if args.cases else None
    args.out.mkdir(parents=True, exist_ok=True)
    json_path = args.out / f"{args.date}-exact.json"
    md_path = args.out / f"{args.date}-exact.md"
    meta = {
        "runs": runs, "cold_runs": args.cold_runs, "cold_budget": args.cold_budget,
        "samples": samples, "seed": args.seed,
        "load_average_start": os.getloadavg(),
        "python": platform.python_version(), "platform": platform.platform(),
        "cpus": os.cpu_count(), "rayon_threads": os.environ.get("RAYON_NUM_THREADS"),
        "native_threads": planner._minkowski_core.num_threads()
        if hasattr(planner, "_minkowski_core") else None,
        "started": time.strftime("%Y-%m-%d %H:%M:%S"),
    }
    rows: list[dict] = []
    t_start = time.perf_counter()

    def save():
        meta["elapsed_seconds"] = time.perf_counter() - t_start
        meta["load_average_end"] = os.getloadavg()
        json_path.write_text(json.dumps(jsonable({"meta": meta, "rows": rows}), indent=1,
                                        allow_nan=True))
        md_path.write_text(markdown(meta, rows, args.date))

    cases = []
    for case in all_cases():
        if case["kind"] == "assembly":
            if wanted is None or case["name"] in wanted or any(
                    w.startswith(case["name"]) for w in wanted):
                cases += [c for c in assembly_cases()
                          if wanted is None or case["name"] in wanted or c["name"] in wanted]
        elif wanted is None or case["name"] in wanted:
            cases.append(case)
    for case in cases:
        if not case.get("available", True):
            rows.append({"case": case["name"], "kind": case["kind"],
                         "skipped": "input not available"})
            continue
        rows.append(measure(case, runs, args.cold_runs, args.cold_budget, samples,
                            args.seed))
        save()   # after every case: a crash in native code keeps the rest

    save()
    sys.stdout.write(table(rows) + "\n\n" + LEGEND)
    met = [r["case"] for r in rows if r.get("meets_2x_cached") and _cold_ok(r)]
    missed = [r["case"] for r in rows if "seconds" in r and r["case"] not in met]
    log.info("target met: %s", ", ".join(met) or "none")
    log.info("target missed: %s", ", ".join(missed) or "none")
    log.info("wrote %s and %s", json_path, md_path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
