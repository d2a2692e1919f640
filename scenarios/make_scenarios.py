"""Generate the obstacle meshes of the bundled planning scenarios (``scenarios/*.yaml``).

Run from anywhere: ``python scenarios/make_scenarios.py``. Writes small binary STL files
next to this script; the YAML files that use them are written by hand.

Every obstacle is a union of axis-aligned boxes stored as separate closed shells in one
mesh file. Neighbouring boxes overlap in volume (never merely touch face to face) and
share no vertex position (the mesh loader would merge such vertices), so
each shell is convex and the decomposition is exact (no CoACD): planner certificates on
these scenarios are exact. Overlapping shells in one file are a valid solid for
``planner.meshes.validate_solid``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent


def box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    mesh = trimesh.creation.box(extents=hi - lo)
    mesh.apply_translation((lo + hi) / 2.0)
    return mesh


def union_of(boxes) -> trimesh.Trimesh:
    return trimesh.util.concatenate([box(lo, hi) for lo, hi in boxes])


def frame_with_hole(axis: int, lo: float, hi: float, half: float, center=(0.0, 0.0),
                    extent: float = 30.0, overlap: float = 1.0):
    """Four boxes forming a plate normal to ``axis`` (from ``lo`` to ``hi`` along it),
    covering ``[-extent, extent]^2`` in the other two axes around a square hole of
    half-width ``half`` at ``center``; the two short bars overlap the long ones."""
    u, v = [k for k in range(3) if k != axis]
    cu, cv = center
    spans = [
        ((-extent, cu - half), (-extent, extent)),
        ((cu + half, extent), (-extent, extent)),
        ((cu - half - overlap, cu + half + overlap), (-extent, cv - half)),
        ((cu - half - overlap, cu + half + overlap), (cv + half, extent)),
    ]
    out = []
    for (u0, u1), (v0, v1) in spans:
        b0, b1 = [0.0] * 3, [0.0] * 3
        b0[axis], b1[axis] = lo, hi
        b0[u], b1[u] = u0, u1
        b0[v], b1[v] = v0, v1
        out.append((b0, b1))
    return out


def peg_blocks() -> dict[str, trimesh.Trimesh]:
    """60 x 60 x 20 blocks (z from -20 to 0) with a square through-hole for the
    10 x 10 x 30 peg, clearance 1, 0.1 and 0.01 per side."""
    out = {}
    for name, clearance in (("block_c1", 1.0), ("block_c0.1", 0.1), ("block_c0.01", 0.01)):
        out[f"peg_in_hole/{name}.stl"] = union_of(
            frame_with_hole(2, -20.0, 0.0, 5.0 + clearance, extent=30.0)
        )
    return out


def chambers() -> dict[str, trimesh.Trimesh]:
    """A closed 100 x 60 x 60 box (walls 5 thick) split at x = 0 by a 4-thick plate with
    a square hole centred at y = z = 8: 6 wide (too small for the 10-cube robot) or 14
    wide (fits)."""
    t = 5.0
    shell = [
        ([-50, -30, -30], [-50 + t, 30, 30]),
        ([50 - t, -30, -30], [50, 30, 30]),
        ([-49, -30, -30], [49, -30 + t, 30]),
        ([-49, 30 - t, -30], [49, 30, 30]),
        ([-48, -29, -30], [48, 29, -30 + t]),
        ([-48, -29, 30 - t], [48, 29, 30]),
    ]
    out = {}
    for name, hole in (("closed", 6.0), ("open", 14.0)):
        # the plate overlaps the side walls (extent 29 > 25)
        plate = frame_with_hole(0, -2.0, 2.0, hole / 2.0, center=(8.0, 8.0), extent=29.0)
        out[f"sealed_chamber/chamber_{name}.stl"] = union_of(shell + plate)
    return out


def bug_trap() -> dict[str, trimesh.Trimesh]:
    """An 80 x 60 x 60 cage (walls 4 thick) whose +x wall has a 20 x 20 opening, with a
    square tube (walls 2 thick) leading from the opening 30 deep into the cage: a robot
    inside must find the tube's inner mouth to get out."""
    t = 4.0
    cage = [
        ([-40, -30, -30], [-40 + t, 30, 30]),
        ([-39, -30, -30], [39, -30 + t, 30]),
        ([-39, 30 - t, -30], [39, 30, 30]),
        ([-38, -29, -30], [38, 29, -30 + t]),
        ([-38, -29, 30 - t], [38, 29, 30]),
    ]
    wall = frame_with_hole(0, 40 - t, 40, 10.0, extent=30.0)
    tube = [
        ([10, 10, -12], [39, 12, 12]),
        ([10, -12, -12], [39, -10, 12]),
        ([10, -11, 10], [39, 11, 12]),
        ([10, -11, -12], [39, 11, -10]),
    ]
    return {"bug_trap/trap.stl": union_of(cage + wall + tube)}


def maze() -> dict[str, trimesh.Trimesh]:
    """A 100 x 100 x 96 tower (walls 3 thick) of three floors. The ceiling of floor 1
    has a 16 x 16 hole at (35, 35), that of floor 2 one at (-35, -35); floor 1 has a wall
    at x = 0 open at its +y end, floor 2 a wall at y = 0 open at its -x end."""
    t = 3.0
    shell = [
        ([-50, -50, 0], [-50 + t, 50, 96]),
        ([50 - t, -50, 0], [50, 50, 96]),
        ([-49, -50, 0], [49, -50 + t, 96]),
        ([-49, 50 - t, 0], [49, 50, 96]),
        ([-48, -48, 0], [48, 48, t]),
        ([-48, -48, 96 - t], [48, 48, 96]),
    ]
    ceil1 = frame_with_hole(2, 31, 34, 8.0, center=(35.0, 35.0), extent=49.0)
    ceil2 = frame_with_hole(2, 62, 65, 8.0, center=(-35.0, -35.0), extent=49.0)
    walls = [
        ([-2, -49, 2], [2, 30, 32]),  # floor 1: open for y > 30
        ([-30, -2, 33], [49, 2, 63]),  # floor 2: open for x < -30
    ]
    return {"maze/tower.stl": union_of(shell + ceil1 + ceil2 + walls)}


def main() -> None:
    meshes = {**peg_blocks(), **chambers(), **bug_trap(), **maze()}
    for rel, mesh in meshes.items():
        path = HERE / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        mesh.export(path, file_type="stl")
        print(f"wrote {path.relative_to(HERE.parent)}: {len(mesh.faces)} triangles")  # noqa: T201


if __name__ == "__main__":
    main()
