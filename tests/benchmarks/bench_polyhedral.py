"""Side-by-side benchmark on polyhedral pairs: the exact source against manifold3d.

Opt-in (pytest never collects tests/benchmarks).  Run from the repository root::

    python tests/benchmarks/bench_polyhedral.py [--quick] [--pairs A,B] [--json F] [--timeout S]

The pairs of the geometry-adaptive issue: flat-faced parts whose exact sum has few faces
(an L-bracket, a jack of three bars, a comb, a tetrahedron, a cube), curved ones (a ball of
320 triangles, tori), a 2k-triangle part and two grates (512 and 1,292 triangles, both
non-convex).  Every run is its own child process, so each row's peak memory is its own;
the tools run one after the other in this one invocation, so their ratio holds on a
loaded machine.  Per pair and tool: wall seconds, CPU seconds, peak resident memory,
triangles; for ours the stated two-sided bound and the seconds by stage; the exact sum's
planar face count (trimesh's coplanar facets of manifold3d's exact answer, where B
contains the origin — B is translated so that it does, and the sum moved back); and the
sampled two-sided surface distance between the two answers (within our bound when both
are right).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))                 # tests/: shapes, oracle
sys.path.insert(0, str(HERE.parent.parent))          # repository root: planner

import shapes  # noqa: E402
from benchlib import jsonable, peak_mb  # noqa: E402

PAIRS = {
    "L-bracket ⊕ cube": (shapes.l_bracket, lambda: shapes.box((1.0, 1.0, 1.0))),
    "jack ⊕ tetrahedron": (shapes.jack, shapes.tetrahedron),
    "comb ⊕ ball (320)": (shapes.comb, lambda: shapes.icosphere(2, 0.3)),
    "L-bracket ⊕ jack": (shapes.l_bracket, shapes.jack),
    "jack ⊕ small torus": (shapes.jack, lambda: shapes.torus(1.0, 0.3, 24, 12)),
    "torus ⊕ ball": (lambda: shapes.torus(10.0, 3.0, 64, 32), lambda: shapes.icosphere(2, 0.9)),
    "part2k ⊕ icosphere": (shapes.nonconvex_part_2k, lambda: shapes.icosphere(2, 0.5)),
    "grate512 ⊕ grate1292": (lambda: shapes.grate(5, 4.0, 0.4, 0.15),
                             lambda: shapes.grate(8, 3.0, 0.3, 0.1)),
    "sphere5120 ⊕ sphere1280 (convex)": (lambda: shapes.icosphere(4, 1.0),
                                         lambda: shapes.icosphere(3, 0.5)),
}
"""name -> (make A, make B)."""

DEFAULT_SOURCE = {"sphere5120 ⊕ sphere1280 (convex)"}
"""Pairs ours runs with the default source (``exact="auto"``: convex bodies, one convex
sum, its hull); the others with the exact source."""

RUNS = [(name, 0.005) for name in PAIRS] + [("grate512 ⊕ grate1292", e) for e in (0.02, 0.01)] \
    + [("torus ⊕ ball", e) for e in (0.02, 0.01, 0.0025)]
"""(pair, eps as a fraction of the sum's diagonal) in the order they run: each pair at
0.5%, then the grates coarser and the curved torus ⊕ ball coarser and finer (its cost in
eps: :func:`scaling`)."""

QUICK = [("L-bracket ⊕ cube", 0.005), ("jack ⊕ tetrahedron", 0.005)]


def log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


# --------------------------------------------------------------------------------------
# one run, in a child process
# --------------------------------------------------------------------------------------

def _exact_faces(mesh) -> int:
    """Planar faces of a mesh: trimesh's coplanar facets, and every triangle in none."""
    in_facets = sum(len(f) for f in mesh.facets)
    return len(mesh.facets) + len(mesh.faces) - in_facets


def _origin_shift(b) -> np.ndarray:
    """A translation that puts a point inside ``b`` at the origin (zero when it is)."""
    import oracle
    if bool(oracle.points_in_mesh(b, np.zeros((1, 3)))[0]):
        return np.zeros(3)
    samples, _ = b.sample(2000, return_index=True), None
    # a point just inside the surface, along the inward normal of a sampled face
    pts, idx = samples
    inner = pts - 1e-3 * b.scale * b.face_normals[idx]
    inside = oracle.points_in_mesh(b, inner)
    return -inner[int(np.argmax(inside))]


def child(tool: str, pair: str, rel_eps: float, out_mesh: str) -> dict:
    """Run ``tool`` on ``pair`` and measure it (this process's own peak memory)."""
    make_a, make_b = PAIRS[pair]
    a, b = make_a(), make_b()
    diag = float(np.linalg.norm((a.bounds[1] + b.bounds[1]) - (a.bounds[0] + b.bounds[0])))
    row: dict = {"tool": tool, "pair": pair, "rel_eps": rel_eps, "diagonal": diag,
                 "triangles_a": len(a.faces), "triangles_b": len(b.faces)}
    if tool == "minkplan":
        # before the clock, as manifold3d's import is: the package and the modules the sum
        # loads on first use (lazily, for the CLI's start-up), not the sum's work
        import planner  # noqa: PLC0415
        import planner.minkowski  # noqa: F401, PLC0415
        import planner.sources  # noqa: F401, PLC0415
    base_rss = peak_mb()
    t0, c0 = time.perf_counter(), time.process_time()
    if tool == "minkplan":
        exact = "auto" if pair in DEFAULT_SOURCE else True
        r = planner.minkowski_sum(a, b, exact=exact, eps=rel_eps * diag, progress=False)
        mesh = r.mesh
        row.update(error_bound=r.error_bound, stages=r.stats.get("seconds"),
                   facets=r.stats.get("facets"), band_cells=r.stats.get("band_cells"))
    else:
        shift = _origin_shift(b)
        ma, mb = shapes.to_manifold(a), shapes.to_manifold(b.copy().apply_translation(shift))
        m = ma.minkowski_sum(mb).translate([float(-s) for s in shift])
        m.to_mesh64()                                  # manifold3d is lazy
        mesh = shapes.from_manifold(m, "manifold3d sum", allow_degenerate=True)
        row["b_shift"] = shift.tolist()
    row["seconds"] = time.perf_counter() - t0
    row["cpu_seconds"] = time.process_time() - c0
    row["peak_mb"] = peak_mb()
    row["peak_mb_before"] = base_rss
    row["triangles"] = len(mesh.faces)
    row["volume"] = float(mesh.volume)
    if tool == "manifold3d":
        row["exact_faces"] = _exact_faces(mesh)
    mesh.export(out_mesh)
    return row


def run_child(tool: str, pair: str, rel_eps: float, timeout: float, workdir: str) -> dict:
    out_mesh = os.path.join(workdir, f"{tool}-{len(os.listdir(workdir))}.ply")
    cmd = [sys.executable, __file__, "--child", tool, pair, repr(rel_eps), out_mesh]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"tool": tool, "pair": pair, "rel_eps": rel_eps, "error": f"over {timeout:g} s"}
    if p.returncode != 0:
        last = (p.stderr.strip().splitlines() or ["?"])[-1]
        return {"tool": tool, "pair": pair, "rel_eps": rel_eps, "error": last[:200]}
    row = json.loads(p.stdout.strip().splitlines()[-1])
    row["mesh"] = out_mesh
    return row


# --------------------------------------------------------------------------------------
# the table
# --------------------------------------------------------------------------------------

def compare(ours: dict, theirs: dict, samples: int) -> dict:
    """Sampled two-sided surface distance between the two answers."""
    import oracle
    import trimesh
    if "error" in ours or "error" in theirs:
        return {}
    x, y = trimesh.load(ours["mesh"]), trimesh.load(theirs["mesh"])
    d1, d2 = oracle.sampled_hausdorff(x, y, n=samples, seed=0)
    return {"distance_to_manifold": max(d1, d2),
            "volume_ratio": ours["volume"] / theirs["volume"] if theirs["volume"] else None}


def _f(x, spec=".3g") -> str:
    if x is None:
        return "-"
    return format(x, spec) if isinstance(x, (int, float)) else str(x)


COLUMNS = ["pair", "eps%", "ours s", "ours cpu", "ours MB", "mf3d s", "mf3d MB",
           "mf3d/ours", "ours tri", "exact faces", "tri/faces", "bound", "dist", "vol ratio"]


def table(rows: list[dict]) -> str:
    lines = []
    for r in rows:
        o, m, c = r["ours"], r["manifold3d"], r.get("compare", {})
        ok_o, ok_m = "error" not in o, "error" not in m
        faces = m.get("exact_faces") if ok_m else None
        lines.append([
            r["pair"], _f(100 * r["rel_eps"], "g"),
            _f(o.get("seconds")) if ok_o else o["error"], _f(o.get("cpu_seconds")),
            _f(o.get("peak_mb"), ".0f"),
            _f(m.get("seconds")) if ok_m else m["error"], _f(m.get("peak_mb"), ".0f"),
            _f(m["seconds"] / o["seconds"]) if ok_o and ok_m else "-",
            _f(o.get("triangles")), _f(faces),
            _f(o["triangles"] / faces) if ok_o and faces else "-",
            _f(o.get("error_bound")), _f(c.get("distance_to_manifold")),
            _f(c.get("volume_ratio"), ".5f"),
        ])
    widths = [max(len(h), *(len(x[i]) for x in lines)) for i, h in enumerate(COLUMNS)]
    out = ["| " + " | ".join(h.ljust(w) for h, w in zip(COLUMNS, widths)) + " |",
           "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
    out += ["| " + " | ".join(x.ljust(w) for x, w in zip(line, widths)) + " |" for line in lines]
    return "\n".join(out)


def scaling(rows: list[dict]) -> str:
    """Per pair run at three or more eps, the least-squares log-log slope of our wall
    seconds and triangles against 1/eps (2: the work follows a curved boundary's band;
    0: a flat answer resolved by planes, whatever eps)."""
    lines = []
    for pair in dict.fromkeys(r["pair"] for r in rows):
        ok = sorted((r for r in rows if r["pair"] == pair and "error" not in r["ours"]),
                    key=lambda r: -r["rel_eps"])
        if len(ok) < 3:
            continue
        x = np.log([1.0 / r["rel_eps"] for r in ok])
        time_slope = np.polyfit(x, np.log([r["ours"]["seconds"] for r in ok]), 1)[0]
        tri_slope = np.polyfit(x, np.log([r["ours"]["triangles"] for r in ok]), 1)[0]
        series = ", ".join(_f(100 * r["rel_eps"], "g") for r in ok)
        lines.append(f"{pair}: time ~ (1/eps)^{time_slope:.2f}, triangles ~ "
                     f"(1/eps)^{tri_slope:.2f} over eps {series}%")
    return "\n".join(lines)


LEGEND = """\
eps% of the sum's bounding-box diagonal; s = wall seconds, cpu = CPU seconds of the
process, MB = its peak resident memory (a child process per run; about 150 MB of it is
Python, numpy and trimesh); mf3d/ours = manifold3d's seconds over ours (> 1: ours is
faster); ours tri = our triangles; exact faces = planar faces of manifold3d's exact sum
(coplanar facets by trimesh); bound = our stated two-sided bound; dist = sampled
two-sided surface distance between the two answers (should be within the bound); vol
ratio = our volume / manifold3d's.
"""


def main(argv=None) -> int:
    if argv is None and len(sys.argv) > 1 and sys.argv[1] == "--child":
        tool, pair, rel, out_mesh = sys.argv[2:6]
        sys.stdout.write(json.dumps(jsonable(child(tool, pair, float(rel), out_mesh))) + "\n")
        return 0
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="two small pairs only")
    parser.add_argument("--json", type=Path, help="write the measurements here")
    parser.add_argument("--markdown", type=Path, help="write the table here")
    parser.add_argument("--timeout", type=float, default=600.0, help="per run, seconds")
    parser.add_argument("--samples", type=int, default=20000,
                        help="surface samples per side for the distance between answers")
    parser.add_argument("--pairs", help="comma-separated subset of the pairs (default: all)")
    args = parser.parse_args(argv)
    runs = QUICK if args.quick else RUNS
    if args.pairs:
        wanted = [p.strip() for p in args.pairs.split(",")]
        unknown = sorted(set(wanted) - set(PAIRS))
        if unknown:
            parser.error(f"unknown pair {unknown[0]!r}; the pairs: {', '.join(PAIRS)}")
        runs = [(pair, rel) for pair, rel in runs if pair in wanted]
    rows = []
    theirs: dict[str, dict] = {}     # manifold3d's answer does not depend on eps: once a pair
    with tempfile.TemporaryDirectory(prefix="minkplan-poly-") as work:
        for pair, rel in runs:
            log(f"[{pair}] eps {100 * rel:g}%")
            row = {"pair": pair, "rel_eps": rel}
            row["ours"] = run_child("minkplan", pair, rel, args.timeout, work)
            if pair not in theirs:
                theirs[pair] = run_child("manifold3d", pair, rel, args.timeout, work)
            row["manifold3d"] = theirs[pair]
            for tool, r in (("minkplan", row["ours"]), ("manifold3d", row["manifold3d"])):
                log(f"  {tool}: " + (r["error"] if "error" in r else
                                      f"{r['seconds']:.2f} s, {r['triangles']} triangles"))
            row["compare"] = compare(row["ours"], row["manifold3d"], args.samples)
            rows.append(row)
    slopes = scaling(rows)
    text = table(rows) + "\n\n" + (f"Scaling in eps (ours):\n\n{slopes}\n\n" if slopes else "") \
        + LEGEND
    sys.stdout.write(text)
    if args.markdown:
        args.markdown.write_text(
            f"# Polyhedral pairs: exact source vs manifold3d\n\n`python "
            f"tests/benchmarks/bench_polyhedral.py`, {time.strftime('%Y-%m-%d')}, "
            f"{platform.platform()}, {os.cpu_count()} cores (shared).\n\n{text}")
    if args.json:
        args.json.write_text(json.dumps(jsonable({"rows": rows}), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
