"""Load, validate and repair the solids minkplan works on.

Entry points:

- :func:`load_mesh` reads a mesh file (STL, OBJ, PLY, OFF, GLB/GLTF, DAE) into one
  ``trimesh.Trimesh``; OBJ files go through :func:`load_obj`, which triangulates n-gon
  faces properly (ear clipping in each polygon's plane) instead of fanning them.
- :func:`validate_solid` checks that a mesh bounds a solid (closed, manifold,
  consistently wound, finite, positive volume, winding number never negative) and
  returns a cleaned copy, or raises :class:`~planner.errors.InvalidMeshError` with a
  one-line reason.
- :func:`repair_mesh` is the explicit, best-effort repair for messy real-world meshes
  (merge vertices, drop degenerate/duplicate faces, fix winding, fill holes).
- :func:`mirror` gives the point reflection ``-M`` used for C-obstacles ``O ⊕ (-R)``.
- :func:`split_solid` splits a valid solid into bodies (an outer shell plus the cavity
  shells inside it), the units that :mod:`planner.decompose` works on.

Conventions: a valid solid's faces are wound counter-clockwise seen from outside (outward
normals, positive volume). A closed shell nested inside another one with inward normals
is a cavity; a shell with inward normals that is not inside another shell is a body that
was exported inside-out, and is flipped. The solid is where the winding number is at
least 1, and it must never be negative (checked exactly by the native core: no face may
have the inside in front of it); shells that overlap are their union. A closed surface
that fails this (a shell glued to another with the wrong side out, as OMPL.app's Easy
frame) is not a solid.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np
import trimesh
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from .errors import InvalidMeshError
from .tolerances import scale_of, tol

__all__ = [
    "MESH_SUFFIXES",
    "load_mesh",
    "load_obj",
    "mirror",
    "repair_mesh",
    "split_solid",
    "validate_solid",
    "winding_numbers",
]

log = logging.getLogger(__name__)

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf", ".dae")
"""File suffixes :func:`load_mesh` accepts (case-insensitive)."""


# ---------------------------------------------------------------------------- loading


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
        try:
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
    faces, problems = _triangulate_polygons(points, polygons)
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


def _as_single_mesh(loaded, label: str) -> trimesh.Trimesh:
    """Turn what ``trimesh.load(force="mesh")`` returned into one Trimesh."""
    if isinstance(loaded, trimesh.Trimesh):
        mesh = loaded
    elif isinstance(loaded, trimesh.Scene):
        meshes = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        if not meshes:
            raise InvalidMeshError(f"{label}: no triangle meshes in file")
        mesh = trimesh.util.concatenate(meshes)
    elif isinstance(loaded, (list, tuple)):
        meshes = [g for g in loaded if isinstance(g, trimesh.Trimesh)]
        if not meshes:
            raise InvalidMeshError(f"{label}: no triangle meshes in file")
        mesh = trimesh.util.concatenate(meshes)
    else:
        raise InvalidMeshError(
            f"{label}: file holds {type(loaded).__name__}, not a triangle mesh"
        )
    return trimesh.Trimesh(
        np.asarray(mesh.vertices, dtype=np.float64),
        np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3),
        process=False,
    )


# ------------------------------------------------------------------ triangulation


def _triangulate_polygons(points: np.ndarray, polygons: list[list[int]]):
    """Triangulate polygons (lists of vertex indices) in their planes.

    Returns ``(faces, problems)``: ``(m, 3)`` int64 faces, and the number of polygons
    that were degenerate or needed a forced (non-ear) cut.
    """
    triangles = [np.asarray([p for p in polygons if len(p) == 3], dtype=np.int64)]
    quads = np.asarray([p for p in polygons if len(p) == 4], dtype=np.int64).reshape(-1, 4)
    triangles.append(_split_quads(points, quads))
    problems = 0
    for polygon in polygons:
        if len(polygon) <= 4:
            continue
        local, ok = _ear_clip(points[polygon])
        problems += not ok
        triangles.append(np.asarray(polygon, dtype=np.int64)[local])
    faces = np.concatenate([t.reshape(-1, 3) for t in triangles])
    return faces, problems


def _split_quads(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Split quads (n, 4) along the diagonal whose two triangles face the quad normal."""
    if len(quads) == 0:
        return np.zeros((0, 3), dtype=np.int64)
    p = points[quads]  # (n, 4, 3)
    normal = np.cross(p[:, 0] - p[:, 2], p[:, 1] - p[:, 3])  # Newell normal of a quad
    # diagonal 0-2 gives (0,1,2) and (0,2,3); diagonal 1-3 gives (1,2,3) and (1,3,0)
    n012 = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n023 = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])
    use_02 = np.minimum((n012 * normal).sum(axis=1), (n023 * normal).sum(axis=1)) >= 0
    first = np.where(use_02[:, None], quads[:, [0, 1, 2]], quads[:, [1, 2, 3]])
    second = np.where(use_02[:, None], quads[:, [0, 2, 3]], quads[:, [1, 3, 0]])
    return np.concatenate([first, second])


def _polygon_frame(points: np.ndarray):
    """Newell normal of a 3D polygon and an orthonormal in-plane basis ``(u, v)`` with
    ``u x v`` along the normal, so the polygon winds counter-clockwise in ``(u, v)``."""
    shifted = points - points.mean(axis=0)
    normal = np.cross(shifted, np.roll(shifted, -1, axis=0)).sum(axis=0)
    length = np.linalg.norm(normal)
    if not np.isfinite(length) or length == 0:
        return None
    normal = normal / length
    helper = np.zeros(3)
    helper[np.argmin(np.abs(normal))] = 1.0
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    return normal, u, v


def _ear_clip(points: np.ndarray):
    """Ear-clip one polygon given as ``(n, 3)`` points in order.

    Returns ``(triangles, ok)``: ``(n - 2, 3)`` local indices wound like the polygon, and
    whether every cut was a proper ear (``False`` for degenerate polygons or when a
    forced cut was needed).
    """
    n = len(points)
    fan = np.stack([np.zeros(n - 2, dtype=np.int64), np.arange(1, n - 1), np.arange(2, n)], 1)
    frame = _polygon_frame(points)
    if frame is None:
        return fan, False
    _, u, v = frame
    centred = points - points.mean(axis=0)
    xy = np.stack([centred @ u, centred @ v], axis=1)
    extent = float(np.ptp(xy, axis=0).max())
    if extent == 0:
        return fan, False
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
            chosen = pos
            break
        if chosen < 0:  # no proper ear: self-touching or numerically degenerate polygon
            ok = False
            chosen = int(np.argmax(turn))
        out.append((int(prev_i[chosen]), int(idx[chosen]), int(next_i[chosen])))
        del ring[chosen % m]
    out.append((ring[0], ring[1], ring[2]))
    return np.asarray(out, dtype=np.int64), ok


# --------------------------------------------------------------------- topology


def _group_rows(rows: np.ndarray):
    """Group equal rows of an integer array (a fast ``np.unique(axis=0)``).

    Returns ``(inverse, counts, first)``: each row's group id (groups numbered in sorted
    row order), the size of each group, and the first row index of each group."""
    rows = np.asarray(rows)
    if len(rows) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    new = np.ones(len(rows), dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    group = np.cumsum(new) - 1
    inverse = np.zeros(len(rows), dtype=np.int64)
    inverse[order] = group
    return inverse, np.bincount(group), order[new]


def _edge_stats(faces: np.ndarray):
    """Edge usage of a triangle list.

    Returns ``(boundary, nonmanifold, consistent)``: the number of undirected edges used
    by one face, by more than two faces, and whether no directed edge is used twice
    (every interior edge is traversed once in each direction).
    """
    if len(faces) == 0:
        return 0, 0, True
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    undirected = np.sort(directed, axis=1)
    counts = _group_rows(undirected)[1]
    dcounts = _group_rows(directed)[1]
    return int((counts == 1).sum()), int((counts > 2).sum()), bool((dcounts == 1).all())


def _shell_edge_stats(faces: np.ndarray):
    """Edge usage counted shell by shell.

    Shells are the face components connected over edges used by exactly two faces.
    Closed shells that touch along an edge (two boxes sharing an edge, after vertex
    merging) make that edge non-manifold for the mesh, but each shell on its own is
    closed: such a mesh is a valid union of solids. Returns ``(boundary, nonmanifold,
    labels)`` counted per shell, and each face's shell label.
    """
    if len(faces) == 0:
        return 0, 0, np.zeros(0, dtype=np.int64)
    pairs, _ = _face_graph(faces)
    _, labels = _components(len(faces), pairs)
    undirected = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keyed = np.column_stack([np.repeat(labels, 3), undirected])
    counts = _group_rows(keyed)[1]
    return int((counts == 1).sum()), int((counts > 2).sum()), labels


def _unshare_vertices(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray):
    """Give every shell its own copy of the vertices it shares with other shells, so
    shells that touch along edges become separate, index-manifold components."""
    pairs = np.column_stack([faces.ravel(), np.repeat(labels, 3)])
    pairs = pairs[_group_rows(pairs)[2]]
    if len(np.unique(pairs[:, 0])) == len(pairs):
        return vertices, faces  # no vertex is shared between shells
    # one new vertex per (vertex, shell) pair
    keys = faces.ravel() * (labels.max() + 1) + np.repeat(labels, 3)
    uniq, inverse = np.unique(keys, return_inverse=True)
    new_vertices = vertices[uniq // (labels.max() + 1)]
    return new_vertices, inverse.reshape(-1, 3)


def _face_graph(faces: np.ndarray):
    """Face adjacency over edges shared by exactly two faces.

    Returns ``(pairs, same)``: ``(k, 2)`` adjacent face indices and whether the two faces
    traverse their shared edge in the same direction (inconsistent winding).
    """
    nf = len(faces)
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    owner = np.repeat(np.arange(nf), 3)
    undirected = np.sort(directed, axis=1)
    inverse, counts, _ = _group_rows(undirected)
    keep = counts[inverse] == 2
    order = np.argsort(inverse[keep], kind="stable")
    rows = np.flatnonzero(keep)[order].reshape(-1, 2)
    pairs = owner[rows]
    same = np.all(directed[rows[:, 0]] == directed[rows[:, 1]], axis=1)
    return pairs, same


def _components(nf: int, pairs: np.ndarray):
    graph = sparse.coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(nf, nf)
    ).tocsr()
    count, labels = csgraph.connected_components(graph, directed=False)
    return count, labels


def _orient_consistently(faces: np.ndarray):
    """Flip faces so that adjacent faces traverse shared edges in opposite directions.

    Works per connected component (over manifold edges), keeping each component's
    first face as it is. Returns ``(faces, flipped_mask, orientable)``.
    """
    nf = len(faces)
    pairs, same = _face_graph(faces)
    if not same.any():
        return faces, np.zeros(nf, dtype=bool), True
    # one breadth-first spanning forest: a virtual node nf links the first face of every
    # component; a face must be flipped iff the number of "same direction" edges on its
    # tree path to the root is odd (accumulated by pointer jumping, vectorised)
    count, labels = _components(nf, pairs)
    _, roots = np.unique(labels, return_index=True)
    virtual = np.full(count, nf)
    graph = sparse.coo_matrix(
        (
            np.ones(2 * len(pairs) + 2 * count),
            (
                np.concatenate([pairs[:, 0], pairs[:, 1], roots, virtual]),
                np.concatenate([pairs[:, 1], pairs[:, 0], virtual, roots]),
            ),
        ),
        shape=(nf + 1, nf + 1),
    ).tocsr()
    _, pred = csgraph.breadth_first_order(graph, nf, directed=False)
    ptr = np.append(pred[:nf], nf).astype(np.int64)
    ptr[roots] = nf
    keys = np.minimum(pairs[:, 0], pairs[:, 1]) * (nf + 1) + np.maximum(pairs[:, 0], pairs[:, 1])
    order = np.argsort(keys, kind="stable")
    keys, same_sorted = keys[order], same[order]
    child = np.arange(nf)
    parent = ptr[:nf]
    tree_keys = np.minimum(child, parent) * (nf + 1) + np.maximum(child, parent)
    at = np.clip(np.searchsorted(keys, tree_keys), 0, len(keys) - 1)
    acc = np.append(np.where(parent == nf, False, same_sorted[at]), False)
    while np.any(ptr[:nf] != nf):
        acc, ptr = acc ^ acc[ptr], ptr[ptr]
    flip = acc[:nf]
    fixed = faces.copy()
    fixed[flip] = fixed[flip][:, ::-1]
    _, still_same = _face_graph(fixed)
    return fixed, flip, not still_same.any()


def _signed_volumes(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray, count: int):
    """Signed volume enclosed by the faces of each component label."""
    centre = vertices.mean(axis=0)
    tri = vertices[faces] - centre
    six_v = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    return np.bincount(labels, weights=six_v, minlength=count) / 6.0


def winding_numbers(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Generalised winding number of points with respect to a triangle surface.

    The sum of the triangles' signed solid angles / 4π (Van Oosterom–Strackee). For a
    valid solid it is 1 inside, 0 outside and ~0.5 on the surface; it adds up over
    shells (cavities cancel) and, unlike ray parity, is not confused by coincident
    faces of bodies that touch. ``inside = winding_numbers(p, mesh.triangles) > 0.5``.
    Exact but brute force: ``O(n m)`` time (about 0.1 µs per point-triangle pair).

    Args:
        points: ``(n, 3)`` query points.
        triangles: ``(m, 3, 3)`` triangle corners (e.g. ``mesh.triangles``).

    Returns:
        ``(n,)`` float64 winding numbers.
    """
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


def _inside_shell(
    vertices: np.ndarray, faces: np.ndarray, inner: np.ndarray, outer: np.ndarray
) -> bool:
    """Whether the closed shell ``faces[inner]`` lies inside the shell ``faces[outer]``.

    Tests the centroids of up to eight of the inner shell's largest faces and decides by
    the one whose winding number is least ambiguous (shells may touch)."""
    tri = vertices[faces[inner]]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    best = np.argsort(-area, kind="stable")[:8]
    points = tri[best].mean(axis=1)
    winding = np.abs(winding_numbers(points, vertices[faces[outer]]))
    pick = np.argmax(np.abs(winding - 0.5))
    return bool(winding[pick] > 0.5)


def _nesting_depths(vertices, faces, labels, count, volumes, which):
    """Number of other shells containing each shell in ``which`` (others: all shells)."""
    lo = np.full((count, 3), np.inf)
    hi = np.full((count, 3), -np.inf)
    corners = vertices[faces].reshape(-1, 3)
    face_labels = np.repeat(labels, 3)
    for axis in range(3):
        np.minimum.at(lo[:, axis], face_labels, corners[:, axis])
        np.maximum.at(hi[:, axis], face_labels, corners[:, axis])
    members = _members(labels, count)
    size = np.abs(volumes)
    depth = {}
    for i in which:
        candidates = np.flatnonzero(
            (size > size[i]) & np.all(lo <= lo[i], axis=1) & np.all(hi >= hi[i], axis=1)
        )
        depth[i] = sum(
            _inside_shell(vertices, faces, members[i], members[j]) for j in candidates
        )
    return depth


def _members(labels: np.ndarray, count: int) -> list[np.ndarray]:
    """Face indices of each label, ``O(n log n)``."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(count + 1))
    return [order[bounds[k]:bounds[k + 1]] for k in range(count)]


# -------------------------------------------------------------------- cleaning


def _arrays(mesh, label: str):
    """Float64 vertices and int64 faces of a mesh-like object, shape-checked."""
    if isinstance(mesh, trimesh.Scene):
        raise InvalidMeshError(
            f"{label}: got a trimesh.Scene; pass one Trimesh (e.g. scene.to_mesh())"
        )
    if not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise InvalidMeshError(
            f"{label}: expected a trimesh.Trimesh, got {type(mesh).__name__}"
        )
    try:
        vertices = np.array(mesh.vertices, dtype=np.float64)
        faces = np.array(mesh.faces, dtype=np.int64)
    except (TypeError, ValueError) as exc:
        raise InvalidMeshError(f"{label}: vertices/faces are not numeric arrays ({exc})") from exc
    if faces.size == 0 or vertices.size == 0:
        raise InvalidMeshError(f"{label}: empty mesh (no triangles)")
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise InvalidMeshError(f"{label}: vertices must be (n, 3), got {vertices.shape}")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidMeshError(f"{label}: faces must be (m, 3) triangles, got {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise InvalidMeshError(
            f"{label}: face indices out of range [0, {len(vertices)}) "
            f"(min {faces.min()}, max {faces.max()})"
        )
    return vertices, faces


def _compact(vertices: np.ndarray, faces: np.ndarray):
    """Drop unreferenced vertices (keeping order)."""
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[faces]


def _merge_vertices(vertices: np.ndarray, faces: np.ndarray, distance: float):
    """Merge vertices closer than ``distance`` (clusters, transitively), keeping the first
    vertex of each cluster. Returns ``(vertices, faces, merged_count)``."""
    tree = cKDTree(vertices)
    pairs = tree.query_pairs(distance, output_type="ndarray")
    if len(pairs) == 0:
        return vertices, faces, 0
    n = len(vertices)
    graph = sparse.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, labels = csgraph.connected_components(graph, directed=False)
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    # renumber clusters in order of their first vertex so output order is stable
    order = np.argsort(first, kind="stable")
    rank = np.zeros_like(order)
    rank[order] = np.arange(len(order))
    return vertices[first[order]], rank[inverse.reshape(-1)][faces], n - len(first)


def _canonical_rotation(faces: np.ndarray) -> np.ndarray:
    """Rotate each face so its smallest index comes first (keeps the winding)."""
    shift = np.argmin(faces, axis=1)
    idx = (shift[:, None] + np.arange(3)[None, :]) % 3
    return np.take_along_axis(faces, idx, axis=1)


def _clean_faces(faces: np.ndarray):
    """Drop collapsed faces (repeated index) and repeated copies of same-wound faces.

    Returns ``(faces, collapsed, duplicates, opposite_mask)`` where ``opposite_mask``
    marks faces that have a coincident face of opposite winding."""
    collapsed = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (
        faces[:, 2] == faces[:, 0]
    )
    faces = faces[~collapsed]
    canonical = _canonical_rotation(faces)
    first = _group_rows(canonical)[2]
    keep = np.zeros(len(faces), dtype=bool)
    keep[first] = True
    duplicates = int(len(faces) - keep.sum())
    faces = faces[np.sort(np.flatnonzero(keep))]
    inverse, counts, _ = _group_rows(np.sort(faces, axis=1))
    opposite = counts[inverse] > 1
    return faces, int(collapsed.sum()), duplicates, opposite


def _self_overlaps(vertices: np.ndarray, faces: np.ndarray, scale: float) -> int:
    """Number of face pairs of one closed shell that face opposite ways in one plane
    and overlap there: the surface covers part of a plane twice, as a fanned non-convex
    polygon does (its signed volume stays right, so nothing else notices).

    Faces of different shells may touch this way (two bodies resting on each other).
    """
    pairs, _ = _face_graph(faces)
    count, labels = _components(len(faces), pairs)
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    length = np.linalg.norm(normals, axis=1)
    ok = 0.5 * length >= tol.degenerate_area_rel * scale**2
    normals = normals / np.where(ok, length, 1.0)[:, None]
    centroids = tri.mean(axis=1) - vertices.mean(axis=0)
    angle = tol.fold_angle
    gap = tol.coplanar_rel * scale
    found: set[tuple[int, int]] = set()
    # anti-parallel normals n, -n lie on opposite sides of any direction g with
    # |n.g| > 0.3; one of three orthogonal directions always has |n.g| >= 0.577
    for g in np.eye(3):
        side = normals @ g
        a = np.flatnonzero(ok & (side > 0.3))
        b = np.flatnonzero(ok & (side < -0.3))
        if len(a) == 0 or len(b) == 0:
            continue
        sign = np.sign(side)[:, None]
        # features: sign-normalised normal, plane offset, shell label (far apart)
        offset = (sign[:, 0] * np.einsum("ij,ij->i", normals, centroids)) / gap * angle
        features = np.column_stack([normals * sign, offset, labels * 10.0])
        ta, tb = cKDTree(features[a]), cKDTree(features[b])
        close = ta.sparse_distance_matrix(tb, 4 * angle, output_type="ndarray")
        for i, j in zip(a[close["i"]], b[close["j"]], strict=True):
            found.add((int(min(i, j)), int(max(i, j))))
    if not found:
        return 0
    cand = np.asarray(sorted(found), dtype=np.int64)
    i, j = cand[:, 0], cand[:, 1]
    coplanar = (
        (np.einsum("ij,ij->i", normals[i], normals[j]) < -np.cos(angle))
        & (np.abs(np.einsum("ij,ij->i", normals[i], centroids[j] - centroids[i])) <= gap)
        & (labels[i] == labels[j])
    )
    i, j = i[coplanar], j[coplanar]
    if len(i) == 0:
        return 0
    # 2D separating-axis test in the plane of face i; touching is not overlapping
    u = tri[i, 1] - tri[i, 0]
    u /= np.linalg.norm(u, axis=1)[:, None]
    v = np.cross(normals[i], u)
    pi = np.stack([np.einsum("kcj,kj->kc", tri[i], u), np.einsum("kcj,kj->kc", tri[i], v)], -1)
    pj = np.stack([np.einsum("kcj,kj->kc", tri[j], u), np.einsum("kcj,kj->kc", tri[j], v)], -1)
    margin = 1e-7 * scale
    separated = np.zeros(len(i), dtype=bool)
    for poly in (pi, pj):
        for e in range(3):
            edge = poly[:, (e + 1) % 3] - poly[:, e]
            axis = np.stack([-edge[:, 1], edge[:, 0]], -1)
            axis /= np.maximum(np.linalg.norm(axis, axis=1), 1e-300)[:, None]
            si = np.einsum("kcj,kj->kc", pi, axis)
            sj = np.einsum("kcj,kj->kc", pj, axis)
            overlap = np.minimum(si.max(1), sj.max(1)) - np.maximum(si.min(1), sj.min(1))
            separated |= overlap <= margin
    return int((~separated).sum())


def _face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def _closed_candidate(faces, degenerate, opposite):
    """Pick the least invasive removal of degenerate / back-to-back faces that leaves a
    closed manifold surface. Returns ``(faces, removed_degenerate, removed_opposite,
    stats)``; ``stats`` are the edge stats of the returned faces."""
    options = [
        (degenerate | opposite, int(degenerate.sum()), int(opposite.sum())),
        (degenerate, int(degenerate.sum()), 0),
        (opposite, 0, int(opposite.sum())),
        (np.zeros(len(faces), dtype=bool), 0, 0),
    ]
    best = None
    for drop, n_deg, n_opp in options:
        if (n_deg or n_opp) and drop.all():
            continue
        candidate = faces[~drop]
        stats = _shell_edge_stats(candidate)[:2]
        if stats[0] == 0 and stats[1] == 0:
            return candidate, n_deg, n_opp, stats
        score = stats[0] + stats[1]
        if best is None or score < best[0]:
            best = (score, candidate, n_deg, n_opp, stats)
    _, candidate, n_deg, n_opp, stats = best
    return candidate, n_deg, n_opp, stats


def _orient_shells(vertices, faces, label, scale, report):
    """Make winding consistent and orient every closed shell (outward bodies, inward
    cavities). Updates ``report`` and returns the faces. Raises for non-orientable or
    flat shells."""
    faces, flipped, orientable = _orient_consistently(faces)
    report["fixed_winding_faces"] = report.get("fixed_winding_faces", 0) + int(flipped.sum())
    if not orientable:
        raise InvalidMeshError(
            f"{label}: surface is not orientable (inconsistent winding that cannot be "
            f"fixed, e.g. a Moebius-like strip); fix the model"
        )
    pairs, _ = _face_graph(faces)
    count, labels = _components(len(faces), pairs)
    # a shell whose winding had to be fixed has no trustworthy orientation: it gets the
    # one its nesting depth implies
    unknown = {int(k) for k in np.unique(labels[flipped])}
    volumes = _signed_volumes(vertices, faces, labels, count)
    flat = np.abs(volumes) <= tol.zero_volume_rel * scale**3
    if flat.any():
        where = "" if count == 1 else f" (closed shell {int(np.argmax(flat))} of {count})"
        raise InvalidMeshError(
            f"{label}: zero volume{where}: the surface is flat or folds onto itself; "
            f"a solid needs an interior"
        )
    # Orientation rule, by nesting depth (number of shells around a shell): outward
    # shells at even depth are bodies, inward ones at odd depth are cavities. An inward
    # shell at even depth is a body exported inside out: flip it. An outward shell at
    # odd depth is a body inside another one (kept: the solid is their union), unless
    # every shell contradicts the rule, which means the whole mesh is inside out.
    flip_shell = np.zeros(count, dtype=bool)
    negative = volumes < 0
    if count == 1:
        flip_shell[0] = negative[0]
    elif negative.any() or unknown:
        depth = _nesting_depths(vertices, faces, labels, count, volumes, range(count))
        odd = np.array([depth[k] % 2 == 1 for k in range(count)])
        known = np.array([k not in unknown for k in range(count)])
        contradicts = negative != odd
        if (contradicts | ~known).all() and (negative & ~odd & known).any():
            flip_shell = known.copy()
        else:
            flip_shell = known & negative & ~odd
        flip_shell |= ~known & (negative != odd)
    if flip_shell.any():
        mask = flip_shell[labels]
        faces = faces.copy()
        faces[mask] = faces[mask][:, ::-1]
        log.info(
            "%s: %d of %d closed shell(s) were inside out; flipped them",
            label, int(flip_shell.sum()), count,
        )
    report["flipped_shells"] = int(flip_shell.sum())
    report["shells"] = int(count)
    report["cavities"] = int(
        (np.where(flip_shell, -volumes, volumes) < 0).sum()
    )
    return faces


def validate_solid(mesh, *, name: str = "mesh") -> trimesh.Trimesh:
    """Check that a mesh bounds a solid and return a cleaned copy.

    Cleaning, all harmless for a valid solid: float64 vertices; unreferenced vertices
    dropped; vertices closer than ``tol.merge_rel * scale`` merged; collapsed and
    repeated faces dropped; zero-area faces and back-to-back coincident face pairs
    dropped when the surface stays closed without them; winding made consistent;
    shells that are inside out (negative volume, not nested in another shell) flipped,
    with a log message. The input is never modified.

    Args:
        mesh: a ``trimesh.Trimesh`` (anything with ``vertices`` and ``faces``).
        name: label for error messages, stored in ``metadata["name"]`` of the result.

    Returns:
        A new ``trimesh.Trimesh`` that is watertight, consistently wound, with outward
        normals (cavity shells, if any, wound inward) and positive volume.

    Raises:
        InvalidMeshError: empty mesh; NaN/inf coordinates; open or non-manifold surface
            (the message counts boundary and non-manifold edges); non-orientable
            surface; zero volume.
    """
    label = f"mesh {name!r}"
    vertices, faces = _arrays(mesh, label)
    bad = ~np.all(np.isfinite(vertices), axis=1)
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    if (bad & used).any():
        first = int(np.flatnonzero(bad & used)[0])
        raise InvalidMeshError(
            f"{label}: {int((bad & used).sum())} vertices have NaN or infinite coordinates "
            f"(first: vertex {first}); fix the exporter or remove them"
        )
    vertices, faces = _compact(vertices, faces)
    cleaned, report = _clean(vertices, faces, label)
    vertices, faces = cleaned
    boundary, nonmanifold = report["edge_stats"]
    if boundary or nonmanifold:
        hint = ""
        if report["degenerate_faces"]:
            hint += f"; {report['degenerate_faces']} zero-area triangles"
        if report["back_to_back_faces"]:
            hint += (
                f"; {report['back_to_back_faces']} faces come in back-to-back pairs "
                f"(a double-sided surface?)"
            )
        raise InvalidMeshError(
            f"{label}: not watertight ({boundary} boundary edges, {nonmanifold} non-manifold "
            f"edges{hint}); close the holes in the model or try "
            f"planner.meshes.repair_mesh"
        )
    faces = _orient_shells(vertices, faces, label, report["scale"], report)
    overlaps = _self_overlaps(vertices, faces, report["scale"])
    if overlaps:
        raise InvalidMeshError(
            f"{label}: surface overlaps itself ({overlaps} pairs of coplanar faces facing "
            f"opposite ways overlap); typically polygons triangulated wrongly by the "
            f"exporter or loader (for OBJ n-gons use planner.meshes.load_obj)"
        )
    _check_winding(vertices, faces, label)
    result = trimesh.Trimesh(vertices, faces, process=False)
    result.metadata.update(getattr(mesh, "metadata", {}) or {})
    result.metadata["name"] = name
    if report["merged_vertices"] or report["removed_faces"]:
        log.debug(
            "%s: merged %d vertices, removed %d faces",
            label, report["merged_vertices"], report["removed_faces"],
        )
    return result


def _check_winding(vertices: np.ndarray, faces: np.ndarray, label: str) -> None:
    """Raise unless the closed, consistently wound surface bounds a solid: its exact
    winding number (the core's) is never negative, so no face has the inside in front of
    it (see :mod:`planner.meshes` conventions)."""
    from ._minkowski_core import front_windings  # noqa: PLC0415 (the native module)

    fronts = front_windings(vertices, faces)
    inverted = int((fronts < 0).sum() - (fronts == np.iinfo(np.int64).min).sum())
    unknown = int((fronts == np.iinfo(np.int64).min).sum())
    if inverted or unknown:
        detail = []
        if inverted:
            detail.append(f"{inverted} of {len(faces)} faces have the inside in front of them "
                          f"(winding number {int(fronts[fronts > np.iinfo(np.int64).min].min())} "
                          f"there: inverted faces, or shells glued inside out)")
        if unknown:
            detail.append(f"{unknown} faces lie on other faces")
        raise InvalidMeshError(
            f"{label}: closed but not a solid: {'; '.join(detail)}; it can only be used as a "
            f"surface (triangles, as FCL sees them)"
        )


def _clean(vertices, faces, label):
    """Shared cleaning of validate_solid and repair_mesh (no hole filling)."""
    scale = scale_of(vertices)
    if scale == 0:
        raise InvalidMeshError(f"{label}: zero volume: all vertices coincide")
    vertices, faces, merged = _merge_vertices(vertices, faces, tol.merge_rel * scale)
    faces, collapsed, duplicates, opposite = _clean_faces(faces)
    if len(faces) == 0:
        raise InvalidMeshError(f"{label}: zero volume: every triangle is degenerate")
    degenerate = _face_areas(vertices, faces) < tol.degenerate_area_rel * scale**2
    faces, n_deg, n_opp, stats = _closed_candidate(faces, degenerate, opposite)
    vertices, faces = _compact(vertices, faces)
    touching = 0
    if stats == (0, 0) and _edge_stats(faces)[1]:
        # closed shells touching along edges: separate them
        touching = _edge_stats(faces)[1]
        vertices, faces = _unshare_vertices(vertices, faces, _shell_edge_stats(faces)[2])
    report = {
        "scale": scale,
        "merged_vertices": int(merged),
        "removed_collapsed_faces": collapsed,
        "removed_duplicate_faces": duplicates,
        "removed_degenerate_faces": n_deg,
        "removed_back_to_back_faces": n_opp,
        "removed_faces": collapsed + duplicates + n_deg + n_opp,
        "degenerate_faces": int(degenerate.sum()) - n_deg,
        "back_to_back_faces": int(opposite.sum()) - n_opp,
        "separated_touching_edges": int(touching),
        "edge_stats": stats,
    }
    return (vertices, faces), report


# --------------------------------------------------------------------- repair


def _boundary_loops(faces: np.ndarray):
    """Closed loops of boundary edges, each a list of vertex indices in the direction
    the existing faces traverse them. Loops through a vertex with several boundary
    edges are returned separately in ``tangled`` (count of skipped edges)."""
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    undirected = np.sort(directed, axis=1)
    inverse, counts, _ = _group_rows(undirected)
    boundary = directed[counts[inverse] == 1]
    nxt: dict[int, int] = {}
    tangled = set()
    for a, b in boundary:
        if a in nxt:
            tangled.add(int(a))
        nxt[int(a)] = int(b)
    loops = []
    visited = set()
    for start in sorted(nxt):
        if start in visited or start in tangled:
            continue
        loop = [start]
        visited.add(start)
        current = nxt[start]
        while current != start:
            if current in visited or current in tangled or current not in nxt:
                loop = None
                break
            loop.append(current)
            visited.add(current)
            current = nxt[current]
        if loop is not None and len(loop) >= 3:
            loops.append(loop)
    return loops, len(boundary)


def repair_mesh(mesh, *, name: str = "mesh"):
    """Best-effort repair of a messy mesh into a solid, with a report of what was done.

    Steps: drop faces that use NaN/inf vertices; merge vertices closer than
    ``tol.merge_rel * scale`` (ignoring texture and normal seams); drop collapsed and
    repeated faces, and zero-area / back-to-back faces where that closes the surface;
    if the surface is double-sided (every face also present with the opposite winding,
    as in meshes made for rendering), keep one copy of each such pair; make winding
    consistent; fill each simple hole (a closed loop of boundary edges) by
    triangulating it in its best-fit plane; orient shells outward. The result must pass
    :func:`validate_solid`. It cannot undo a wrong triangulation of the source (e.g. a
    fanned non-convex OBJ polygon; read such files with :func:`load_obj`), resolve
    self-intersections, or fix non-manifold edges.

    Args:
        mesh: a ``trimesh.Trimesh``.
        name: label for messages.

    Returns:
        ``(mesh, report)``: the repaired ``trimesh.Trimesh`` and a ``dict`` with counts
        (``merged_vertices``, ``removed_nonfinite_faces``, ``removed_collapsed_faces``,
        ``removed_duplicate_faces``, ``removed_degenerate_faces``,
        ``removed_back_to_back_faces``, ``single_sided_faces``, ``fixed_winding_faces``,
        ``filled_holes``, ``added_faces``, ``flipped_shells``, ``shells``) and the
        final ``volume``.

    Raises:
        InvalidMeshError: the result is still not a watertight, orientable solid
            (the message says what is left).
    """
    label = f"mesh {name!r}"
    vertices, faces = _arrays(mesh, label)
    finite = np.all(np.isfinite(vertices), axis=1)
    good_faces = finite[faces].all(axis=1)
    report: dict = {"input_vertices": len(vertices), "input_faces": len(faces)}
    report["removed_nonfinite_faces"] = int((~good_faces).sum())
    faces = faces[good_faces]
    if len(faces) == 0:
        raise InvalidMeshError(f"{label}: nothing to repair: no faces with finite vertices")
    vertices, faces = _compact(vertices, faces)
    scale = scale_of(vertices)
    vertices, faces, merged = _merge_vertices(vertices, faces, tol.merge_rel * scale)

    attempts = [False]
    _, _, _, opposite = _clean_faces(faces)
    if opposite.any():
        attempts.append(True)  # fall back to reading a double-sided surface one-sided
    best = None
    for single_sided in attempts:
        result = _repair_attempt(vertices, faces, label, single_sided)
        if best is None or result[3] < best[3]:
            best = result
        if result[3] == 0:
            break
    vertices, faces, attempt, bad, shells = best
    report.update(attempt)
    if bad:
        raise InvalidMeshError(
            f"{label}: could not repair: {attempt['edge_stats'][0]} boundary edges and "
            f"{attempt['edge_stats'][1]} non-manifold edges remain after filling "
            f"{attempt['filled_holes']} holes; fix the model (if it is an OBJ with "
            f"n-gons, read it with planner.meshes.load_obj)"
        )
    vertices, faces = _unshare_vertices(vertices, faces, shells)
    faces = _orient_shells(vertices, faces, label, scale, report)
    repaired = validate_solid(trimesh.Trimesh(vertices, faces, process=False), name=name)
    report["volume"] = float(repaired.volume)
    report["merged_vertices"] = int(merged) + attempt["merged_vertices"]
    for key in ("degenerate_faces", "back_to_back_faces", "cavities", "edge_stats", "scale"):
        report.pop(key, None)
    log.info("%s: repaired: %s", label, report)
    return repaired, report


def _repair_attempt(vertices, faces, label, single_sided: bool):
    """One repair pass; returns ``(vertices, faces, report, bad_edges, shell_labels)``."""
    kept = 0
    if single_sided:
        faces, _, _, opposite = _clean_faces(faces)
        first = _group_rows(np.sort(faces, axis=1))[2]
        keep = np.zeros(len(faces), dtype=bool)
        keep[first] = True
        kept = int((opposite & ~keep).sum())
        faces = faces[keep]
    (vertices, faces), report = _clean(vertices, faces, label)
    report["single_sided_faces"] = kept
    faces, flipped, _ = _orient_consistently(faces)
    report["fixed_winding_faces"] = int(flipped.sum())
    loops, _ = _boundary_loops(faces)
    added = []
    for loop in loops:
        hole = loop[::-1]  # the fill traverses the boundary edges the other way
        local, _ = _ear_clip(vertices[hole])
        added.append(np.asarray(hole, dtype=np.int64)[local])
    report["filled_holes"] = len(added)
    report["added_faces"] = int(sum(len(a) for a in added))
    if added:
        faces = np.concatenate([faces, *added])
    boundary, nonmanifold, shells = _shell_edge_stats(faces)
    report["edge_stats"] = (boundary, nonmanifold)
    return vertices, faces, report, boundary + nonmanifold, shells


# ------------------------------------------------------------------ geometry ops


def mirror(mesh) -> trimesh.Trimesh:
    """Point reflection ``-M`` of a mesh: negated vertices, faces reversed so that the
    normals stay outward (a reflection flips orientation). Used for C-obstacles
    ``O ⊕ (-R)``. Returns a new mesh; ``metadata["name"]`` becomes ``"-<name>"``."""
    vertices = -np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)[:, ::-1].copy()
    result = trimesh.Trimesh(vertices, faces, process=False)
    name = (getattr(mesh, "metadata", None) or {}).get("name")
    if name is not None:
        result.metadata["name"] = f"-{name}"
    return result


def split_solid(mesh) -> list[trimesh.Trimesh]:
    """Split a valid solid (see :func:`validate_solid`) into bodies.

    A body is an outward closed shell together with the inward (cavity) shells directly
    inside it. Bodies are returned in order of their first face.

    Args:
        mesh: a mesh returned by :func:`validate_solid`.

    Returns:
        List of ``trimesh.Trimesh`` bodies, each closed with positive volume.
    """
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    pairs, _ = _face_graph(faces)
    count, labels = _components(len(faces), pairs)
    # renumber components by first face so the order is deterministic
    _, first = np.unique(labels, return_index=True)
    rank = np.zeros(count, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(count)
    labels = rank[labels]
    volumes = _signed_volumes(vertices, faces, labels, count)
    members = _members(labels, count)
    owner = np.arange(count)
    cavities = np.flatnonzero(volumes <= 0)
    if len(cavities):
        lo = np.stack([vertices[faces[m]].reshape(-1, 3).min(axis=0) for m in members])
        hi = np.stack([vertices[faces[m]].reshape(-1, 3).max(axis=0) for m in members])
        for k in cavities:
            # the smallest outward shell around the cavity owns it
            candidates = np.flatnonzero(
                (volumes > -volumes[k])
                & np.all(lo <= lo[k], axis=1)
                & np.all(hi >= hi[k], axis=1)
            )
            for j in candidates[np.argsort(volumes[candidates], kind="stable")]:
                if _inside_shell(vertices, faces, members[k], members[j]):
                    owner[k] = j
                    break
    by_body = _members(owner[labels], count)
    bodies = []
    for j in np.flatnonzero(volumes > 0):
        v, f = _compact(vertices, faces[np.sort(by_body[j])])
        bodies.append(trimesh.Trimesh(v, f, process=False))
    return bodies
