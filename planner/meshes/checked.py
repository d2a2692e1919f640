"""The core's checked mesh of a trimesh, built once per mesh and content.

Checking a solid is the costly part of taking a mesh into the core (its winding numbers in
front of every triangle and at every crossing: about a sixth of a coarse offset of a
20k-triangle gear). :func:`planner.meshes.validate_solid` computes them with the core's
:func:`~planner._minkowski_core.solid_windings`, which gives the checked solid too; it is
remembered here against the validated trimesh, so the sums, offsets and depths that take
that mesh next (:func:`core_mesh`) do not check it again.

A remembered mesh is given back only for the same trimesh object with the same content
(a digest of its vertex and face arrays' bytes: trimesh's own hash misses writes made
through a plain array view, ``np.asarray(mesh.vertices)[...] = ...``) and of the same
kind; the entry goes with the trimesh. Nothing is attached to the trimesh itself,
so copies and pickles of it are as before.
"""

from __future__ import annotations

import hashlib
import weakref
from typing import Any

import numpy as np
import trimesh

__all__ = ["core_mesh", "remember"]

_REMEMBERED: dict[int, tuple[weakref.ref, bytes, bool, Any]] = {}
"""``id(trimesh)`` -> (a weak reference to it, its content digest, solid, the CheckedMesh)."""


def _content(mesh: trimesh.Trimesh) -> bytes:
    """A digest of the mesh's vertex and face arrays as they are now (about a millisecond
    for 20k triangles; the check it saves takes a fifth of a second)."""
    digest = hashlib.blake2b(digest_size=16)
    for array in (mesh.vertices, mesh.faces):
        plain = np.ascontiguousarray(array)
        digest.update(str((plain.dtype, plain.shape)).encode())
        digest.update(plain.data)
    return digest.digest()


def remember(mesh: trimesh.Trimesh, checked: Any, *, solid: bool) -> None:
    """Keep ``checked`` (a :class:`~planner._minkowski_core.CheckedMesh` of ``mesh``'s
    vertices and faces as they are now) for :func:`core_mesh`."""
    key = id(mesh)
    _REMEMBERED[key] = (weakref.ref(mesh, lambda _ref: _REMEMBERED.pop(key, None)),
                        _content(mesh), solid, checked)


def core_mesh(mesh: trimesh.Trimesh, *, solid: bool, name: str) -> Any:
    """The core's :class:`~planner._minkowski_core.CheckedMesh` of ``mesh`` (a solid, or
    with ``solid=False`` its triangles as a surface): the one remembered for it when its
    content has not changed since, else checked now (and remembered). ``name`` names it
    in the core's errors."""
    from planner._minkowski_core import CheckedMesh  # noqa: PLC0415

    entry = _REMEMBERED.get(id(mesh))
    if entry is not None:
        ref, content, kind, checked = entry
        if ref() is mesh and kind == solid and content == _content(mesh):
            return checked
    checked = CheckedMesh(np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                          np.ascontiguousarray(mesh.faces, dtype=np.int64),
                          solid=solid, name=name)
    remember(mesh, checked, solid=solid)
    return checked
