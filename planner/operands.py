"""Operands of the one-shot commands (sums, offsets, penetration depth): a
:class:`~planner.problem.Part` as it is, or a mesh, ``(vertices, faces)`` or a mesh file
made a checked solid part the way a problem's parts are (T-junctions of a CAD export split:
:func:`planner.meshes.kinds.classify`), named by its role and the file it came from."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from .errors import InvalidMeshError
from .meshes import load_mesh
from .meshes.kinds import classify
from .meshes.topology import checked_arrays
from .problem import Part

__all__ = ["REPAIR_OFFER", "as_mesh", "label", "solid_part"]


def as_mesh(obj, role: str) -> trimesh.Trimesh:
    """The operand's triangles: a mesh as it is, ``(vertices, faces)``, or a mesh file."""
    if isinstance(obj, (str, Path)):
        return load_mesh(obj, name=role)
    if isinstance(obj, tuple) and len(obj) == 2:
        try:
            return trimesh.Trimesh(np.asarray(obj[0], dtype=np.float64),
                                   np.asarray(obj[1], dtype=np.int64), process=False)
        except (TypeError, ValueError) as error:
            raise InvalidMeshError(f"{role}: not a (vertices, faces) pair: {error}") from None
    if not isinstance(obj, trimesh.Trimesh):
        raise InvalidMeshError(f"{role}: expected a trimesh.Trimesh, (vertices, faces) or a "
                               f"mesh file, got {type(obj).__name__}")
    return obj


def label(mesh: trimesh.Trimesh, role: str) -> str:
    """How errors and logs name an operand: its role, and the file it came from if any
    (``"a (peg.obj)"``, as the commands name the files they read)."""
    path = mesh.metadata.get("file_path")
    return f"{role} ({Path(path).name})" if path else role


def solid_part(obj, role: str, *, repair: bool | None = None) -> Part:
    """The operand as a solid part: a part as it is (a problem's, whose kind and checks a
    source keeps), anything else checked as a solid (see the module documentation); with
    ``repair``, its holes filled where they can be (:func:`planner.meshes.repair_mesh`).
    ``repair=False``: the caller has that option, and a refusal offers it;
    ``None``: it has none."""
    if isinstance(obj, Part):
        return obj
    mesh = as_mesh(obj, role)
    name = label(mesh, role)
    if repair is False:
        checked_arrays(mesh, f"mesh {name!r}")  # what the offer below would not mend
    try:
        solid = classify(mesh, name=name, kind="solid", repair=bool(repair))
    except InvalidMeshError as error:
        if repair is not False:  # (offered as the offsets offer it: for any refusal)
            raise
        raise InvalidMeshError(f"{error}; or: {REPAIR_OFFER}") from None
    return Part(name, solid.mesh, f"operand {role}", kind_reason=solid.reason, checked=True,
                repairs=solid.changes)


REPAIR_OFFER = ("repair=True (minkplan: --repair) drops faces it cannot use and fills the holes "
                "where it can, saying what it changed")
"""What an open operand's refusal offers where the call takes ``repair`` (and its command
``--repair``)."""
