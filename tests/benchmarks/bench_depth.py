"""Side-by-side benchmark: planner.penetration_depth vs FCL's EPA and a sampled search.

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_depth.py [--directions N] [--json out.json]

* Convex pairs (random hulls, spheres): our proved interval against FCL's GJK/EPA
  penetration depth (libccd and FCL's own solver, on ``fcl.Convex`` objects); whether
  they agree (EPA inside ``[lower - 1e-6, upper + 1e-6]``), and the time ratio
  ours / EPA (ours: from the meshes, the exact source built; EPA: one query on objects
  built beforehand, so the ratio flatters EPA).
* Non-convex pairs: our interval against a sampled directional search: for ``N`` unit
  directions ``u`` (the six axes and random ones), the first free ``s·u`` (FCL,
  containment included) bisected to 1e-6; its minimum is a free translation, so the true
  depth is at most it: ``lower`` must lie below it ("ok") and ``upper`` within the
  tolerance of it or below it ("tight") — below it means the sampling missed the best
  direction. Steps 0.05 and bisection to 1e-6 (on a pair under 1 across, parts in
  metres, scaled by a fifth of its size); real CAD parts from ../shared/assets join the
  shapes when present.

Prints a markdown table (and writes JSON with ``--json``). Timings are wall-clock on
whatever cores are free.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))                 # tests/: shapes, test_depth helpers
sys.path.insert(0, str(HERE.parent.parent))          # repository root: planner

import fcl  # noqa: E402
import manifold3d  # noqa: E402
import shapes  # noqa: E402
from benchlib import jsonable  # noqa: E402
from test_depth import _convex, _unit, directional_min  # noqa: E402

import planner  # noqa: E402
from planner.validation import FclChecker  # noqa: E402


def log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


def convex_cases():
    rng = np.random.default_rng(0)
    for n in (20, 100, 400):
        for k in range(2):
            seed = 10 * n + k
            a = shapes.random_convex(n, scale=(1.0, 0.7, 0.5), seed=seed)
            b = shapes.random_convex(n, scale=(0.6, 0.9, 0.8), seed=seed + 1,
                                     center=rng.uniform(-0.6, 0.6, size=3))
            yield f"hulls {n} pts #{k}", a, b
    yield "spheres (sub 3)", shapes.icosphere(3), shapes.icosphere(3, r=0.7,
                                                                   center=(1.2, 0.3, 0.1))


def nonconvex_cases():
    block = manifold3d.Manifold.cube([4.0, 4.0, 2.0], center=True)
    hole = manifold3d.Manifold.cube([1.2, 1.2, 2.0], center=True).translate([0.0, 0.0, 0.5])
    holed = shapes.from_manifold(block - hole, "block")
    for shift in (0.05, 0.2):
        yield f"peg in hole, {shift} into wall", shapes.box(
            size=(1.0, 1.0, 2.0), center=(0.1 + shift, 0.0, 1.0)), holed
    bracket = shapes.l_bracket(length=2.0, height=1.5, thickness=0.5, depth=1.0)
    rng = np.random.default_rng(1)
    for k in range(2):
        yield f"L bracket vs hull #{k}", bracket, shapes.random_convex(
            30, scale=(0.5, 0.5, 0.5), seed=k, center=rng.uniform(-0.5, 0.5, size=3))
    yield "torus vs box", shapes.torus(R=2.0, r=0.6, major_sections=24, minor_sections=12), \
        shapes.box(size=(1.0, 1.0, 1.0), center=(2.0, 0.0, 0.3))
    yield "slotted bar vs peg", shapes.slotted_bar(), shapes.box(
        size=(0.3, 0.3, 1.0), center=(-0.5, 0.05, 0.2))
    for shift in ((0.3, 0.2, 0.1), (0.05, 0.03, 0.02)):
        yield f"L bracket vs itself + {shift}", bracket, bracket.copy().apply_translation(shift)
    part = shapes.nonconvex_part_2k()
    yield "2k-triangle part vs itself + (0.5, 0.3, 0.2)", part, \
        part.copy().apply_translation((0.5, 0.3, 0.2))
    yield from real_cases()


ASSETS = HERE.parents[2] / "shared" / "assets" / "assemblies"


def real_cases():
    """Real CAD parts pushed into their mates (when ../shared/assets is there): Factory's
    round peg aslant into its bore, IndustReal's medium gear into the large one (whose
    whole convolution, over 4 million facets, does not fit the default memory limit)."""
    if not ASSETS.is_dir():
        log(f"skipping the real parts: {ASSETS} is absent")
        return
    from planner.meshes.kinds import classify

    def load(path: Path, shift=(0.0, 0.0, 0.0)):
        mesh = classify(planner.load_mesh(path), name=path.name, kind="solid").mesh
        return mesh.apply_translation(shift)

    pegs = ASSETS / "factory_round_peg_8mm" / "meshes"
    yield "Factory round peg + (0.3, 0.2, 0) mm into its hole", \
        load(pegs / "factory_round_peg_8mm_loose.obj", (0.0003, 0.0002, 0.0)), \
        load(pegs / "factory_round_hole_8mm_subdiv_3x.obj")
    gears = ASSETS / "industreal_gears" / "meshes"
    yield "IndustReal medium gear - 1 mm x into the large one", \
        load(gears / "industreal_gear_medium.obj", (-0.001, 0.0, 0.0)), \
        load(gears / "industreal_gear_large.obj")


def _epa(a, b, solver) -> tuple[float, float]:
    oa, ob = fcl.CollisionObject(_convex(a)), fcl.CollisionObject(_convex(b))
    request = fcl.CollisionRequest(enable_contact=True, num_max_contacts=1)
    request.gjk_solver_type = solver
    best = np.inf
    value = np.nan
    for _ in range(5):
        result = fcl.CollisionResult()
        t0 = time.perf_counter()
        fcl.collide(oa, ob, request, result)
        best = min(best, time.perf_counter() - t0)
        value = abs(result.contacts[0].penetration_depth) if result.contacts else 0.0
    return value, best


def _ours(a, b):
    """The result (timed without the FCL check) and whether FCL finds its translation
    free (strictly: no contact at all)."""
    t0 = time.perf_counter()
    r = planner.penetration_depth(a, b, validate=False)
    secs = time.perf_counter() - t0
    return r, secs, not FclChecker(a, [b]).collides(r.translation)


def run_convex() -> list[dict]:
    rows = []
    for name, a, b in convex_cases():
        r, secs, free = _ours(a, b)
        ccd, t_ccd = _epa(a, b, fcl.GJKSolverType.GST_LIBCCD)
        indep, t_indep = _epa(a, b, fcl.GJKSolverType.GST_INDEP)
        agree = [bool(r.lower - 1e-6 <= e <= r.upper + 1e-6) for e in (ccd, indep)]
        rows.append({"case": name, "lower": r.lower, "upper": r.upper, "tol": r.tolerance,
                     "epa_libccd": ccd, "epa_indep": indep, "agree": agree,
                     "free": free, "cells": r.stats["cells"], "seconds": secs,
                     "search_seconds": r.stats["seconds"]["search"], "epa_seconds": t_ccd,
                     "ratio": secs / t_ccd})
        log(f"{name}: [{r.lower:.6f}, {r.upper:.6f}] libccd {ccd:.6f} indep {indep:.6f}")
    return rows


def run_nonconvex(n_directions: int) -> list[dict]:
    rows = []
    for k, (name, a, b) in enumerate(nonconvex_cases()):
        r, secs, free = _ours(a, b)
        t0 = time.perf_counter()
        size = float(np.linalg.norm(np.ptp(np.vstack([a.bounds, b.bounds]), axis=0)))
        scale = 1.0 if size > 1.0 else size / 5.0    # parts in metres: steps to their size
        brute = directional_min(a, b, _unit(n_directions, k), step=0.05 * scale,
                                tol=1e-6 * scale)
        t_brute = time.perf_counter() - t0
        rows.append({"case": name, "lower": r.lower, "upper": r.upper, "tol": r.tolerance,
                     "sampled_min": brute, "ok": bool(r.lower <= brute + 1e-9),
                     "tight": bool(r.upper <= brute + r.tolerance + 1e-9), "free": free,
                     "cells": r.stats["cells"], "facets": r.stats["facets"],
                     "seconds": secs, "sampled_seconds": t_brute})
        log(f"{name}: [{r.lower:.6f}, {r.upper:.6f}] sampled {brute:.6f}")
    return rows


def table(convex: list[dict], nonconvex: list[dict]) -> str:
    out = ["| convex pair | ours [lower, upper] | EPA libccd | EPA indep | EPA in ours "
           "| ours free (FCL) | cells | ours s (search s) | EPA s | ratio |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in convex:
        agree = "/".join("yes" if x else "NO" for x in r["agree"])
        out.append(f"| {r['case']} | [{r['lower']:.6f}, {r['upper']:.6f}] | "
                   f"{r['epa_libccd']:.6f} | {r['epa_indep']:.6f} | {agree} | "
                   f"{'yes' if r['free'] else 'NO'} | {r['cells']} | "
                   f"{r['seconds']:.4f} ({r['search_seconds']:.1e}) | {r['epa_seconds']:.1e} | "
                   f"{r['ratio']:.0f} |")
    out += ["", "| non-convex pair | ours [lower, upper] | sampled min | lower ≤ sampled "
                "| upper ≤ sampled + tol | ours free (FCL) | facets | cells | ours s | sampled s |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for r in nonconvex:
        out.append(f"| {r['case']} | [{r['lower']:.6f}, {r['upper']:.6f}] | "
                   f"{r['sampled_min']:.6f} | {'yes' if r['ok'] else 'NO'} | "
                   f"{'yes' if r['tight'] else 'NO'} | {'yes' if r['free'] else 'NO'} | "
                   f"{r['facets']} | {r['cells']} | "
                   f"{r['seconds']:.4f} | {r['sampled_seconds']:.2f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--directions", type=int, default=200,
                   help="random directions of the sampled search (plus the six axes)")
    p.add_argument("--json", default=None, help="also write the rows as JSON here")
    args = p.parse_args(argv)
    convex = run_convex()
    nonconvex = run_nonconvex(args.directions)
    sys.stdout.write(table(convex, nonconvex) + "\n")
    if args.json:
        Path(args.json).write_text(json.dumps(jsonable({"convex": convex,
                                                        "nonconvex": nonconvex}), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
