"""Mesh files: read STL, OBJ, PLY, OFF, GLB/GLTF and DAE into one triangle mesh.

Entry points: :func:`load_mesh` (any supported format; scenes flattened with every node's
transform applied) and :func:`load_obj` (Wavefront OBJ read for its geometry only, n-gon
faces triangulated in their own plane by :mod:`planner.meshes.triangulation`).
Nothing here judges whether a mesh is a solid: see :mod:`planner.meshes.solids`.
"""

from __future__ import annotations

import logging
import os
import warnings
from pathlib import Path

import numpy as np
import trimesh

from planner.errors import InvalidMeshError

from .triangulation import triangulate_polygons

__all__ = ["MESH_SUFFIXES", "load_mesh", "load_obj"]

log = logging.getLogger(__name__)


MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf", ".dae")
"""File suffixes :func:`load_mesh` accepts (case-insensitive)."""


def load_mesh(path, *, name: str | None = None) -> trimesh.Trimesh:
    """Read a mesh file into a single triangle mesh.

    Scenes (GLB, DAE, multi-object files) are flattened into one mesh with every node's
    transform applied. OBJ files are read by :func:`load_obj` (n-gons ear-clipped in
    their plane; texture coordinates and normals ignored). The mesh is returned as read
    (vertices not merged, float64): pass it to :func:`validate_solid` (or
    :func:`repair_mesh`) before use.

    Args:
        path: file path (``str`` or ``os.PathLike``).
        name: label used in error messages and stored in ``mesh.metadata["name"]``;
            defaults to the path.

    Returns:
        ``trimesh.Trimesh`` with ``metadata["name"]`` and ``metadata["file_path"]`` set.

    Raises:
        InvalidMeshError: the file does not exist, is not a file, has an unsupported
            suffix, cannot be parsed, or holds no triangles.
    """
    path = Path(os.fspath(path))
    label = _file_label(path, name)
    if not path.exists():
        raise InvalidMeshError(f"{label}: file not found; check the path")
    if not path.is_file():
        raise InvalidMeshError(f"{label}: not a regular file")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise InvalidMeshError(
            f"{label}: unsupported mesh format {suffix or '(no suffix)'!r}; "
            f"use one of {', '.join(MESH_SUFFIXES)}"
        )
    if path.stat().st_size == 0:
        raise InvalidMeshError(f"{label}: empty file (0 bytes)")
    if suffix == ".obj":
        mesh = load_obj(path, name=name)
    else:
        if suffix == ".stl":
            _check_stl(path, label)
        try:  # NaN/inf coordinates make trimesh's normals warn: validation refuses them
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                loaded = trimesh.load(path, force="mesh", process=False)
        except Exception as exc:  # trimesh raises many types on bad files
            raise InvalidMeshError(
                f"{label}: cannot read {suffix[1:].upper()} file "
                f"({type(exc).__name__}: {_first_line(exc)})"
            ) from exc
        mesh = _as_single_mesh(loaded, label)
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise InvalidMeshError(f"{label}: no triangles in file (empty or not a surface mesh)")
    mesh.metadata["name"] = name if name is not None else str(path)
    mesh.metadata["file_path"] = str(path)
    return mesh


def load_obj(path, *, name: str | None = None) -> trimesh.Trimesh:
    """Read the geometry of a Wavefront OBJ file, triangulating polygons correctly.

    Only ``v`` and ``f`` records are used (texture coordinates, normals, groups and
    materials are ignored), so vertices are shared exactly as the file's indices say —
    no seams are introduced along texture or normal discontinuities. Every face with
    more than three corners is triangulated in its own plane: quads along the diagonal
    that keeps both triangles facing the polygon's normal, larger polygons by ear
    clipping (which handles non-convex and "keyhole" polygons, and collinear corners).
    A naive fan triangulation gets non-convex polygons wrong while keeping the volume
    right, so the error would go unnoticed downstream.

    Args:
        path: the ``.obj`` file.
        name: label for error messages (defaults to the path).

    Returns:
        ``trimesh.Trimesh`` (``process=False``); ``metadata["polygon_problems"]`` counts
        polygons that could not be triangulated cleanly (degenerate or self-touching).

    Raises:
        InvalidMeshError: unreadable file, malformed record (the message gives the
            line), an index out of range, or no faces.
    """
    path = Path(os.fspath(path))
    label = _file_label(path, name)
    try:
        text = path.read_text(encoding="utf-8", errors="strict")
    except UnicodeDecodeError as exc:
        raise InvalidMeshError(f"{label}: not a text OBJ file ({exc.reason})") from exc
    except OSError as exc:
        raise InvalidMeshError(f"{label}: cannot read file ({exc.strerror or exc})") from exc

    vertices: list[tuple[float, float, float]] = []
    polygons: list[list[int]] = []
    lines = text.replace("\\\n", " ").splitlines()
    for number, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        key, _, rest = line.partition(" ")
        if key == "v":
            fields = rest.split()
            try:
                if len(fields) < 3:
                    raise ValueError("fewer than 3 coordinates")
                vertices.append((float(fields[0]), float(fields[1]), float(fields[2])))
            except ValueError as exc:
                raise InvalidMeshError(f"{label}: line {number}: bad vertex ({exc})") from exc
        elif key == "f":
            corners = []
            for token in rest.split():
                try:
                    index = int(token.split("/", 1)[0])
                except ValueError as exc:
                    raise InvalidMeshError(
                        f"{label}: line {number}: bad face index {token!r}"
                    ) from exc
                if index < 0:
                    index += len(vertices)  # relative to the vertices read so far
                else:
                    index -= 1
                if not 0 <= index < len(vertices):
                    raise InvalidMeshError(
                        f"{label}: line {number}: face index {token!r} out of range "
                        f"({len(vertices)} vertices defined so far)"
                    )
                corners.append(index)
            if len(corners) < 3:
                raise InvalidMeshError(
                    f"{label}: line {number}: face with {len(corners)} corners (need >= 3)"
                )
            polygons.append(corners)
    if not polygons:
        raise InvalidMeshError(f"{label}: no faces in OBJ file (empty or not a surface mesh)")
    points = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    faces, problems = triangulate_polygons(points, polygons)
    if problems:
        log.warning(
            "%s: %d polygon(s) could not be triangulated cleanly (degenerate or "
            "self-touching); validate the result",
            label,
            problems,
        )
    mesh = trimesh.Trimesh(points, faces, process=False)
    mesh.metadata["polygon_problems"] = problems
    return mesh


def _check_stl(path: Path, label: str) -> None:
    """Reject a corrupt or truncated STL with a clear message before trimesh tries to
    read it (trimesh falls back to parsing unknown binary as ASCII, which fails with
    unrelated errors such as a missing ``charset_normalizer``)."""
    size = path.stat().st_size
    with path.open("rb") as handle:
        head = handle.read(84)
    if len(head) == 84:
        count = int.from_bytes(head[80:84], "little")
        if size == 84 + 50 * count:
            return  # a well-formed binary STL
    with path.open("rb") as handle:
        sample = handle.read(4096)
    text = sample.lstrip().lower()
    if text.startswith(b"solid") and (b"facet" in sample.lower() or size <= 4096):
        try:
            sample.decode("ascii")
        except UnicodeDecodeError:
            pass
        else:
            return  # ASCII STL; trimesh reports its own parse errors
    if len(head) == 84:
        raise InvalidMeshError(
            f"{label}: corrupt or truncated binary STL (header says {count} triangles = "
            f"{84 + 50 * count} bytes, file has {size} bytes); re-export the file"
        )
    raise InvalidMeshError(f"{label}: not an STL file (too short and not ASCII STL)")


def _file_label(path: Path, name: str | None) -> str:
    if name is None or name == str(path):
        return f"mesh file '{path}'"
    return f"mesh {name!r} (file '{path}')"


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    text = text.splitlines()[0] if text else "no details"
    prefix = f"{type(exc).__name__}: "
    while text.startswith(prefix):  # some loaders repeat the class name
        text = text[len(prefix):]
    return text


def _concatenated(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """One mesh of several, as ``trimesh.util.concatenate`` makes it."""
    mesh = trimesh.util.concatenate(meshes)
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def _as_single_mesh(loaded, label: str) -> trimesh.Trimesh:
    """Turn what ``trimesh.load(force="mesh")`` returned into one Trimesh."""
    mesh: trimesh.Trimesh
    if isinstance(loaded, trimesh.Trimesh):
        mesh = loaded
    elif isinstance(loaded, trimesh.Scene):
        meshes = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        if not meshes:
            raise InvalidMeshError(f"{label}: no triangle meshes in file")
        mesh = _concatenated(meshes)
    elif isinstance(loaded, (list, tuple)):
        meshes = [g for g in loaded if isinstance(g, trimesh.Trimesh)]
        if not meshes:
            raise InvalidMeshError(f"{label}: no triangle meshes in file")
        mesh = _concatenated(meshes)
    else:
        raise InvalidMeshError(
            f"{label}: file holds {type(loaded).__name__}, not a triangle mesh"
        )
    return trimesh.Trimesh(
        np.asarray(mesh.vertices, dtype=np.float64),
        np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3),
        process=False,
    )
