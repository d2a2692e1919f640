"""Subsets of a moving part's triangles whose C-obstacles lie inside the part's: slabs.

The part's triangles that meet a slab across its middle, taken as a *surface*, collide
only where some of them meet an obstacle's triangles or lie inside a solid obstacle —
and then the whole part collides too. So the slab's C-obstacles lie inside the part's,
the part's free space inside the slab's, and a component walled off for the slab is
walled off for the part (the enclosure proofs of :mod:`.local_proof` and
:mod:`planner.assembly.enclosure` use that). A slab has far fewer triangle pairs (a
nut's thread turn against the bolt, not all of them), hence a far cheaper C-space; when
it slips out where the part cannot, the whole part is tried after it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np
import trimesh

from planner.problem import Part

__all__ = ["SLAB_MIN_TRIANGLES", "SLAB_REL", "cropped", "subsets"]

SLAB_MIN_TRIANGLES = 2000
"""Slabs are tried only for parts with at least this many triangles (for fewer, the
whole part's C-space is cheap)."""

SLAB_REL = 0.25
"""Thickness of the part's slabs, as a fraction of its extent along the slab's axis."""


def subsets(part: Part) -> Iterator[tuple[str, Part]]:
    """``(label, robot)``: the part's slabs across its middle, along its shortest extent
    first, as surfaces (for a part of :data:`SLAB_MIN_TRIANGLES` or more); then the whole
    part (label ``"whole part"``)."""
    lo, hi = part.mesh.bounds
    centre, extent = (lo + hi) / 2, hi - lo
    many = len(part.mesh.faces) >= SLAB_MIN_TRIANGLES
    slabs: list[int] = [int(a) for a in np.argsort(extent, kind="stable")] if many else []
    for axis in slabs:
        slab_lo, slab_hi = lo.copy(), hi.copy()
        slab_lo[axis] = centre[axis] - SLAB_REL * extent[axis] / 2
        slab_hi[axis] = centre[axis] + SLAB_REL * extent[axis] / 2
        robot = cropped(part, slab_lo, slab_hi)
        if len(robot.mesh.faces):
            yield (f"{'xyz'[axis]} slab", robot)
    yield ("whole part", part)


def cropped(part: Part, lo: np.ndarray, hi: np.ndarray) -> Part:
    """The part's triangles whose boxes meet the box ``[lo, hi]``, as a surface."""
    triangles = part.mesh.triangles
    keep = np.all(triangles.max(axis=1) >= lo, axis=1) & np.all(triangles.min(axis=1) <= hi,
                                                                  axis=1)
    mesh = trimesh.Trimesh(part.mesh.vertices, part.mesh.faces[keep], process=False)
    mesh.remove_unreferenced_vertices()
    return dataclasses.replace(part, mesh=mesh, solid=False, checked=False,
                               kind_reason="a subset of the part's triangles (enclosure)")
