"""Side-by-side benchmark: planner.offset vs libigl's offset_surface and manifold3d's
Minkowski sum with an icosphere (issue 17).

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_offsets.py [--quick] [--out PREFIX] [--samples N]

Inputs (every tool gets the same closed solid, as planner reads it):

* a box 1 x 0.6 x 0.4, offset by 0.1;
* a bunny-like solid of 2,040 triangles: no bunny file ships with the repository or an
  installed package, so it is a deterministic union of nine ellipsoids (body, head, ears,
  tail, feet, haunches) through manifold3d, with concave creases where they meet; offset
  by 0.03 (its ears are about 0.07 thick);
* a CAD part with sharp features: the Factory round hole (a 25 x 25 x 9 mm plate with an
  8 mm bore; ../shared/assets, skipped saying so when absent), offset by 1 mm;
* the Factory round peg (8 mm, 1,152 triangles, convex up to its OBJ's rounding: ours takes
  the hull path), offset by 1 mm;
* the IndustReal small gear (22 mm, 20,524 triangles after its repair, teeth finely
  tessellated: many small facets in every cell, ours' hard case), offset by 1 mm.

Tools, each at a few resolutions: ours (``planner.offset`` at ``eps``: the box and the peg,
convex bodies, take the hull path of :mod:`planner.offsets_convex`, the others the sum with
an inscribed ball of :mod:`planner.offsets_ball`), ours-cells (``method="cells"``: the
native cell source, exact distances cell by cell, on the non-convex inputs), libigl
(``igl.offset_surface``: signed distance on a grid of ``s`` cells along the longest side,
pseudonormal sign, marching cubes), manifold3d (``Manifold.minkowski_sum`` with an
icosphere of radius ``r`` and ``k`` subdivisions, vertices on the sphere; its two
Manifolds are made from the arrays on the clock, as ours validates its input on it: until
2026-12-07 they were made before it). Every run is a child process, so its wall and CPU
seconds and its peak resident memory are its own: ``wall`` is the first call's, one-time
costs (libraries' first use) in; ``warm`` the least of a few more calls in that process
(runs under a second).

Error, measured, both ways: on ``--samples`` points sampled on the output,
``|dist(x, P) - r|`` with an exact point-to-triangle distance (numpy, brute force; 0
inside ``P``, by trimesh's containment): the
distance to the exact offset's boundary for points outside it, a lower bound of it inside;
and on points of the exact offset's boundary (``p + r u`` for points ``p`` of ``P``'s faces,
edges and vertices and unit ``u`` in their normal cones, kept where ``p`` is the nearest
point), the distance to the output (FCL). The max of both is a lower estimate of the
Hausdorff distance; ours is compared with its stated bound.

The "equal error" table takes, for each of our runs, each other tool's cheapest run whose
measured error is at most ours, and gives its seconds and triangles as ratios to ours; and
the same ratios interpolated (log-log, between the tool's two runs whose errors bracket
ours) at exactly our error; then the same for the warm seconds (the cheapest run by them).
Rerun the tables from a results JSON with ``--tables PREFIX.json``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))                 # tests/: shapes
sys.path.insert(0, str(HERE.parent.parent))          # repository root: planner

from benchlib import jsonable, peak_mb  # noqa: E402

ASSETS = HERE.parent.parent.parent / "shared" / "assets" / "assemblies"
HOLE = ASSETS / "factory_round_peg_8mm" / "meshes" / "factory_round_hole_8mm_subdiv_3x.obj"
PEG = ASSETS / "factory_round_peg_8mm" / "meshes" / "factory_round_peg_8mm_loose.obj"
GEAR = ASSETS / "industreal_gears" / "meshes" / "industreal_gear_small.obj"
RESULTS = HERE / "results" / f"{datetime.date.today().isoformat()}-offsets"
TIMEOUT = 600.0


def log(msg: str) -> None:
    sys.stderr.write(msg + "\n")
    sys.stderr.flush()


# --------------------------------------------------------------------------------------
# inputs
# --------------------------------------------------------------------------------------

def bunny_like():
    """Nine ellipsoids (20 circular segments each) unioned by manifold3d: 2,040
    triangles, genus 0, about 1.1 x 0.6 x 1.1."""
    import manifold3d
    import shapes

    def ellipsoid(centre, radii, rotation=(0.0, 0.0, 0.0)):
        return manifold3d.Manifold.sphere(1.0, 20).scale(list(radii)).rotate(
            list(rotation)).translate(list(centre))

    parts = [ellipsoid((0.0, 0.0, 0.35), (0.45, 0.3, 0.32)),
             ellipsoid((0.38, 0.0, 0.68), (0.2, 0.18, 0.19)),
             ellipsoid((0.30, 0.08, 0.95), (0.05, 0.035, 0.2), (15.0, 0.0, -10.0)),
             ellipsoid((0.30, -0.08, 0.95), (0.05, 0.035, 0.2), (-15.0, 0.0, 10.0)),
             ellipsoid((-0.46, 0.0, 0.42), (0.08, 0.08, 0.08)),
             ellipsoid((0.22, 0.17, 0.06), (0.17, 0.07, 0.06)),
             ellipsoid((0.22, -0.17, 0.06), (0.17, 0.07, 0.06)),
             ellipsoid((-0.2, 0.2, 0.15), (0.2, 0.1, 0.15)),
             ellipsoid((-0.2, -0.2, 0.15), (0.2, 0.1, 0.15))]
    union = manifold3d.Manifold.batch_boolean(parts, manifold3d.OpType.Add)
    return shapes.from_manifold(union, "bunny-like")


def inputs(quick: bool, only: set[str] | None = None) -> list[dict]:
    """(name, solid, radius, each tool's resolutions) per input (``only``: those whose
    name starts with one of these words); the CAD part only when ../shared/assets is
    there."""
    import trimesh

    from planner.meshes.kinds import classify
    cases = [{"name": "box 1x0.6x0.4", "mesh": trimesh.creation.box((1.0, 0.6, 0.4)),
              "r": 0.1, "ours": [0.02, 0.005, 0.001, 0.0002],
              "libigl": [20, 30, 50, 100, 200, 300],
              "manifold": [1, 2, 3, 4, 5]},
             {"name": "bunny-like 2k", "mesh": bunny_like(), "r": 0.03,
              "ours": [0.004, 0.0011, 0.00028], "ours-cells": [0.024, 0.012],
              "libigl": [50, 100, 200, 300], "manifold": [1, 2, 3]}]
    if HOLE.exists():
        import planner
        hole = classify(planner.load_mesh(HOLE), name="hole", kind="solid").mesh
        cases.append({"name": "Factory round hole (CAD)", "mesh": hole, "r": 0.001,
                      "ours": [0.0004, 0.0001, 0.00002, 0.000005], "ours-cells": [0.0004],
                      "libigl": [50, 100, 200, 300], "manifold": [1, 2, 3]})
        peg = classify(planner.load_mesh(PEG), name="peg", kind="solid").mesh
        cases.append({"name": "peg: Factory round peg (CAD, convex up to rounding)",
                      "mesh": peg, "r": 0.001, "ours": [0.0004, 0.0001, 0.00005, 0.00002],
                      "libigl": [50, 100, 200, 300], "manifold": [1, 2, 3, 4]})
        gear = classify(planner.load_mesh(GEAR), name="gear", kind="solid").mesh
        cases.append({"name": "gear: IndustReal small gear (CAD, 20k triangles)",
                      "mesh": gear, "r": 0.001, "ours": [0.002, 0.001, 0.0005, 0.00025],
                      "libigl": [20, 30, 40, 50, 75, 100, 150, 200], "manifold": [1]})
    else:
        log(f"skipping the CAD part: {HOLE} is absent (../shared/assets not laid out)")
    if only:
        cases = [c for c in cases if c["name"].split()[0].lower().rstrip(":") in only]
    if quick:
        for c in cases:
            c["ours"], c["libigl"], c["manifold"] = c["ours"][:1], c["libigl"][:2], \
                c["manifold"][:2]
            c["ours-cells"] = c.get("ours-cells", [])[:1]
    return cases


# --------------------------------------------------------------------------------------
# one run, in a child process
# --------------------------------------------------------------------------------------

def _ours(V, F, r, eps, method="auto"):
    import scipy.optimize  # noqa: F401  (the hull path's lazy imports, not on the clock)
    import scipy.spatial  # noqa: F401

    import planner
    offset = planner.offset  # planner.offsets imported here, not on the clock

    def run():
        res = offset((V, F), r, eps=eps, method=method)
        return res.mesh.vertices, res.mesh.faces, {"bound": res.error_bound,
                                                   "stats": res.stats}
    return run


def _ours_cells(V, F, r, eps):
    return _ours(V, F, r, eps, method="cells")


def _libigl(V, F, r, s):
    import igl

    def run():
        SV, SF, _, _, _ = igl.offset_surface(V, F, r, int(s),
                                             igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)
        return SV, SF, {}
    return run


def _manifold(V, F, r, k):
    import manifold3d
    import trimesh

    def to_m(v, f):
        return manifold3d.Manifold(manifold3d.Mesh64(
            vert_properties=np.array(v, dtype=np.float64, order="C"),
            tri_verts=np.array(f, dtype=np.uint64, order="C")))
    ball = trimesh.creation.icosphere(subdivisions=int(k), radius=r)

    def run():
        # its Manifolds made on the clock, from the same arrays ours takes: making one
        # checks the mesh, as ours validates its input on the clock
        out = to_m(V, F).minkowski_sum(to_m(ball.vertices, ball.faces)).to_mesh64()
        return (np.asarray(out.vert_properties)[:, :3],
                np.asarray(out.tri_verts, dtype=np.int64), {"ball_triangles": len(ball.faces)})
    return run


TOOLS = {"ours": _ours, "ours-cells": _ours_cells, "libigl": _libigl, "manifold": _manifold}


def worker(spec_path: str) -> int:
    """Run one tool on one input (a JSON spec), write the output mesh and the measurements.
    Imports and inputs are made before the clock starts."""
    spec = json.loads(Path(spec_path).read_text())
    data = np.load(spec["input"])
    V, F = np.ascontiguousarray(data["V"]), np.ascontiguousarray(data["F"])
    run = TOOLS[spec["tool"]](V, F, spec["r"], spec["param"])
    base = peak_mb()
    cpu0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    SV, SF, extra = run()
    wall, cpu1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_SELF)
    peak = peak_mb()
    warm = _warm_wall(run) if wall < WARM_UNDER else None
    np.savez(spec["output"], V=np.asarray(SV, dtype=np.float64), F=np.asarray(SF, dtype=np.int64))
    cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    Path(spec["result"]).write_text(json.dumps(jsonable(
        {"wall": wall, "warm": warm, "cpu": cpu, "peak_mb": peak, "base_mb": base,
         **extra})))
    return 0


WARM_CALLS = 5
"""Calls after the first whose least wall time is a run's ``warm`` seconds: what a
process that offsets many parts pays per part, each tool's one-time costs (its first
call's libraries, pages and pools) left out."""

WARM_UNDER = 1.0
"""Runs whose first call took longer are not repeated (their one-time costs are noise)."""


def _warm_wall(run) -> float:
    """The least wall seconds of :data:`WARM_CALLS` more calls of ``run``."""
    best = float("inf")
    for _ in range(WARM_CALLS):
        t0 = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - t0)
    return best


def run_child(tool: str, param, case: dict, tmp: Path) -> dict:
    tag = f"{tool}-{param}"
    spec = {"tool": tool, "param": param, "r": case["r"], "input": str(tmp / "input.npz"),
            "output": str(tmp / f"{tag}.npz"), "result": str(tmp / f"{tag}.json")}
    spec_path = tmp / f"{tag}.spec.json"
    spec_path.write_text(json.dumps(spec))
    try:
        done = subprocess.run([sys.executable, __file__, "--worker", str(spec_path)],
                              capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"failed": f"timed out after {TIMEOUT:.0f} s"}
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["?"])[-1]
        return {"failed": f"exit {done.returncode}: {last[:160]}"}
    out = json.loads(Path(spec["result"]).read_text())
    mesh = np.load(spec["output"])
    out["V"], out["F"] = mesh["V"], mesh["F"]
    return out


# --------------------------------------------------------------------------------------
# the error to the exact offset
# --------------------------------------------------------------------------------------

def _faces(solid) -> dict:
    """Per triangle: corners, edges, unit normal and inward edge normals (zero for a
    sliver: twice its area below 1e-9 of its longest edge squared, taken for its edges)."""
    p = np.asarray(solid.vertices)[np.asarray(solid.faces)]
    e = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]], axis=1)
    cross = np.cross(e[:, 0], e[:, 1])
    size = np.linalg.norm(cross, axis=1)
    flat = size > 1e-9 * np.max(np.sum(e * e, axis=2), axis=1)
    n = np.where(flat[:, None], cross / np.where(size > 0, size, 1.0)[:, None], 0.0)
    return {"p": p, "e": e, "n": n, "m": np.cross(n[:, None, :], e), "flat": flat}


def distance_to_triangles(faces: dict, points, chunk: int = 256) -> np.ndarray:
    """Exact distance from each point to the nearest triangle, brute force in numpy: to
    the plane where the point lies over a face, else to the nearest edge. (trimesh's
    closest_point was up to 4e-6 off near the CAD part's thin triangles: more than the
    errors measured there.)"""
    p, e, n, m, flat = faces["p"], faces["e"], faces["n"], faces["m"], faces["flat"]
    out = np.full(len(points), np.inf)
    for lo in range(0, len(points), chunk):
        x = np.asarray(points[lo:lo + chunk])[:, None, :]           # (c, 1, 3)
        best = np.full((len(x), len(p)), np.inf)
        over = np.repeat(flat[None, :], len(x), axis=0)
        for k in range(3):
            w = x - p[None, :, k]                                    # (c, T, 3)
            over &= np.einsum("ctj,tj->ct", w, m[:, k]) >= 0.0
            ee = np.sum(e[:, k] ** 2, axis=1)
            t = np.clip(np.einsum("ctj,tj->ct", w, e[:, k]) / np.where(ee > 0, ee, 1.0), 0, 1)
            best = np.minimum(best, np.linalg.norm(w - t[..., None] * e[None, :, k], axis=2))
        h = np.abs(np.einsum("ctj,tj->ct", x - p[None, :, 0], n))
        out[lo:lo + chunk] = np.min(np.where(over, h, best), axis=1)
    return out


def distance_to_solid(solid, points, faces: dict | None = None) -> np.ndarray:
    """Exact distance from each point to the solid (0 inside, by the core's exact winding
    number: trimesh's ray test took more than 20 GB on the 20k-triangle gear)."""
    from planner._minkowski_core import winding_numbers

    d = distance_to_triangles(faces or _faces(solid), points)
    inside = winding_numbers(np.asarray(solid.vertices, dtype=np.float64),
                             np.asarray(solid.faces, dtype=np.int64),
                             np.ascontiguousarray(points, dtype=np.float64)) > 0
    return np.where(inside, 0.0, d)


def _unit(rng, n) -> np.ndarray:
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def true_boundary_points(solid, r: float, n: int, seed: int) -> np.ndarray:
    """Points of the exact offset's boundary: ``p + r u`` for ``p`` on faces (``u`` the
    normal), on edges (``u`` normal to the edge) and at vertices (any ``u``), kept where
    ``dist(p + r u, solid) = r`` (``p`` is then a nearest point)."""
    import trimesh
    rng = np.random.default_rng(seed)
    p, fid = trimesh.sample.sample_surface(solid, n, seed=seed)
    cands = [p + r * solid.face_normals[fid]]
    edges = solid.edges_unique
    ev = solid.vertices[edges]
    length = np.linalg.norm(ev[:, 1] - ev[:, 0], axis=1)
    pick = rng.choice(len(edges), size=2 * n, p=length / length.sum())
    t = rng.uniform(size=(2 * n, 1))
    q = ev[pick, 0] + t * (ev[pick, 1] - ev[pick, 0])
    axis = (ev[pick, 1] - ev[pick, 0]) / length[pick, None]
    u = _unit(rng, 2 * n)
    u -= np.sum(u * axis, axis=1, keepdims=True) * axis
    cands.append(q + r * u / np.linalg.norm(u, axis=1, keepdims=True))
    verts = solid.vertices[rng.integers(len(solid.vertices), size=2 * n)]
    cands.append(verts + r * _unit(rng, 2 * n))
    y = np.concatenate(cands)
    keep = distance_to_solid(solid, y) >= r * (1.0 - 1e-9)
    return y[keep]


def distance_to_surface(V, F, points) -> np.ndarray:
    """Distance from each point to the triangles (V, F), by FCL."""
    import fcl
    bvh = fcl.BVHModel()
    bvh.beginModel(len(V), len(F))
    bvh.addSubModel(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int32))
    bvh.endModel()
    mesh, probe = fcl.CollisionObject(bvh), fcl.Sphere(0.0)
    request = fcl.DistanceRequest()
    out = np.full(len(points), np.nan)
    for k, p in enumerate(points):
        out[k] = fcl.distance(mesh, fcl.CollisionObject(probe, fcl.Transform(p)), request,
                              fcl.DistanceResult())
    return np.maximum(out, 0.0)


def measure_error(solid, faces, r: float, V, F, truth: np.ndarray, samples: int,
                  seed: int) -> dict:
    import trimesh
    out = trimesh.Trimesh(V, F, process=False)
    pts, _ = trimesh.sample.sample_surface(out, samples, seed=seed)
    e_out = float(np.max(np.abs(distance_to_solid(solid, pts, faces) - r)))
    e_true = float(np.max(distance_to_surface(V, F, truth)))
    # as indexed (trimesh's merge of vertices within 1e-8 would pinch a part in metres)
    return {"err_out": e_out, "err_true": e_true, "err": max(e_out, e_true),
            "closed": bool(out.is_watertight and out.is_winding_consistent)}


# --------------------------------------------------------------------------------------
# the runs and the tables
# --------------------------------------------------------------------------------------

def run_case(case: dict, samples: int, seed: int) -> list[dict]:
    solid, r = case["mesh"], case["r"]
    faces = _faces(solid)
    truth = true_boundary_points(solid, r, max(samples // 4, 500), seed)
    log(f"{case['name']}: {len(solid.faces)} triangles, r = {r:g}, "
        f"{len(truth)} exact boundary points")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_offsets_") as d:
        tmp = Path(d)
        np.savez(tmp / "input.npz", V=np.asarray(solid.vertices, dtype=np.float64),
                 F=np.asarray(solid.faces, dtype=np.int64))
        for tool in TOOLS:
            for param in case.get(tool, []):
                res = run_child(tool, param, case, tmp)
                row = {"input": case["name"], "r": r, "tool": tool, "param": param}
                if "failed" in res:
                    row["failed"] = res["failed"]
                else:
                    V, F = res.pop("V"), res.pop("F")
                    row.update(res, triangles=len(F))
                    row.update(measure_error(solid, faces, r, V, F, truth, samples, seed))
                    if tool.startswith("ours"):
                        row["holds"] = row["err"] <= row["bound"]
                rows.append(row)
                log(f"  {tool} {param}: " + (row.get("failed") or
                    f"{row['wall']:.2f} s, {row['triangles']} tris, err {row['err']:.2e}"))
    return rows


PARAM = {"ours": "eps={}", "ours-cells": "eps={}", "libigl": "s={}", "manifold": "ico sub {}"}


def _g(x, spec=".3g") -> str:
    return "—" if x is None else format(x, spec)


def table(rows: list[dict]) -> str:
    out = ["| input | tool | resolution | wall s | warm s | CPU s | peak MB (call) | triangles | "
           "err out→true | err true→out | measured err | bound (ours) | bound holds | closed |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for w in rows:
        res = PARAM[w["tool"]].format(w["param"])
        if "failed" in w:
            out.append(f"| {w['input']} | {w['tool']} | {res} | {w['failed']} |||||||||||")
            continue
        holds = {True: "yes", False: "NO"}.get(w.get("holds"), "—")
        out.append(
            f"| {w['input']} | {w['tool']} | {res} | {w['wall']:.3f} | "
            f"{_g(w.get('warm'), '.4f')} | {w['cpu']:.3f} | "
            f"{w['peak_mb']:.0f} ({w['peak_mb'] - w['base_mb']:.0f}) | {w['triangles']} | "
            f"{w['err_out']:.2e} | {w['err_true']:.2e} | {w['err']:.2e} | "
            f"{_g(w.get('bound'), '.2e')} | {holds} | {'yes' if w['closed'] else 'NO'} |")
    return "\n".join(out)


def equal_error(rows: list[dict]) -> str:
    """Per run of ours: each other tool's cheapest run at most as far off as ours."""
    out = ["| input | ours | ours err | ours s | ours tris | tool | its cheapest run ≤ ours err "
           "| its err | s ratio (it / ours) | tris ratio (it / ours) "
           "| interpolated at ours err: s ratio | tris ratio | warm s ratio (its cheapest warm) "
           "| warm s, interpolated |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    ok = [w for w in rows if "failed" not in w]
    for o in (w for w in ok if w["tool"] == "ours"):
        for tool in ("libigl", "manifold"):
            fit = [w for w in ok if w["tool"] == tool and w["input"] == o["input"]
                   and w["err"] <= o["err"]]
            head = (f"| {o['input']} | eps={o['param']} | {o['err']:.2e} | {o['wall']:.2f} | "
                    f"{o['triangles']} | {tool} |")
            if not fit:
                best = min((w["err"] for w in ok if w["tool"] == tool
                            and w["input"] == o["input"]), default=None)
                out.append(f"{head} none (best err {_g(best, '.2e')}) | | | | — | — | — | — |")
                continue
            w = min(fit, key=lambda x: x["wall"])
            s_i, t_i = _interpolated(ok, o, tool)
            # (warm, the cheapest run by its warm seconds: the first call's one-time costs
            # can order them otherwise)
            warm_runs = [x["warm"] for x in fit if x.get("warm")]
            warm = _ratio(min(warm_runs), o.get("warm")) if warm_runs else None
            warm_i = _interpolated(ok, o, tool, "warm")[0]
            out.append(f"{head} {PARAM[tool].format(w['param'])} | {w['err']:.2e} | "
                       f"{w['wall'] / o['wall']:.3g} | {w['triangles'] / o['triangles']:.3g} | "
                       f"{_g(s_i)} | {_g(t_i)} | {_g(warm)} | {_g(warm_i)} |")
    return "\n".join(out)


def _ratio(theirs: float | None, ours: float | None) -> float | None:
    """Their seconds over ours, when both were measured."""
    return None if theirs is None or not ours else theirs / ours


def _interpolated(ok: list[dict], o: dict, tool: str, seconds: str = "wall"
                  ) -> tuple[float | None, float | None]:
    """The tool's ``seconds`` (first call's ``wall``, or ``warm``) and triangles at our
    error, over ours: log-log between its two runs whose errors bracket ours (none when
    none do, or when a run has no such seconds)."""
    if not o.get(seconds):
        return None, None
    runs = sorted((w for w in ok if w["tool"] == tool and w["input"] == o["input"]),
                  key=lambda w: w["err"])
    for lo, hi in zip(runs, runs[1:]):
        if lo["err"] <= o["err"] <= hi["err"] and lo["err"] < hi["err"]:
            if not (lo.get(seconds) and hi.get(seconds)):
                return None, None
            f = np.log(o["err"] / lo["err"]) / np.log(hi["err"] / lo["err"])

            def at(key, lo=lo, hi=hi, f=f):
                return float(np.exp((1 - f) * np.log(lo[key]) + f * np.log(hi[key])))
            return at(seconds) / o[seconds], at("triangles") / o["triangles"]
    return None, None


def versions() -> dict:
    from importlib.metadata import version
    return {name: version(name) for name in ("minkplan", "libigl", "manifold3d", "trimesh",
                                             "python-fcl", "numpy")}


def markdown(meta: dict, rows: list[dict]) -> str:
    doc = (__doc__ or "").split("\n\n")
    return "\n\n".join([
        f"# Offsets: ours vs libigl vs manifold3d ({meta['date']})",
        "Run: `python tests/benchmarks/bench_offsets.py` — " + " ".join(doc[0].split()),
        f"Machine: {meta['cpu_count']} cores (shared with other builds: wall seconds are "
        f"noisy, compare within this run), load average at start {meta['load']}, "
        f"{meta['platform']}. Versions: " + ", ".join(f"{k} {v}" for k, v in
                                                    meta["versions"].items()) + ".",
        f"Error: {meta['samples']} points sampled on each output and the exact offset's "
        "boundary points; see the script's docstring. `peak MB` is the child process's "
        "peak resident memory, `(call)` what the call added to the peak after imports and "
        "input.",
        "## All runs", table(rows),
        "## At equal error", equal_error(rows)]) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--worker", help=argparse.SUPPRESS)
    p.add_argument("--tables", type=Path,
                   help="write the tables again from a results JSON (to --out) and stop")
    p.add_argument("--quick", action="store_true", help="one resolution or two per tool")
    p.add_argument("--samples", type=int, default=20000,
                   help="points sampled on each output (and a quarter as many candidates of "
                        "the exact boundary, per kind of feature)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--inputs", default="",
                   help="comma-separated first words of the inputs to run (box, bunny-like, "
                        "factory, peg, gear); default: all")
    p.add_argument("--out", type=Path, default=RESULTS,
                   help="write PREFIX.md and PREFIX.json (default: results/<date>-offsets)")
    args = p.parse_args(argv)
    if args.worker:
        return worker(args.worker)
    if args.tables:
        saved = json.loads(args.tables.read_text())
        args.out.with_suffix(".md").write_text(markdown(saved["meta"], saved["rows"]))
        return 0
    meta = {"date": datetime.date.today().isoformat(), "cpu_count": os.cpu_count(),
            "load": " ".join(f"{x:.1f}" for x in os.getloadavg()),
            "platform": platform.platform(), "versions": versions(),
            "samples": args.samples, "seed": args.seed, "quick": args.quick}
    rows: list[dict] = []
    only = {w.strip().lower() for w in args.inputs.split(",") if w.strip()} or None
    for case in inputs(args.quick, only):
        rows += run_case(case, args.samples, args.seed)
        args.out.with_suffix(".json").write_text(
            json.dumps(jsonable({"meta": meta, "rows": rows}), indent=2, allow_nan=True))
    text = markdown(meta, rows)
    args.out.with_suffix(".md").write_text(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
