"""Solid or surface: what a part is, decided once per mesh, with the reason and what was
changed to make it so.

A *solid* is a closed mesh whose winding number is never negative
(:func:`~planner.meshes.validate_solid`); containment counts (a part inside it collides).
A *surface* is any set of triangles, as FCL and OMPL.app see every mesh: it collides only
where triangles meet. ``kind`` chooses:

- ``"auto"`` (the default): a solid when the mesh is one, or becomes one without moving
  its geometry -- vertices closer than the tolerance welded, degenerate and repeated faces
  dropped, winding made consistent, inverted shells flipped (all in ``validate_solid``),
  and T-junctions split (a vertex lying on another face's edge: the edge is split there,
  :func:`split_t_junctions`); else a surface. What dropped degenerate faces, turned faces,
  flipped shells or split edges is in :attr:`Classified.changes`.
- ``"solid"``: a solid or an error (with ``repair``: :func:`~planner.meshes.repair_mesh`
  may also fill holes, which adds geometry, and says so).
- ``"surface"``: the triangles as they are.

Entry point: :func:`classify`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from planner.errors import InvalidMeshError
from planner.tolerances import scale_of, tol

from .repair import repair_mesh
from .solids import SOLID_CHANGES, SOLID_REASON, not_solid_reason, validate_solid
from .topology import checked_arrays, group_rows

__all__ = ["KINDS", "Classified", "classify", "split_t_junctions"]

KINDS = ("auto", "solid", "surface")
"""The kinds a part may be asked to be."""


@dataclass(frozen=True)
class Classified:
    """A mesh as the part it is.

    Attributes:
        mesh: the mesh to use (a checked solid, or the surface's triangles).
        solid: whether it is a solid.
        reason: why (for reports).
        changes: what was changed to make it a solid (``{"t_junctions_split": 36}``,
            repair counts), empty when nothing was.
    """

    mesh: trimesh.Trimesh
    solid: bool
    reason: str
    changes: dict[str, Any] = field(default_factory=dict)


def classify(mesh: trimesh.Trimesh, *, name: str, kind: str = "auto",
             repair: bool = False) -> Classified:
    """The part ``mesh`` is (see the module documentation).

    Raises:
        InvalidMeshError: ``kind="solid"`` and the mesh is no solid (even repaired, with
            ``repair``); a mesh without triangles or with non-finite coordinates, whatever
            the kind; an unknown kind.
    """
    if kind not in KINDS:
        raise InvalidMeshError(f"mesh {name!r}: kind {kind!r}: use one of {', '.join(KINDS)}")
    if kind == "surface":
        return Classified(_surface(mesh, name), False, "kind surface asked for")
    try:
        solid = validate_solid(mesh, name=name)
        return Classified(solid, True, SOLID_REASON, dict(solid.metadata.get(SOLID_CHANGES, {})))
    except InvalidMeshError as error:
        first = error
    split = _with_t_junctions_split(mesh, name)
    if split is not None:
        return split
    if repair:
        try:
            repaired, report = repair_mesh(mesh, name=name)
        except InvalidMeshError as error:
            first = error  # repair did not close it: a surface (auto) or the error
        else:
            done = {k: v for k, v in report.items()
                    if k.startswith(("removed_", "merged_", "fixed_", "filled_", "flipped_"))
                    and k != "removed_faces" and v}
            return Classified(repaired, True, "repaired (repair: true)", done)
    if kind == "solid":
        raise first
    return Classified(_surface(mesh, name), False, not_solid_reason(first))


def _surface(mesh: trimesh.Trimesh, name: str) -> trimesh.Trimesh:
    """The triangles as they are (finite, indices in range), unreferenced vertices kept."""
    vertices, faces = checked_arrays(mesh, f"mesh {name!r}")
    if not np.all(np.isfinite(vertices[faces])):
        raise InvalidMeshError(f"mesh {name!r}: a face has NaN or infinite coordinates; fix "
                               f"the exporter or remove it")
    surface = trimesh.Trimesh(vertices, faces, process=False)
    surface.metadata.update(getattr(mesh, "metadata", {}) or {})
    surface.metadata["name"] = name
    return surface


def _with_t_junctions_split(mesh: trimesh.Trimesh, name: str) -> Classified | None:
    """The mesh as a solid once its T-junctions are split, or ``None``."""
    vertices, faces = checked_arrays(mesh, f"mesh {name!r}")
    if not np.all(np.isfinite(vertices)):
        return None
    scale = scale_of(vertices)
    merged = trimesh.Trimesh(vertices, faces, process=False)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    split, count = split_t_junctions(np.asarray(merged.vertices, dtype=np.float64),
                                     np.asarray(merged.faces, dtype=np.int64),
                                     tol.touch_rel * scale)
    if count == 0:
        return None
    try:
        solid = validate_solid(trimesh.Trimesh(merged.vertices, split, process=False),
                               name=name)
    except InvalidMeshError:
        return None
    return Classified(solid, True, f"closed once {count} T-junctions were split",
                      {"t_junctions_split": count, **solid.metadata.get(SOLID_CHANGES, {})})


def split_t_junctions(vertices: np.ndarray, faces: np.ndarray, tolerance: float,
                      *, passes: int = 8) -> tuple[np.ndarray, int]:
    """Split every boundary edge (used by one face) at the vertices lying on it (within
    ``tolerance``, strictly between its ends): the face becomes a fan of triangles from
    its third corner, wound like it. No vertex moves. Returns the faces ``(m', 3)`` and
    how many vertices were inserted into edges.

    Args:
        vertices: ``(n, 3)`` float64.
        faces: ``(m, 3)`` int64.
        tolerance: largest distance of a vertex from an edge it lies on.
        passes: rounds at most (a face with T-junctions on two edges needs two).
    """
    tree = cKDTree(vertices)
    total = 0
    for _ in range(passes):
        faces, count = _split_pass(vertices, faces, tree, tolerance)
        total += count
        if count == 0:
            break
    return faces, total


def _split_pass(vertices: np.ndarray, faces: np.ndarray, tree: cKDTree,
                tolerance: float) -> tuple[np.ndarray, int]:
    """One round of :func:`split_t_junctions`: at most one edge per face."""
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    inverse, counts, _ = group_rows(np.sort(directed, axis=1))
    boundary = np.flatnonzero(counts[inverse] == 1)
    keep = np.ones(len(faces), dtype=bool)
    added: list[list[int]] = []
    inserted = 0
    for row in boundary:
        f, k = divmod(int(row), 3)
        if not keep[f]:
            continue  # this face was split already in this pass
        a, b, c = faces[f, k], faces[f, (k + 1) % 3], faces[f, (k + 2) % 3]
        on_edge = _vertices_on(vertices, tree, a, b, tolerance)
        if not on_edge:
            continue
        keep[f] = False
        chain = [int(a), *on_edge, int(b)]
        added.extend([p, q, int(c)] for p, q in zip(chain[:-1], chain[1:], strict=True))
        inserted += len(on_edge)
    if not inserted:
        return faces, 0
    return np.concatenate([faces[keep], np.asarray(added, dtype=np.int64)]), inserted


def _vertices_on(vertices: np.ndarray, tree: cKDTree, a: int, b: int,
                 tolerance: float) -> list[int]:
    """Vertices strictly inside the segment ``a b`` (within ``tolerance``), in order."""
    pa, pb = vertices[a], vertices[b]
    d = pb - pa
    length = float(np.linalg.norm(d))
    if length <= tolerance:
        return []
    near = tree.query_ball_point((pa + pb) / 2, length / 2 + tolerance)
    found = []
    for v in near:
        if v in (a, b):
            continue
        t = float(np.dot(vertices[v] - pa, d)) / length**2
        if not (0.0 < t < 1.0):
            continue
        if np.linalg.norm(pa + t * d - vertices[v]) <= tolerance:
            found.append((t, int(v)))
    return [v for t, v in sorted(found) if tolerance < t * length < length - tolerance]
