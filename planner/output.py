"""Output files: JSON-ready values and writes that never leave half a file.

Every JSON file minkplan writes starts with ``"schema": "minkplan/NAME/1"``
(:func:`schema_id`). Entry points: :func:`jsonable` (numpy scalars and arrays to Python
ones, non-finite floats to ``None``), :func:`atomic_write` (a temporary file in the same
folder, then a rename), :func:`write_json`, :func:`write_mesh`, :func:`unwritable` (why a
file could not be written there, checked before the work).
"""

from __future__ import annotations

import json
import logging
import math
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FLOAT32_SUFFIXES", "SCHEMA_VERSION", "atomic_write", "float32_fault", "jsonable",
           "schema_id", "unwritable", "write_json", "write_mesh"]

SCHEMA_VERSION = 1
"""The version of every output file's layout; it changes when a key changes meaning or
goes away (new keys do not change it). Each file's JSON Schema is
``docs/schemas/NAME.schema.json``."""


def schema_id(name: str) -> str:
    """The ``"schema"`` value of output file ``name``: ``minkplan/NAME/VERSION``."""
    return f"minkplan/{name}/{SCHEMA_VERSION}"


def jsonable(value: Any) -> Any:
    """``value`` with numpy scalars and arrays turned into Python ones, non-finite floats
    into ``None`` (JSON has no inf/nan)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, str):
        return str(value)  # str enums (PlanStatus) as their value
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        number = float(value)
        return number if math.isfinite(number) else None
    return value


MESH_SUFFIXES = (".glb", ".obj", ".off", ".ply", ".stl")
"""Output mesh formats the commands write (trimesh's exporters)."""


TEXT_DIGITS = 17
"""Decimals of the text formats' coordinates (trimesh writes 8 for OBJ: 1e-8 m, coarser
than an offset's bound on a part measured in metres)."""


def write_mesh(mesh, path: Path) -> None:
    """Write ``mesh`` at ``path`` in the format its suffix names, atomically (text formats
    with :data:`TEXT_DIGITS` decimals); warn when vertices apart in float64 share a
    position at float32 (STL, glTF and PLY as trimesh writes it store no more): a reader
    that joins vertices by position then sees the surface pinched there."""
    kind = path.suffix.lower().lstrip(".")
    options = {"digits": TEXT_DIGITS} if kind in ("obj", "off") else {}
    atomic_write(path, lambda tmp: mesh.export(tmp, file_type=kind, **options))
    if kind in ("stl", "glb", "ply"):
        vertices = np.asarray(mesh.vertices, dtype=np.float64)
        joined = len(np.unique(vertices, axis=0)) - len(np.unique(vertices.astype(np.float32),
                                                                   axis=0))
        if joined:
            logging.getLogger(__name__).warning(
                "%s: %d vertices fall on others at the format's float32 precision: a reader "
                "joining vertices by position sees the surface pinched there (.obj and .off "
                "keep every digit)", path, joined)


def float32_move(mesh, path: Path) -> float:
    """How far the format of ``path`` moves the mesh's vertices at most: their rounding to
    float32 for STL, glTF and PLY (as trimesh writes them), 0 for OBJ and OFF."""
    if path.suffix.lower() not in (".stl", ".glb", ".ply"):
        return 0.0
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    return float(np.linalg.norm(vertices - vertices.astype(np.float32), axis=1).max(initial=0.0))


FLOAT32_SUFFIXES = (".stl", ".glb", ".ply")
"""The mesh formats written with float32 coordinates."""


def float32_fault(mesh, path: Path) -> str | None:
    """Why the clean solid ``mesh``, rounded to float32 as the format of ``path`` stores
    it, is no clean solid (two sheets a rounding apart now cross, a sliver turns over), or
    ``None``: always ``None`` for OBJ and OFF, which keep every digit, and for a ``mesh``
    that is no clean solid itself. The copy is validated as :func:`planner.validate_solid`
    would read the file back."""
    if path.suffix.lower() not in FLOAT32_SUFFIXES:
        return None
    import trimesh

    from planner.errors import InvalidMeshError
    from planner.meshes.solids import not_solid_reason, validate_solid

    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    try:
        validate_solid(trimesh.Trimesh(vertices.astype(np.float32).astype(np.float64), faces,
                                       process=False), name=str(path))
    except InvalidMeshError as error:
        try:  # (said only of a clean solid the rounding breaks)
            validate_solid(trimesh.Trimesh(vertices, faces, process=False), name=str(path))
        except InvalidMeshError:
            return None
        return not_solid_reason(error)
    return None


def unknown_mesh_format(path: Path) -> str | None:
    """Why ``path`` names no mesh format the commands write, or ``None``."""
    if path.suffix.lower() in MESH_SUFFIXES:
        return None
    return f"unknown mesh format {path.suffix!r}; use one of {list(MESH_SUFFIXES)}"


def unwritable(path: Path) -> str | None:
    """Why a file cannot be written at ``path`` (its missing folders would be created), or
    ``None``: checked before the work, so a bad path costs nothing."""
    try:
        return _unwritable(path)
    except OSError as exc:  # a name over the file system's limit, a loop of links...
        return f"cannot be used ({exc.strerror or exc})"


def missing_folder(path: Path) -> Path | None:
    """The outermost folder that writing ``path`` would create (:func:`atomic_write` makes
    missing folders), or ``None`` when its folder exists; said in what a command prints, so
    a mistyped path does not make folders unnoticed."""
    try:
        return _nearest_existing(Path(path))[1]
    except OSError:  # a name over the file system's limit: :func:`unwritable` says so
        return None


def _nearest_existing(path: Path) -> tuple[Path | None, Path | None]:
    """The nearest folder above ``path`` that exists, and the outermost one below it that
    does not (``None`` when ``path``'s own folder exists)."""
    missing = None
    for parent in path.parents:
        if parent.exists():
            return parent, missing
        missing = parent
    return None, missing


def created_text(folder: Path | None) -> str:
    """``"; created folder F"`` for a command's summary line, or ``""``."""
    return f"; created folder {folder}" if folder is not None else ""


def _unwritable(path: Path) -> str | None:
    if path.is_dir():
        return "is a directory"
    parent, missing = _nearest_existing(path)
    if parent is None:
        return None
    if not parent.is_dir():
        return f"{parent} is a file, not a folder"
    return _unwritable_in(parent, missing)


def _unwritable_in(folder: Path, missing: Path | None) -> str | None:
    """Why nothing can be written in the existing ``folder`` (``missing``: the folder in
    it that would be created first, named when that is what fails), or ``None``."""
    what = (f"folder {folder} is not writable" if missing is None else
            f"folder {missing} does not exist and cannot be created in {folder}")
    if not os.access(folder, os.W_OK | os.X_OK):
        return what
    try:  # the permission bits can say yes where the file system says no (/proc)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:  # (the OS's reason can be odd: /proc says no such file)
        return f"{what} (creating a file there failed: {exc.strerror or exc})"
    return None


def atomic_write(path: Path, write: Callable[[str], Any]) -> None:
    """Write via a temporary file in the same directory (``write(temporary path)``), then
    rename: never half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the usual permissions
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_json(path: Path, document: Any, indent: int | None = 2) -> None:
    """``document`` as JSON (strict: no NaN), written atomically."""
    text = json.dumps(document, indent=indent, allow_nan=False) + "\n"
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))
