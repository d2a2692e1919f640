"""Hand-written mesh code against the libraries that do the same (issue 19, item 6).

Opt-in (pytest never collects tests/benchmarks). Run from the repository root::

    python tests/benchmarks/bench_libraries.py [--out PREFIX]

For each piece of ``planner.meshes`` that a well-kept library also offers, the same input
goes through both; the table gives seconds (best of three), the library's time as a ratio
to the hand-written code's (the anchor) and whether the answers agree. Where the library
replaced the code (winding numbers, grouping rows, ear clipping), the hand-written side is
the code as it was, kept here. The numbers are the measured reasons in the code's
comments: a piece is kept only where the library is slower or answers another question.

Inputs: the IndustReal large gear (50,566 triangles, ``../shared/assets``; an icosphere of
81,920 triangles stands in when the folder is absent), the geometric peg-in-hole OBJ
files (n-gons) and a few constructed cases (a pair of vertices straddling trimesh's
rounding grid, polygons with collinear corners, a box with a non-convex hole).

Needs the ``bench`` extra (``pip install -e '.[test,bench]'``: networkx for
``trimesh.repair.fix_winding`` and ``fill_holes``, mapbox-earcut for the ear clipper
trimesh's ``triangulate_polygon`` calls).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import mapbox_earcut
import numpy as np
import trimesh

from planner.meshes import load_mesh, load_obj, validate_solid, winding_numbers
from planner.meshes.topology import (
    boundary_loops,
    group_rows,
    merge_vertices,
    orient_consistently,
)
from planner.meshes.triangulation import _polygon_frame, polygon_in_plane, triangulate_polygons
from planner.tolerances import scale_of, tol

HERE = Path(__file__).resolve().parent
ASSETS = HERE.parents[1].parent / "shared" / "assets"
GEAR = ASSETS / "assemblies" / "industreal_gears" / "meshes" / "industreal_gear_large.obj"
PEG_SET = ASSETS / "geometric_peg_in_hole_2mm"
RESULTS = HERE / "results" / "2026-12-02-libraries"


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)  # noqa: T201 (progress of an opt-in script)


def best_of(run, repeat: int = 3):
    """``(seconds, result)``: the fastest of ``repeat`` calls and the last result."""
    best, result = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def big_solid() -> tuple[str, trimesh.Trimesh]:
    if GEAR.is_file():
        return "IndustReal large gear", validate_solid(load_mesh(GEAR), name="gear")
    log(f"{GEAR} is absent: using an icosphere instead")
    return "icosphere", validate_solid(trimesh.creation.icosphere(subdivisions=6))


def row(item: str, ours: float, theirs: float, library: str, agree: str) -> dict:
    return {"item": item, "ours_s": ours, "library": library, "library_s": theirs,
            "ratio": theirs / ours, "agree": agree}


def numpy_solid_angles(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """The numpy direct sum ``planner.meshes.winding_numbers`` was before libigl."""
    points = np.asarray(points, dtype=np.float64)
    result = np.zeros(len(points))
    if len(points) == 0 or len(triangles) == 0:
        return result
    corners = [np.ascontiguousarray(triangles[:, i, j]) for i in range(3) for j in range(3)]
    chunk = max(1, 1_000_000 // len(triangles))
    for start in range(0, len(points), chunk):
        px, py, pz = (points[start:start + chunk, k, None] for k in range(3))
        ax, ay, az = corners[0] - px, corners[1] - py, corners[2] - pz
        bx, by, bz = corners[3] - px, corners[4] - py, corners[5] - pz
        cx, cy, cz = corners[6] - px, corners[7] - py, corners[8] - pz
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (
            la * lb * lc
            + (ax * bx + ay * by + az * bz) * lc
            + (ax * cx + ay * cy + az * cz) * lb
            + (bx * cx + by * cy + bz * cz) * la
        )
        result[start:start + chunk] = np.arctan2(det, den).sum(axis=1) / (2 * np.pi)
    return result


def bench_winding(name: str, solid: trimesh.Trimesh) -> list[dict]:
    from planner._minkowski_core import winding_numbers as core_windings

    points = np.random.default_rng(0).uniform(*solid.bounds, size=(400, 3))
    triangles = np.asarray(solid.triangles)
    ours, old = best_of(lambda: numpy_solid_angles(points, triangles), 1)
    theirs, new = best_of(lambda: winding_numbers(points, triangles))
    core, exact = best_of(lambda: core_windings(np.asarray(solid.vertices),
                                                np.asarray(solid.faces), points))
    same = int(((old > 0.5) == (new > 0.5)).sum())
    agree = (f"max |diff| {np.abs(old - new).max():.1e}; {same}/400 same side; the core's "
             f"exact ray cast agrees on {int(((exact != 0) == (new > 0.5)).sum())}/400 "
             f"in {core:.3f} s")
    return [row(f"winding numbers, 400 points ({name})", ours, theirs,
                "igl.winding_number", agree)]


def hand_group_rows(rows: np.ndarray):
    """The lexsort ``planner.meshes.topology.group_rows`` was before trimesh's."""
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    new = np.ones(len(rows), dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    group = np.cumsum(new) - 1
    inverse = np.zeros(len(rows), dtype=np.int64)
    inverse[order] = group
    return inverse, np.bincount(group), order[new]


def bench_group_rows(name: str, solid: trimesh.Trimesh) -> list[dict]:
    faces = np.asarray(solid.faces, dtype=np.int64)
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    ours, (inverse, counts, first) = best_of(lambda: hand_group_rows(edges), 5)
    theirs, (inv, cnt, uniq) = best_of(lambda: group_rows(edges), 5)
    same = np.array_equal(np.sort(first), np.sort(uniq)) and np.array_equal(
        counts[inverse], cnt[inv])
    return [row(f"group equal rows, {len(edges)} edges ({name})", ours, theirs,
                "trimesh.grouping.unique_rows (group_rows now)",
                "same groups" if same else "DIFFERENT")]


def bench_merge(name: str, solid: trimesh.Trimesh) -> list[dict]:
    raw = load_mesh(GEAR) if GEAR.is_file() else solid
    vertices = np.asarray(raw.vertices, dtype=np.float64)
    faces = np.asarray(raw.faces, dtype=np.int64)
    distance = tol.merge_rel * scale_of(vertices)
    ours, (_, _, merged) = best_of(lambda: merge_vertices(vertices, faces, distance))

    def library():
        copy = trimesh.Trimesh(vertices, faces, process=False)
        copy.merge_vertices(merge_tex=True, merge_norm=True)
        return len(vertices) - len(copy.vertices)

    theirs, trimesh_merged = best_of(library)
    clusters, groups = best_of(lambda: trimesh.grouping.clusters(vertices, distance))
    # two vertices 1e-12 apart on either side of trimesh's rounding grid (tol.merge = 1e-8)
    straddle = np.array([[0.5e-8 - 1e-12, 0, 0], [0.5e-8 + 1e-12, 0, 0], [1, 0, 0], [0, 1, 0]])
    tri = np.array([[0, 2, 3], [1, 3, 2]])
    ours_pair = merge_vertices(straddle, tri, 1e-9)[2]
    pair = trimesh.Trimesh(straddle, tri, process=False)
    pair.merge_vertices()
    agree = (f"ours merges {merged}, trimesh {trimesh_merged} (rounded to 1e-8 absolute, "
             f"scale {scale_of(vertices):.3g}); 2 vertices 2e-12 apart across a grid line: "
             f"ours merges {ours_pair}, trimesh {4 - len(pair.vertices)}; "
             f"grouping.clusters (same cKDTree pairs) {clusters:.3f} s, {len(groups)} groups")
    return [row(f"merge vertices, {len(vertices)} vertices ({name})", ours, theirs,
                "Trimesh.merge_vertices", agree)]


def bench_winding_fix(name: str, solid: trimesh.Trimesh) -> list[dict]:
    faces = np.asarray(solid.faces, dtype=np.int64).copy()
    flip = np.random.default_rng(1).random(len(faces)) < 0.1
    faces[flip] = faces[flip][:, ::-1]
    ours, (fixed, _, orientable) = best_of(lambda: orient_consistently(faces))

    def library():
        mesh = trimesh.Trimesh(np.asarray(solid.vertices), faces.copy(), process=False)
        trimesh.repair.fix_winding(mesh)
        return mesh

    theirs, mesh = best_of(library, 1)
    ours_ok = trimesh.Trimesh(np.asarray(solid.vertices), fixed, process=False)
    agree = (f"both consistent: ours {ours_ok.is_winding_consistent} (and says orientable: "
             f"{orientable}), trimesh {mesh.is_winding_consistent} (says nothing when it "
             f"cannot)")
    return [row(f"consistent winding, {len(faces)} faces, 10% flipped ({name})", ours,
                theirs, "trimesh.repair.fix_winding", agree)]


def obj_polygons(path: Path) -> tuple[np.ndarray, list[list[int]]]:
    vertices, polygons = [], []
    for line in path.read_text().splitlines():
        fields = line.split()
        if fields[:1] == ["v"]:
            vertices.append([float(x) for x in fields[1:4]])
        elif fields[:1] == ["f"]:
            polygons.append([int(t.split("/")[0]) - 1 for t in fields[1:]])
    return np.asarray(vertices), polygons


def earcut(points: np.ndarray) -> np.ndarray:
    """mapbox-earcut on a 3D polygon put in its plane, as ``(k, 3)`` local indices."""
    frame = _polygon_frame(points)
    assert frame is not None
    _, u, v = frame
    xy = np.stack([points @ u, points @ v], axis=1)
    flat = mapbox_earcut.triangulate_float64(xy, np.array([len(points)], dtype=np.uint32))
    return np.asarray(flat, dtype=np.int64).reshape(-1, 3)


def bench_triangulation() -> list[dict]:
    polygons = []
    for path in sorted(PEG_SET.glob("*.obj")) if PEG_SET.is_dir() else []:
        vertices, faces = obj_polygons(path)
        polygons += [vertices[p] for p in faces if len(p) > 4]
    square = [(0, 0), (1, 0), (2, 0), (2, 1), (2, 2), (0, 2)]  # corners on straight sides
    collinear = np.array([[x, y, 0.0] for x, y in square])
    polygons.append(collinear)
    ours, ours_out = best_of(lambda: [hand_ear_clip(p)[0] for p in polygons])
    theirs, their_out = best_of(lambda: [earcut(p) for p in polygons])
    short = sum(len(t) < len(p) - 2 for t, p in zip(their_out, polygons, strict=True))
    kept = sum(len(t) == len(p) - 2 for t, p in zip(ours_out, polygons, strict=True))
    solid_files = earcut_solids = 0
    for path in sorted(PEG_SET.glob("*.obj")) if PEG_SET.is_dir() else []:
        solid_files += _is_solid(load_obj(path))
        earcut_solids += _is_solid(_earcut_obj(path))
    same_area = sum(
        np.isclose(_area(p, t), _area(p, e), rtol=1e-9, atol=0)
        for p, t, e in zip(polygons, ours_out, their_out, strict=True))
    agree = (f"n-2 triangles: old {kept}/{len(polygons)}, earcut "
             f"{len(polygons) - short}/{len(polygons)}; same area {same_area}/"
             f"{len(polygons)}; peg-in-hole OBJs that are closed solids as read: old "
             f"{solid_files}, earcut {earcut_solids}")
    quads = np.random.default_rng(3).random((5000, 4, 3)) * [1, 1, 0]
    quads[:, :, 0] += [0, 1, 1, 0]
    quads[:, :, 1] += [0, 0, 1, 1]
    points = quads.reshape(-1, 3)
    index = np.arange(len(points)).reshape(-1, 4)
    vectorised, _ = best_of(lambda: triangulate_polygons(points, index.tolist()))
    looped, _ = best_of(lambda: [earcut(points[q]) for q in index], 1)
    return [row(f"triangulate {len(polygons)} n-gons (peg-in-hole OBJs + 1)", ours, theirs,
                "mapbox_earcut (trimesh.creation.triangulate_polygon's engine)", agree),
            row("split 5000 convex quads", vectorised, looped, "mapbox_earcut per quad",
                "all quads at once (numpy) vs one earcut call each")]


def _area(points: np.ndarray, triangles: np.ndarray) -> float:
    corners = points[triangles]
    return float(0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum())


def hand_ear_clip(points: np.ndarray):
    """The hand-written ear clipper ``planner.meshes.triangulation`` had before earcut.

    Returns ``(triangles, ok)``: ``(n - 2, 3)`` local indices wound like the polygon, and
    whether every cut was a proper ear (``False`` for degenerate polygons or when a
    forced cut was needed).
    """
    n = len(points)
    fan, xy = polygon_in_plane(points)
    if xy is None:
        return fan, False
    extent = float(np.ptp(xy, axis=0).max())
    eps = 1e-12 * extent * extent  # orientation tolerance (twice a triangle area)

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (
            b[..., 1] - a[..., 1]
        ) * (c[..., 0] - a[..., 0])

    ring = list(range(n))
    out: list[tuple[int, int, int]] = []
    ok = True
    while len(ring) > 3:
        m = len(ring)
        idx = np.asarray(ring)
        prev_i, next_i = np.roll(idx, 1), np.roll(idx, -1)
        turn = orient(xy[prev_i], xy[idx], xy[next_i])
        reflex = idx[turn <= eps]
        chosen = -1
        for pos in np.flatnonzero(turn > eps):
            a, b, c = prev_i[pos], idx[pos], next_i[pos]
            others = reflex[(reflex != a) & (reflex != b) & (reflex != c)]
            if len(others):
                q = xy[others]
                # points coinciding with a corner (keyhole bridges) do not block the ear
                same = (
                    np.all(q == xy[a], axis=1)
                    | np.all(q == xy[b], axis=1)
                    | np.all(q == xy[c], axis=1)
                )
                q = q[~same]
                inside = (
                    (orient(xy[a], xy[b], q) >= -eps)
                    & (orient(xy[b], xy[c], q) >= -eps)
                    & (orient(xy[c], xy[a], q) >= -eps)
                )
                if inside.any():
                    continue
            chosen = int(pos)
            break
        if chosen < 0:  # no proper ear: self-touching or numerically degenerate polygon
            ok = False
            chosen = int(np.argmax(turn))
        out.append((int(prev_i[chosen]), int(idx[chosen]), int(next_i[chosen])))
        del ring[chosen % m]
    out.append((ring[0], ring[1], ring[2]))
    return np.asarray(out, dtype=np.int64), ok


def _is_solid(mesh: trimesh.Trimesh) -> bool:
    try:
        validate_solid(mesh)
    except Exception:  # noqa: BLE001 (any refusal counts as "not a solid")
        return False
    return True


def _earcut_obj(path: Path) -> trimesh.Trimesh:
    vertices, polygons = obj_polygons(path)
    faces = []
    for polygon in polygons:
        local = earcut(vertices[polygon]) if len(polygon) > 3 else np.array([[0, 1, 2]])
        triangles = np.asarray(polygon)[local]
        corners = vertices[triangles]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        frame = _polygon_frame(vertices[polygon])
        if frame is not None:  # earcut winds its own way: wind like the polygon
            backwards = normal @ frame[0] < 0
            triangles[backwards] = triangles[backwards][:, ::-1]
        faces.append(triangles)
    return trimesh.Trimesh(vertices, np.concatenate(faces), process=False)


def holed_box() -> trimesh.Trimesh:
    """A 4 x 4 x 1 box with an L-shaped hole (three unit squares, 8 corners, two of them
    on straight sides) cut in its top face."""
    box = trimesh.creation.box([4.0, 4.0, 1.0]).subdivide().subdivide()
    centres = box.triangles_center
    in_l = ((centres[:, 2] > 0.49) & (centres[:, 0] < 0) & (centres[:, 1] < -1)) | (
        (centres[:, 2] > 0.49) & (centres[:, 0] < -1) & (centres[:, 1] < 0))
    holed = trimesh.Trimesh(box.vertices, box.faces[~in_l], process=False)
    holed.remove_unreferenced_vertices()
    return holed


def bench_loops(name: str, solid: trimesh.Trimesh) -> list[dict]:
    """Boundary loops of the big solid with 2% of its faces removed (many holes, some
    touching)."""
    import networkx

    keep = np.random.default_rng(2).random(len(solid.faces)) >= 0.02
    holed = trimesh.Trimesh(np.asarray(solid.vertices), np.asarray(solid.faces)[keep],
                            process=False)
    faces = np.asarray(holed.faces, dtype=np.int64)
    ours, (loops, tangled) = best_of(lambda: boundary_loops(faces))

    def library():
        edges = holed.edges[trimesh.grouping.group_rows(holed.edges_sorted, require_count=1)]
        return networkx.cycle_basis(networkx.from_edgelist(edges))

    theirs, cycles = best_of(library)
    agree = (f"ours {len(loops)} loops in the faces' direction and {tangled} edges at "
             f"pinches set apart; networkx {len(cycles)} undirected basis cycles (a pinch "
             f"splits or joins them arbitrarily)")
    return [row(f"boundary loops, {int((~keep).sum())} faces removed ({name})", ours, theirs,
                "networkx.cycle_basis (as trimesh.repair.fill_holes)", agree)]


def bench_fill() -> list[dict]:
    from planner.meshes import repair_mesh

    mesh = holed_box()
    ours, (repaired, report) = best_of(lambda: repair_mesh(mesh))

    def library():
        filled = mesh.copy()
        return filled, trimesh.repair.fill_holes(filled)

    theirs, (filled, closed) = best_of(library)
    fanned = mesh.copy()
    trimesh.repair.fill_holes(fanned, use_fan=True)
    agree = (f"repair_mesh fills {report['filled_holes']} hole: volume "
             f"{repaired.volume:.3f} (the box's 16); fill_holes: closed {closed}, watertight "
             f"{filled.is_watertight} (it fills triangles and quads only); with use_fan: "
             f"watertight {fanned.is_watertight}, a solid {_is_solid(fanned)}")
    return [row("fill an L-shaped hole (8 corners) in a box's top", ours, theirs,
                "trimesh.repair.fill_holes", agree)]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(RESULTS), help="results prefix (.json, .md)")
    args = parser.parse_args(argv)
    name, solid = big_solid()
    rows = []
    for stage in (bench_winding, bench_group_rows, bench_merge, bench_winding_fix,
                  bench_loops):
        log(f"{stage.__name__} on {name} ({len(solid.faces)} triangles)")
        rows += stage(name, solid)
    log("triangulation")
    rows += bench_triangulation()
    log("hole filling")
    rows += bench_fill()
    out = Path(args.out)
    out.with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")
    lines = ["| item | hand-written (s) | library | library (s) | library / hand | answers |",
             "| --- | ---: | --- | ---: | ---: | --- |"]
    lines += [f"| {r['item']} | {r['ours_s']:.4f} | {r['library']} | {r['library_s']:.4f} | "
              f"{r['ratio']:.2f} | {r['agree']} |" for r in rows]
    out.with_suffix(".md").write_text(
        "# Hand-written mesh code vs libraries\n\nRun: `python "
        "tests/benchmarks/bench_libraries.py` (best of three; one run where the library "
        "or the old code is slow).\n\n" + "\n".join(lines) + "\n")
    log("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
