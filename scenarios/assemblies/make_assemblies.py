"""Generate the part meshes of the assembly demos (``scenarios/assemblies/*.yaml``).

Run from anywhere: ``python scenarios/assemblies/make_assemblies.py``. Writes small STL
files into ``scenarios/assemblies/meshes/``; the YAML files are written by hand.

The burr puzzles (``six_piece_burr``, ``three_piece_burr``) are notched square sticks on a
unit lattice, each one closed manifold shell (its voxels unioned with manifold3d), every
piece eroded by half the clearance so neighbours keep ``BURR_GAP`` between them; see
:func:`burr_piece`. The other demos are described below.

Every part is a union of axis-aligned boxes stored as separate closed shells in one mesh
file, in world coordinates of the assembled pose (so the YAML poses are the identity).
Boxes of one part overlap in volume and share no vertex position, so every shell is
convex and the decomposition is exact (no CoACD). Different parts touch face to face
where they rest on each other, and otherwise keep gaps (0.05, or 0.01 between the box's
walls and lid). No part touches two parts on opposite faces: the FCL checker certifies a
tolerated contact with a short free escape, which a clamped part does not have.
"""

from __future__ import annotations

import sys
from pathlib import Path

import manifold3d
import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
OUT = HERE / "meshes"


def box(lo, hi) -> trimesh.Trimesh:
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    mesh = trimesh.creation.box(extents=hi - lo)
    mesh.apply_translation((lo + hi) / 2.0)
    return mesh


def union_of(*boxes) -> trimesh.Trimesh:
    return trimesh.util.concatenate([box(lo, hi) for lo, hi in boxes])


PARTS = {
    # peg_in_block: a block with a 0.5 x 0.5 blind hole (floor at z = 0.2) and a
    # 0.4 x 0.4 peg resting on the hole's floor: clearance 0.05 on every side.
    "block": union_of(
        ([-0.75, -0.75, 0.0], [0.75, 0.75, 0.2]),      # floor slab
        ([-0.75, -0.75, 0.1], [-0.25, 0.75, 1.0]),     # west wall
        ([0.25, -0.75, 0.1], [0.75, 0.75, 1.0]),       # east wall
        ([-0.3, -0.75, 0.1], [0.3, -0.25, 1.0]),       # south wall
        ([-0.3, 0.25, 0.1], [0.3, 0.75, 1.0]),         # north wall
    ),
    "peg": union_of(([-0.2, -0.2, 0.2], [0.2, 0.2, 1.4])),
    # pegs_and_holes: two plates, each with a peg and a through-hole, mated along z.
    "lower": union_of(
        ([-1.0, -0.5, 0.0], [0.25, 0.5, 0.3]),
        ([0.75, -0.5, 0.0], [1.0, 0.5, 0.3]),
        ([0.2, -0.5, 0.0], [0.8, -0.25, 0.3]),
        ([0.2, 0.25, 0.0], [0.8, 0.5, 0.3]),
        ([-0.7, -0.2, 0.2], [-0.3, 0.2, 0.9]),         # peg up through the upper plate
    ),
    "upper": union_of(
        ([-1.0, -0.5, 0.3], [-0.75, 0.5, 0.6]),
        ([-0.25, -0.5, 0.3], [1.0, 0.5, 0.6]),
        ([-0.8, -0.5, 0.3], [-0.2, -0.25, 0.6]),
        ([-0.8, 0.25, 0.3], [-0.2, 0.5, 0.6]),
        ([0.3, -0.2, 0.05], [0.7, 0.2, 0.4]),          # peg down into the lower plate
    ),
    # latched_box: floor, four walls, a lid with a channel on top, and a latch in the
    # channel under a roof: it must slide +x out from under the roof, then lift.
    "floor": union_of(([-1.0, -1.0, 0.0], [1.0, 1.0, 0.2])),
    "wall_w": union_of(([-1.0, -1.0, 0.2], [-0.8, 1.0, 1.19])),
    "wall_e": union_of(([0.8, -1.0, 0.2], [1.0, 1.0, 1.19])),
    "wall_s": union_of(([-0.79, -1.0, 0.2], [0.79, -0.8, 1.19])),
    "wall_n": union_of(([-0.79, 0.8, 0.2], [0.79, 1.0, 1.19])),
    "lid": union_of(
        ([-1.0, -1.0, 1.2], [1.0, 1.0, 1.4]),          # plate
        ([-0.9, -0.5, 1.3], [0.9, -0.3, 1.7]),         # rails
        ([-0.9, 0.3, 1.3], [0.9, 0.5, 1.7]),
        ([-0.85, -0.45, 1.3], [-0.7, 0.45, 1.7]),      # end stops
        ([0.75, -0.45, 1.3], [0.88, 0.45, 1.7]),
        ([-0.8, -0.5, 1.6], [0.0, 0.5, 1.8]),          # roof over the -x half
    ),
    "latch": union_of(([-0.65, -0.25, 1.4], [-0.25, 0.25, 1.55])),
    # linked_rings: two square rings of bars, one through the other.
    "ring_a": union_of(
        ([-1.0, -1.0, -0.1], [1.0, -0.8, 0.1]),
        ([-1.0, 0.8, -0.1], [1.0, 1.0, 0.1]),
        ([-1.0, -0.95, -0.1], [-0.8, 0.95, 0.1]),
        ([0.8, -0.95, -0.1], [1.0, 0.95, 0.1]),
    ),
    "ring_b": union_of(
        ([0.3, -0.1, -0.6], [1.5, 0.1, -0.4]),
        ([0.3, -0.1, 0.4], [1.5, 0.1, 0.6]),
        ([0.3, -0.1, -0.55], [0.5, 0.1, 0.55]),
        ([1.3, -0.1, -0.55], [1.5, 0.1, 0.55]),
    ),
    # rings_in_tray: the linked rings above the floor of an open tray: neither ring can
    # leave alone, the two leave upwards together (and stay linked).
    "tray": union_of(
        ([-1.2, -1.2, -0.8], [1.8, 1.2, -0.65]),      # floor, 0.05 under ring_b
        ([-1.2, -1.2, -0.75], [-1.05, 1.2, 0.8]),     # west wall
        ([1.65, -1.2, -0.75], [1.8, 1.2, 0.8]),       # east wall
        ([-1.15, -1.2, -0.75], [1.75, -1.05, 0.8]),   # south wall
        ([-1.15, 1.05, -0.75], [1.75, 1.2, 0.8]),     # north wall
    ),
    # hooked_pair: in an open cup, a C-shaped hook_a (opening +x) holds the arm of a
    # Γ-shaped hook_b: each blocks the other upwards and the cup blocks them sideways, so
    # neither can leave alone; together they lift out, then hook_b slides out along +x.
    "cup": union_of(
        ([0.0, -0.1, 0.0], [1.0, 0.5, 0.1]),          # floor
        ([0.0, -0.1, 0.05], [0.1, 0.5, 0.8]),         # west wall
        ([0.9, -0.1, 0.05], [1.0, 0.5, 0.8]),         # east wall
        ([0.05, -0.1, 0.05], [0.95, 0.0, 0.8]),       # south wall
        ([0.05, 0.4, 0.05], [0.95, 0.5, 0.8]),        # north wall
    ),
    "hook_a": union_of(
        ([0.12, 0.02, 0.1], [0.2, 0.38, 0.7]),        # stem, resting on the floor
        ([0.15, 0.02, 0.1], [0.6, 0.38, 0.2]),        # foot
        ([0.15, 0.02, 0.6], [0.6, 0.38, 0.7]),        # top
    ),
    "hook_b": union_of(
        ([0.3, 0.02, 0.3], [0.8, 0.38, 0.5]),         # arm, between hook_a's foot and top
        ([0.75, 0.02, 0.1], [0.88, 0.38, 0.7]),       # stem, resting on the floor
    ),
}


# ------------------------------------------------------------------ burr puzzles
#
# Lattice: voxel index i spans [i - 2, i - 1] along each axis, so the 4 x 4 x 4 core of
# the six-piece burr is [-2, 2]^3 (indices 0..3) and a stick of length 8 runs over
# indices -2..5. A stick is named by its axis and its two indices across it.

BURR_GAP = 0.02
"""Clearance between neighbouring burr pieces (each piece is eroded by half of it)."""


def _stick(axis: int, across: tuple[tuple[int, int], tuple[int, int]],
           length: range) -> set[tuple[int, int, int]]:
    cells = set()
    for t in length:
        for u in across[0]:
            for v in across[1]:
                c = [u, v]
                c.insert(axis, t)
                cells.add((c[0], c[1], c[2]))
    return cells


def _cube(cell, grow: float = 0.0) -> manifold3d.Manifold:
    lo = np.asarray(cell, dtype=float) - 2.0 - grow
    return manifold3d.Manifold.cube([1.0 + 2 * grow] * 3).translate(tuple(lo))


def burr_piece(cells: set[tuple[int, int, int]], gap: float = BURR_GAP) -> trimesh.Trimesh:
    """One closed manifold mesh: the union of the voxels ``cells``, eroded by ``gap / 2``
    (the voxels around it, grown by ``gap / 2``, cut away: an exact erosion of a union of
    boxes, which shrinking each box would not be)."""
    solid = manifold3d.Manifold.batch_boolean([_cube(c) for c in sorted(cells)],
                                              manifold3d.OpType.Add)
    near = {(c[0] + dx, c[1] + dy, c[2] + dz) for c in cells
            for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)} - cells
    cut = manifold3d.Manifold.batch_boolean([_cube(c, gap / 2) for c in sorted(near)],
                                            manifold3d.OpType.Add)
    mesh = (solid - cut).to_mesh()
    out = trimesh.Trimesh(np.asarray(mesh.vert_properties, dtype=float)[:, :3],
                          np.asarray(mesh.tri_verts, dtype=np.int64), process=True)
    assert out.is_watertight and out.is_volume, "a burr piece must be one closed solid"
    return out


# Six-piece burr: two sticks along each axis (2 x 2 x 8), side by side; every cell of the
# core claimed by two or three sticks belongs to one of them (or, one cell, to none).
# Found by a search over those assignments on the lattice (each piece one face-connected
# solid; with every piece present only the key x1 can leave, straight along +x; then z1
# must step sideways before it can leave; then y0, x0, y1 lift out straight). The notches
# below are the cells each full stick gives up.
SIX_STICKS = {
    "x0": (0, ((0, 1), (1, 2))), "x1": (0, ((2, 3), (1, 2))),
    "y0": (1, ((1, 2), (0, 1))), "y1": (1, ((1, 2), (2, 3))),
    "z0": (2, ((0, 1), (1, 2))), "z1": (2, ((2, 3), (1, 2))),
}
SIX_NOTCHES = {
    "x0": [(0, 1, 1), (0, 1, 2), (1, 1, 1), (1, 1, 2), (2, 1, 1), (2, 1, 2), (3, 1, 1),
           (3, 1, 2)],
    "x1": [(1, 2, 2)],
    "y0": [(1, 0, 1), (1, 1, 0), (1, 1, 1), (1, 2, 0), (1, 2, 1), (1, 3, 1), (2, 0, 1),
           (2, 2, 1), (2, 3, 1)],
    "y1": [(1, 0, 2), (1, 2, 2), (1, 3, 2), (2, 0, 2), (2, 1, 2), (2, 2, 2), (2, 3, 2)],
    "z0": [(0, 2, 1), (0, 2, 2), (1, 1, 2), (1, 1, 3), (1, 2, 1), (1, 2, 2), (1, 2, 3)],
    "z1": [(2, 1, 0), (2, 1, 1), (2, 1, 3), (2, 2, 0), (2, 2, 1), (2, 2, 2), (2, 2, 3),
           (3, 2, 1), (3, 2, 2)],
}

# Three-piece burr: three orthogonal sticks (2 x 2 x 8) crossing near the middle; z is the
# base. Neither x nor y can leave alone, but together they slide off z along -y, and
# then come apart (x steps out of y's notch).
THREE_STICKS = {"x": (0, ((0, 1), (1, 2))), "y": (1, ((1, 2), (0, 1))),
                "z": (2, ((0, 1), (1, 2)))}
THREE_NOTCHES = {
    "x": [(0, 1, 1), (0, 1, 2), (1, 1, 1), (2, 0, 1)],
    "y": [(1, 0, 1), (1, 1, 0), (1, 1, 1), (1, 2, 1), (2, 1, 1)],
    "z": [(1, 1, 0), (1, 1, 1), (1, 1, 2), (1, 2, 0), (1, 2, 1)],
}


def burr_cells(sticks: dict, notches: dict) -> dict[str, set[tuple[int, int, int]]]:
    """Each piece's cells: its full stick minus its notches (checked to be disjoint)."""
    cells = {}
    for name, (axis, across) in sticks.items():
        full = _stick(axis, across, range(-2, 6))
        notch = set(notches[name])
        assert notch <= full, name
        cells[name] = full - notch
    names = list(cells)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert not cells[a] & cells[b], (a, b)
    return cells


def burr_parts() -> dict[str, trimesh.Trimesh]:
    """The burr puzzles' meshes, by file stem."""
    out = {}
    for prefix, sticks, notches in (("burr6", SIX_STICKS, SIX_NOTCHES),
                                    ("burr3", THREE_STICKS, THREE_NOTCHES)):
        for name, cells in burr_cells(sticks, notches).items():
            out[f"{prefix}_{name}"] = burr_piece(cells)
    return out


def main() -> None:
    OUT.mkdir(exist_ok=True)
    for name, mesh in {**PARTS, **burr_parts()}.items():
        mesh.export(OUT / f"{name}.stl")
        sys.stdout.write(f"wrote {OUT / (name + '.stl')}\n")


if __name__ == "__main__":
    main()
