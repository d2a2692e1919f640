"""Side-by-side benchmark: planner.minkowski_sum vs manifold3d's Manifold.minkowski_sum.

Opt-in (pytest never collects tests/benchmarks).  Run from the repository root::

    python tests/benchmarks/bench_minkowski.py [--quick] [--json out.json] [--samples N]

Both run in this one process on the same meshes.  For every case it reports:

* seconds: ours cold (decomposition computed: a fresh temporary cache directory), ours
  cached (second call, decomposition from that cache), manifold3d, and the ratio
  ours-cached / manifold3d;
* accuracy of both against the independent FCL membership oracle (tests/oracle.py):
  the two one-sided Hausdorff estimates (true→result, result→true), and membership
  disagreements on random points farther than the result's error bound (manifold3d: 1e-6
  of the diagonal) from its surface; manifold3d's answer is marked untrusted ("!") when
  it fails these checks (it is exact only when the second operand contains the origin,
  and can miss interior volume when both operands are non-convex);
* our error_bound, eps, and the triangle counts.

The scaling series fits the log-log slope of our (cached) time against 1/eps (DESIGN.md
aims for ~2: the work follows the boundary band, a surface) and against the triangle
count of the first operand.

Machine note: timings are wall-clock on whatever cores are free; RAYON_NUM_THREADS is
recorded in the JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))                 # tests/: shapes, oracle
sys.path.insert(0, str(HERE.parent.parent))          # repository root: planner

import oracle  # noqa: E402
import shapes  # noqa: E402
from benchlib import jsonable  # noqa: E402


def log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


# --------------------------------------------------------------------------------------
# cases
# --------------------------------------------------------------------------------------

def main_cases():
    return [
        ("torus ⊕ icosphere",
         lambda: shapes.torus(10.0, 3.0, 32, 16), lambda: shapes.icosphere(2, 0.9)),
        ("cross ⊕ torus",
         lambda: shapes.cross_of_bars(30.0, 6.0), lambda: shapes.torus(3.0, 1.0, 16, 8)),
        ("part2k ⊕ icosphere",
         shapes.nonconvex_part_2k, lambda: shapes.icosphere(2, 0.5)),
        # the manifold3d quirk on display: B does not contain the origin, so its answer
        # is wrong (cube ⊕ cube at (10, 0, 0) has volume 9, not 8) and flagged "!"
        ("box ⊕ far box (mf3d quirk)",
         lambda: shapes.box((1.0, 1.0, 1.0)),
         lambda: shapes.box((1.0, 1.0, 1.0), center=(10.0, 0.0, 0.0))),
    ]


EPS_SERIES = (0.02, 0.01, 0.005, 0.0025)
MAX_ORACLE_TRIANGLES = 6_000_000     # larger results are timed but not measured
TRIANGLE_SERIES = ((16, 8), (32, 16), (64, 32), (128, 64))   # torus sections


# --------------------------------------------------------------------------------------
# measurements
# --------------------------------------------------------------------------------------

def ours_available() -> bool:
    try:
        import planner
    except ImportError as exc:
        log(f"planner not importable ({exc}); measuring manifold3d only")
        return False
    if not hasattr(planner, "minkowski_sum"):
        log("planner.minkowski_sum not there yet; measuring manifold3d only")
        return False
    return True


_TEMP_DIRS: list[str] = []     # fresh decomposition caches, removed at exit


def run_ours(a, b, eps, cache_dir):
    import planner
    t0 = time.perf_counter()
    r = planner.minkowski_sum(a, b, eps=eps, cache_dir=cache_dir, progress=False)
    return r, time.perf_counter() - t0


def limit_memory(gigabytes: float) -> None:
    """Cap this process's address space so a runaway case fails here (MemoryError, or an
    abort in native code) instead of waking the OOM killer on a shared machine."""
    if gigabytes <= 0:
        return
    import resource
    limit = int(gigabytes * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def run_manifold(a, b):
    """manifold3d's sum, with B as given (the caller keeps B around the origin)."""
    ma, mb = shapes.to_manifold(a), shapes.to_manifold(b)
    t0 = time.perf_counter()
    m = ma.minkowski_sum(mb)
    mesh_gl = m.to_mesh64()              # force evaluation (manifold3d is lazy)
    seconds = time.perf_counter() - t0
    del mesh_gl
    return shapes.from_manifold(m, "manifold3d sum", allow_degenerate=True), seconds


def accuracy(mesh, a, b, band, n, seed):
    """Hausdorff estimates against the oracle and membership disagreements on points
    farther than ``band`` from ``mesh``'s surface."""
    t0 = time.perf_counter()
    d_true_to_mesh, d_mesh_to_true = oracle.hausdorff_estimate(mesh, a, b, n, seed)
    rng = np.random.default_rng(seed)
    lo = a.bounds[0] + b.bounds[0]
    hi = a.bounds[1] + b.bounds[1]
    pad = 0.1 * (hi - lo)
    pts = rng.uniform(lo - pad, hi + pad, size=(4 * n, 3))
    pts = pts[oracle.surface_distance(mesh, pts) > band]
    wrong = int(np.sum(oracle.points_in_mesh(mesh, pts) != oracle.in_minkowski_sum(pts, a, b)))
    return {
        "hausdorff_true_to_result": d_true_to_mesh,
        "hausdorff_result_to_true": d_mesh_to_true,
        "membership_points": int(len(pts)),
        "membership_wrong": wrong,
        "oracle_seconds": time.perf_counter() - t0,
    }


def measure_case(name, a, b, rel_eps, *, samples, seed, with_ours, cold=True,
                 manifold=None, cache_dir=None):
    """One row.  ``manifold``: a previous (mesh, seconds, accuracy) to reuse (the eps
    series shares one manifold3d run).  ``cache_dir``: a warm cache to reuse."""
    diag = float(np.linalg.norm((a.bounds[1] + b.bounds[1]) - (a.bounds[0] + b.bounds[0])))
    eps = rel_eps * diag
    row = {"case": name, "rel_eps": rel_eps, "eps": eps, "diagonal": diag,
           "triangles_a": len(a.faces), "triangles_b": len(b.faces)}
    log(f"[{name}] eps={eps:.4g} ({100 * rel_eps:g}% of the diagonal)")
    # manifold3d
    if manifold is None:
        origin_in_b = bool(oracle.points_in_mesh(b, np.zeros((1, 3)))[0])
        mesh_m, t_m = run_manifold(a, b)
        acc_m = accuracy(mesh_m, a, b, 1e-6 * diag, samples, seed)
        tol = 1e-4 * diag
        # manifold3d claims an exact answer: trust it only where the oracle agrees
        trusted = (acc_m["membership_wrong"] == 0
                   and acc_m["hausdorff_true_to_result"] <= tol
                   and acc_m["hausdorff_result_to_true"] <= tol)
        manifold = (mesh_m, t_m, acc_m, trusted, origin_in_b)
        log(f"  manifold3d {t_m:.2f}s, {len(mesh_m.faces)} triangles, trusted={trusted}")
    mesh_m, t_m, acc_m, trusted, origin_in_b = manifold
    row["manifold"] = {"seconds": t_m, "triangles": len(mesh_m.faces), "trusted": trusted,
                       "b_contains_origin": origin_in_b, **acc_m}
    if not with_ours:
        return row, manifold, cache_dir
    # ours: cold then cached, in one cache directory
    if cache_dir is None:
        cache_dir = tempfile.mkdtemp(prefix="minkplan-bench-")
        _TEMP_DIRS.append(cache_dir)
    try:
        if cold:
            _, t_cold = run_ours(a, b, eps, cache_dir)
            row["ours_cold_seconds"] = t_cold
            log(f"  ours cold {t_cold:.2f}s")
        r, t_cached = run_ours(a, b, eps, cache_dir)
    except Exception as exc:       # a failed case (MemoryError, ResourceLimitError) is data
        row["ours_error"] = f"{type(exc).__name__}: {exc}"
        log(f"  ours failed: {row['ours_error']}")
        return row, manifold, cache_dir
    log(f"  ours cached {t_cached:.2f}s, {len(r.mesh.faces)} triangles, "
        f"bound {r.error_bound:.4g}")
    if len(r.mesh.faces) <= MAX_ORACLE_TRIANGLES:
        acc = accuracy(r.mesh, a, b, r.error_bound, samples, seed)
    else:   # the oracle's BVH and column grid for it would not fit beside it
        acc = {"oracle_skipped": f"{len(r.mesh.faces)} triangles > {MAX_ORACLE_TRIANGLES}"}
        log(f"  accuracy not measured: {acc['oracle_skipped']}")
    row["ours"] = {"seconds_cached": t_cached, "triangles": len(r.mesh.faces),
                   "error_bound": r.error_bound, "eps_used": r.eps,
                   "stats": jsonable(r.stats), **acc}
    row["ratio_cached"] = t_cached / t_m if t_m > 0 else math.inf
    if "ours_cold_seconds" in row:
        row["ratio_cold"] = row["ours_cold_seconds"] / t_m if t_m > 0 else math.inf
    if trusted and "oracle_skipped" not in acc:
        d1, d2 = oracle.sampled_hausdorff(r.mesh, mesh_m, n=20 * samples, seed=seed)
        row["ours"]["hausdorff_to_manifold"] = max(d1, d2)
    return row, manifold, cache_dir


def loglog_slope(xs, ys):
    xs, ys = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    ok = (xs > 0) & (ys > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(xs[ok]), np.log(ys[ok]), 1)[0])


# --------------------------------------------------------------------------------------
# table
# --------------------------------------------------------------------------------------

COLUMNS = ("case", "eps%", "ours cold s", "ours cached s", "mf3d s", "ratio",
           "H ours t→r", "H ours r→t", "bound", "wrong", "tri ours",
           "H mf3d t→r", "H mf3d r→t", "mf3d wrong", "tri mf3d")


def _fmt(x, spec=".3g"):
    if x is None:
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return format(x, spec) if isinstance(x, (int, float)) else str(x)


def table(rows) -> str:
    lines, notes = [], []
    for row in rows:
        if "ours_error" in row:
            notes.append(f"{row['case']} eps {100 * row['rel_eps']:g}%: ours failed: "
                         f"{row['ours_error']}")
        o, m = row.get("ours", {}), row["manifold"]
        flag = "" if m["trusted"] else " !"
        if not m["b_contains_origin"]:
            notes.append(f"{row['case']}: B does not contain the origin (manifold3d "
                         f"{'still right here' if m['trusted'] else 'wrong, as expected'})")
        if "oracle_skipped" in o:
            notes.append(f"{row['case']} eps {100 * row['rel_eps']:g}%: accuracy not "
                         f"measured ({o['oracle_skipped']})")
        lines.append([
            row["case"], _fmt(100 * row["rel_eps"], "g"),
            _fmt(row.get("ours_cold_seconds")), _fmt(o.get("seconds_cached")),
            _fmt(m["seconds"]), _fmt(row.get("ratio_cached")),
            _fmt(o.get("hausdorff_true_to_result")), _fmt(o.get("hausdorff_result_to_true")),
            _fmt(o.get("error_bound")),
            _fmt(o.get("membership_wrong")) if o else "-",
            _fmt(o.get("triangles")) if o else "-",
            _fmt(m["hausdorff_true_to_result"]) + flag,
            _fmt(m["hausdorff_result_to_true"]) + flag,
            _fmt(m["membership_wrong"]), _fmt(m["triangles"]),
        ])
    widths = [max(len(str(c)), *(len(r[i]) for r in lines)) for i, c in enumerate(COLUMNS)]
    out = ["  ".join(str(c).ljust(w) for c, w in zip(COLUMNS, widths)),
           "  ".join("-" * w for w in widths)]
    out += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in lines]
    return "\n".join(out + list(dict.fromkeys(notes)))


LEGEND = """\
Columns: eps% of the sum's bbox diagonal; seconds ours cold (fresh decomposition cache),
cached (decomposition reused), manifold3d (mf3d); ratio = ours cached / mf3d;
H t→r / r→t = Hausdorff estimates true boundary→result and result→true boundary (FCL
oracle, bisection); bound = our error_bound; wrong = membership disagreements with the
oracle on random points farther than the bound (mf3d: 1e-6 of the diagonal) from the
result's surface; tri = triangles.  "!" = manifold3d's answer is not trustworthy here:
the oracle disagrees (Hausdorff > 1e-4 of the diagonal or a membership error).  Its
known failure modes: B not containing the origin, and two non-convex operands.
"""


# --------------------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------------------

def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="one case, two eps values, fewer samples")
    parser.add_argument("--json", type=Path, help="write the measurements here")
    parser.add_argument("--samples", type=int, default=None,
                        help="oracle samples per Hausdorff direction (default 400, quick 100)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-memory-gb", type=float, default=8.0,
                        help="address-space cap for this process (0: none)")
    parser.add_argument("--only", nargs="+", choices=("main", "eps", "triangles"),
                        default=("main", "eps", "triangles"),
                        help="parts to run (default: all)")
    args = parser.parse_args(argv)
    limit_memory(args.max_memory_gb)
    try:
        return _run(args)
    finally:
        for d in _TEMP_DIRS:
            shutil.rmtree(d, ignore_errors=True)


def _run(args) -> int:
    samples = args.samples or (100 if args.quick else 400)
    with_ours = ours_available()

    rows, series = [], {}

    def save():
        if args.json:
            payload = {
                "rows": jsonable(rows), "series": jsonable(series),
                "machine": {"python": platform.python_version(),
                            "platform": platform.platform(), "cpu_count": os.cpu_count(),
                            "rayon_num_threads": os.environ.get("RAYON_NUM_THREADS")},
                "samples": samples, "seed": args.seed, "quick": args.quick,
            }
            args.json.write_text(json.dumps(payload, indent=2, allow_nan=True))

    # the first main case's manifold3d run and warm cache serve the eps series too
    first_manifold, first_cache = None, None
    cases = main_cases()[:1] if args.quick else main_cases()
    for k, (name, make_a, make_b) in enumerate(cases if "main" in args.only else []):
        a, b = make_a(), make_b()
        row, manifold, cache_dir = measure_case(name, a, b, 0.005, samples=samples,
                                                seed=args.seed, with_ours=with_ours)
        if k == 0:
            first_manifold, first_cache = manifold, cache_dir
        rows.append(row)
        save()                  # after every row: a crash in native code keeps the rest
        oracle.clear_caches()   # the oracle's BVHs of big results add up otherwise

    # scaling in eps: one manifold3d run and one warm cache for the whole series
    eps_values = EPS_SERIES[:2] if args.quick else EPS_SERIES
    name, make_a, make_b = main_cases()[0]
    a, b = make_a(), make_b()
    manifold, cache_dir, eps_rows = first_manifold, first_cache, []
    for rel in eps_values if "eps" in args.only else []:
        row, manifold, cache_dir = measure_case(
            f"{name} [eps series]", a, b, rel, samples=samples, seed=args.seed,
            with_ours=with_ours, cold=cache_dir is None, manifold=manifold,
            cache_dir=cache_dir)
        eps_rows.append(row)
        rows.append(row)
        save()
        oracle.clear_caches()
    done = [r for r in eps_rows if "ours" in r]
    if done:
        series["eps"] = {
            "inverse_eps": [1 / r["eps"] for r in done],
            "seconds": [r["ours"]["seconds_cached"] for r in done],
            "triangles": [r["ours"]["triangles"] for r in done],
        }
        series["eps"]["slope_time_vs_inverse_eps"] = loglog_slope(
            series["eps"]["inverse_eps"], series["eps"]["seconds"])
        series["eps"]["slope_triangles_vs_inverse_eps"] = loglog_slope(
            series["eps"]["inverse_eps"], series["eps"]["triangles"])

    # scaling in triangle count (torus sections) at 1 % eps
    if not args.quick and "triangles" in args.only:
        tri_rows = []
        for major, minor in TRIANGLE_SERIES:
            a = shapes.torus(10.0, 3.0, major, minor)
            b = shapes.icosphere(2, 0.9)
            row, _, _ = measure_case(f"torus {major}x{minor} ⊕ icosphere [tri series]",
                                     a, b, 0.01, samples=samples, seed=args.seed,
                                     with_ours=with_ours)
            tri_rows.append(row)
            rows.append(row)
            save()
            oracle.clear_caches()
        done = [r for r in tri_rows if "ours" in r]
        if done:
            series["triangles"] = {
                "triangles_a": [r["triangles_a"] for r in done],
                "seconds_cold": [r["ours_cold_seconds"] for r in done],
                "seconds_cached": [r["ours"]["seconds_cached"] for r in done],
                "manifold_seconds": [r["manifold"]["seconds"] for r in done],
            }
            s = series["triangles"]
            s["slope_cached_vs_triangles"] = loglog_slope(s["triangles_a"], s["seconds_cached"])
            s["slope_cold_vs_triangles"] = loglog_slope(s["triangles_a"], s["seconds_cold"])
            s["slope_manifold_vs_triangles"] = loglog_slope(s["triangles_a"],
                                                            s["manifold_seconds"])

    sys.stdout.write(table(rows) + "\n\n" + LEGEND)
    if "eps" in series:
        sys.stdout.write(
            f"\nscaling in eps ({name}): time ~ (1/eps)^"
            f"{series['eps']['slope_time_vs_inverse_eps']:.2f}, triangles ~ (1/eps)^"
            f"{series['eps']['slope_triangles_vs_inverse_eps']:.2f} (target: ~2)\n")
    if "triangles" in series:
        s = series["triangles"]
        sys.stdout.write(
            f"scaling in triangles of A (torus ⊕ icosphere, eps 1%): ours cached ~ n^"
            f"{s['slope_cached_vs_triangles']:.2f}, ours cold ~ n^"
            f"{s['slope_cold_vs_triangles']:.2f}, manifold3d ~ n^"
            f"{s['slope_manifold_vs_triangles']:.2f}\n")
    if not with_ours:
        sys.stdout.write("\n(planner.minkowski_sum unavailable: manifold3d columns only)\n")

    save()
    if args.json:
        log(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
