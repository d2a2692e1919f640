"""Generate the part meshes of the assembly demos (``scenarios/assemblies/*.yaml``).

Run from anywhere: ``python scenarios/assemblies/make_assemblies.py``. Writes small STL
files into ``scenarios/assemblies/meshes/``; the YAML files are written by hand.

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


def main() -> None:
    OUT.mkdir(exist_ok=True)
    for name, mesh in PARTS.items():
        mesh.export(OUT / f"{name}.stl")
        sys.stdout.write(f"wrote {OUT / (name + '.stl')}\n")


if __name__ == "__main__":
    main()
