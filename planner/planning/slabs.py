"""Subsets of a moving part's triangles whose C-obstacles lie inside the part's: slabs.

The part's triangles that meet a slab across its middle, taken as a *surface*, collide
only where some of them meet an obstacle's triangles or lie inside a solid obstacle —
and then the whole part collides too. So the slab's C-obstacles lie inside the part's,
the part's free space inside the slab's, and a component walled off for the slab is
walled off for the part (the enclosure proofs of :mod:`.local_proof` and
:mod:`planner.assembly.enclosure` use that). A slab has far fewer triangle pairs (a
nut's thread turn against the bolt, not all of them), hence a far cheaper C-space; when
it slips out where the part cannot, the whole part is tried after it.

A part taken as a surface that is mostly one closed shell (mod 2: at least
:data:`WHOLE_FIRST_SHELL_SHARE` of its triangles; OMPL.app's escape robot, a ring of tube
segments sharing their caps) is tried whole first: the core shows its C-obstacle's
interior with that shell (an obstacle's connected surface crossing it), in cells as wide
as the shell is thick, and a slab cuts it open. (spirelli's robot, a surface with one
small closed shell, is proved fastest by a slab: in half the time of the whole part.)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

import numpy as np
import trimesh

from planner._minkowski_core import closed_shell_sizes
from planner.problem import Part

__all__ = ["SLAB_MIN_TRIANGLES", "SLAB_REL", "WHOLE_FIRST_SHELL_SHARE", "cropped", "subsets"]

SLAB_MIN_TRIANGLES = 2000
"""Slabs are tried only for parts with at least this many triangles (for fewer, the
whole part's C-space is cheap)."""

SLAB_REL = 0.25
"""Thickness of the part's slabs, as a fraction of its extent along the slab's axis."""

WHOLE_FIRST_SHELL_SHARE = 0.5
"""A surface part whose largest closed shell holds at least this share of its triangles
is tried whole before its slabs."""


def subsets(part: Part) -> Iterator[tuple[str, Part]]:
    """``(label, robot)``: the part's slabs across its middle, along its shortest extent
    first, as surfaces (for a part of :data:`SLAB_MIN_TRIANGLES` or more); then the whole
    part (label ``"whole part"``) — first instead when it is a surface that is mostly one
    closed shell (see the module documentation)."""
    whole_first = not part.solid and _mostly_one_shell(part.mesh)
    if whole_first:
        yield ("whole part", part)
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
    if not whole_first:
        yield ("whole part", part)


def _mostly_one_shell(mesh: trimesh.Trimesh) -> bool:
    """Whether the mesh's largest closed shell (mod 2) holds at least
    :data:`WHOLE_FIRST_SHELL_SHARE` of its triangles."""
    sizes = closed_shell_sizes(np.asarray(mesh.vertices, dtype=np.float64),
                               np.asarray(mesh.faces, dtype=np.int64))
    return bool(sizes) and sizes[0] >= WHOLE_FIRST_SHELL_SHARE * len(mesh.faces)


def cropped(part: Part, lo: np.ndarray, hi: np.ndarray) -> Part:
    """The part's triangles whose boxes meet the box ``[lo, hi]``, as a surface."""
    triangles = part.mesh.triangles
    keep = np.all(triangles.max(axis=1) >= lo, axis=1) & np.all(triangles.min(axis=1) <= hi,
                                                                  axis=1)
    mesh = trimesh.Trimesh(part.mesh.vertices, part.mesh.faces[keep], process=False)
    mesh.remove_unreferenced_vertices()
    return dataclasses.replace(part, mesh=mesh, solid=False, checked=False,
                               kind_reason="a subset of the part's triangles (enclosure)")
