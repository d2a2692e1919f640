"""The meshes of an OMPL.app problem as OMPL.app sees them: COLLADA files read in its
frame, the robot's reference point, and the world split into solids and surfaces.

Frames (checked against OMPL.app's reference solutions in ``tests/test_omplapp.py``):

- OMPL.app reads meshes through assimp, which turns a ``Z_UP`` COLLADA file into its
  Y-up frame: a file point ``(x, y, z)`` is at ``(x, z, -y)`` in the app frame
  (:data:`APP_FROM_ZUP`). Every number in the ``.cfg`` is in the app frame.
- The robot's reference point is the mean of all its vertices (assimp's vertex
  arrays: node transforms applied, nothing merged), in the app frame.

Meshes: the SketchUp exports OMPL.app ships have every triangle twice, once per side,
so none is a closed manifold as loaded. :func:`single_sided` keeps one triangle of each
such pair; :func:`world_parts` splits the world into connected pieces and checks each
with :func:`planner.meshes.validate_solid`. A shell whose only defects are pairs of
facing openings with the walls between them missing (a hole through a slab, modelled as
a hole in its top and one in its bottom face) gets those walls added and is a solid; any
other piece that is not a solid (open, flat, or closed with inverted faces, as Easy's
frame) is a *surface*: its triangles as imported, colliding where triangles meet, as
OMPL.app and FCL see every mesh.

Entry points: :func:`read_app_mesh`, :func:`robot_reference_point`, :func:`single_sided`,
:func:`world_parts`.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import trimesh

from planner.errors import InvalidMeshError
from planner.meshes import SOLID_REASON, load_mesh, not_solid_reason, validate_solid
from planner.meshes.topology import boundary_loops, group_rows
from planner.tolerances import scale_of, tol

__all__ = ["APP_FROM_ZUP", "read_app_mesh", "robot_reference_point",
           "single_sided", "world_parts"]


APP_FROM_ZUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""Rotation from a Z-up COLLADA file's frame to OMPL.app's (assimp's Y-up) frame:
``app = APP_FROM_ZUP @ file``, i.e. ``(x, y, z) -> (x, z, -y)``."""


def _up_axis(path: Path) -> str:
    """The ``<up_axis>`` of a COLLADA file (``Y_UP`` when absent, as the spec says)."""
    head = path.read_bytes()[:65536].decode("utf-8", errors="replace")
    asset = head.split("</asset>", 1)[0]
    match = re.search(r"<up_axis>\s*([XYZ]_UP)\s*</up_axis>", asset)
    unit = re.search(r"<unit\b[^>]*\bmeter\s*=\s*\"([^\"]+)\"", asset)
    if unit is not None and not math.isclose(float(unit.group(1)), 1.0):
        raise InvalidMeshError(
            f"mesh file '{path}': COLLADA <unit meter=\"{unit.group(1)}\"> is not supported "
            "by the OMPL.app importer (only unscaled files have been checked against "
            "OMPL.app)")
    return match.group(1) if match else "Y_UP"


def read_app_mesh(path: str | os.PathLike[str]) -> trimesh.Trimesh:
    """All triangles of a COLLADA file, in OMPL.app's frame, exactly as loaded.

    Node transforms are applied; vertices are not merged and duplicate faces are kept
    (so the vertex mean is OMPL.app's reference point, see
    :func:`robot_reference_point`). ``Z_UP`` files are turned by :data:`APP_FROM_ZUP`;
    ``Y_UP`` files are used as they are.

    Raises:
        InvalidMeshError: unreadable file, no triangles, ``X_UP`` or a scaled ``<unit>``.
    """
    path = Path(path)
    mesh = load_mesh(path)
    axis = _up_axis(path)
    if axis == "Z_UP":
        mesh.vertices = mesh.vertices @ APP_FROM_ZUP.T
    elif axis != "Y_UP":
        raise InvalidMeshError(f"mesh file '{path}': up axis {axis} is not supported by the "
                               "OMPL.app importer")
    return mesh


def robot_reference_point(mesh: trimesh.Trimesh) -> np.ndarray:
    """OMPL.app's reference point of a robot mesh from :func:`read_app_mesh`: the mean
    of its vertices, ``(3,)``. (assimp's vertex arrays may hold each corner a different
    number of times than trimesh's; on the shipped problems the two means agree to
    ``2e-4``, far below their clearances.)"""
    return np.asarray(mesh.vertices, dtype=np.float64).mean(axis=0)


def single_sided(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int]:
    """Merge coincident vertices and keep one triangle of every group of triangles on
    the same three vertices (double-sided exports). Returns the mesh and how many
    triangles were dropped."""
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    faces = np.asarray(merged.faces, dtype=np.int64)
    first = group_rows(np.sort(faces, axis=1))[2]
    keep = np.sort(first)
    return trimesh.Trimesh(merged.vertices, faces[keep], process=False), len(faces) - len(keep)


def _pieces(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    """Edge-connected pieces, in order of their first face."""
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency,
                                                      node_count=len(mesh.faces))
    _, first = np.unique(labels, return_index=True)
    pieces = []
    for label in labels[np.sort(first)]:
        piece = trimesh.Trimesh(mesh.vertices, mesh.faces[labels == label], process=False)
        piece.remove_unreferenced_vertices()
        pieces.append(piece)
    return pieces


def _thickness(points: np.ndarray) -> float:
    """Smallest extent of a point set over all directions (0 for coplanar points)."""
    centred = points - points.mean(axis=0)
    return float(np.linalg.svd(centred, compute_uv=False)[-1]) if len(points) > 3 else 0.0


def _loop_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid, unit normal and out-of-plane spread of a loop's points."""
    centre = points.mean(axis=0)
    _, singular, vt = np.linalg.svd(points - centre)
    return centre, vt[-1], float(singular[-1])


def _bridge(vertices: np.ndarray, a: list[int], b: list[int], normal: np.ndarray) -> np.ndarray:
    """Triangles joining two facing loops (a band, like the wall of a drilled hole).

    Both loops are put in the same rotational sense about ``normal`` and started at the
    closest pair of vertices; the band then advances along whichever loop gives the
    shorter diagonal. Winding is left to :func:`planner.meshes.validate_solid`.
    """
    def sense(loop: list[int]) -> float:
        p = vertices[loop]
        return float(np.dot(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0), normal))

    if (sense(a) > 0) != (sense(b) > 0):
        b = b[::-1]
    distances = np.linalg.norm(vertices[a][:, None] - vertices[b][None], axis=2)
    i0, j0 = np.unravel_index(np.argmin(distances), distances.shape)
    a = a[i0:] + a[:i0] + [a[i0]]
    b = b[j0:] + b[:j0] + [b[j0]]
    i = j = 0
    triangles = []
    while i < len(a) - 1 or j < len(b) - 1:
        advance_a = j == len(b) - 1 or (
            i < len(a) - 1
            and np.linalg.norm(vertices[a[i + 1]] - vertices[b[j]])
            <= np.linalg.norm(vertices[a[i]] - vertices[b[j + 1]]))
        if advance_a:
            triangles.append((a[i], a[i + 1], b[j]))
            i += 1
        else:
            triangles.append((a[i], b[j + 1], b[j]))
            j += 1
    return np.array(triangles, dtype=np.int64)


def _bridge_openings(piece: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int] | None:
    """Close a piece whose boundary loops come in facing pairs (planar, parallel, their
    outlines overlapping, closer together than their size) by joining each pair with a
    band. Returns ``(mesh, pairs)`` or None when the boundary is not of that kind."""
    vertices = np.asarray(piece.vertices, dtype=np.float64)
    faces = np.asarray(piece.faces, dtype=np.int64)
    loops, tangled = boundary_loops(faces)
    if tangled or not loops or len(loops) % 2:
        return None
    planes = [_loop_plane(vertices[loop]) for loop in loops]
    sizes = [float(np.ptp(vertices[loop], axis=0).max()) for loop in loops]
    if any(spread > tol.planar_rel * size for (_, _, spread), size in zip(planes, sizes)):
        return None  # a loop that is not planar

    def overlap(i: int, j: int) -> float:
        # overlap of the two outlines' boxes in the plane, relative to the smaller one
        normal = planes[i][1]
        basis = np.linalg.svd(np.eye(3) - np.outer(normal, normal))[0][:, :2]
        pi, pj = vertices[loops[i]] @ basis, vertices[loops[j]] @ basis
        lo = np.maximum(pi.min(0), pj.min(0))
        hi = np.minimum(pi.max(0), pj.max(0))
        inter = float(np.prod(np.clip(hi - lo, 0, None)))
        smaller = min(float(np.prod(np.ptp(pi, 0))), float(np.prod(np.ptp(pj, 0))))
        return inter / smaller if smaller > 0 else 0.0

    unpaired = set(range(len(loops)))
    bands = []
    while unpaired:
        i = min(unpaired)
        unpaired.discard(i)
        best, best_score = None, 0.5
        for j in unpaired:
            (ci, ni, _), (cj, nj, _) = planes[i], planes[j]
            gap = abs(float(np.dot(cj - ci, ni)))
            if abs(float(np.dot(ni, nj))) < 1 - 1e-9 or not 0 < gap < min(sizes[i], sizes[j]):
                continue
            score = overlap(i, j)
            if score > best_score:
                best, best_score = j, score
        if best is None:
            return None
        unpaired.discard(best)
        bands.append(_bridge(vertices, loops[i], loops[best], planes[i][1]))
    closed = trimesh.Trimesh(vertices, np.concatenate([faces, *bands]), process=False)
    return closed, len(bands)


def world_parts(raw: trimesh.Trimesh, label: str,
                 notes: list[str]) -> list[tuple[trimesh.Trimesh, bool, str]]:
    """The world mesh as ``(mesh, solid, why)``, one per connected piece (see module doc)."""
    single, dropped = single_sided(raw)
    if dropped:
        notes.append(f"{label}: dropped {dropped} back-side duplicate triangles "
                     "(double-sided export)")
    size = scale_of(single)
    parts = []
    for index, piece in enumerate(_pieces(single)):
        where = f"{label} piece {index} ({len(piece.faces)} triangles, box "\
                f"{np.round(piece.bounds, 2).tolist()})"
        try:
            parts.append((validate_solid(piece, name=f"{label}[{index}]"), True, SOLID_REASON))
            continue
        except InvalidMeshError as error:
            problem = not_solid_reason(error)
        if _thickness(np.asarray(piece.vertices)) > tol.flat_rel * size:
            bridged = _bridge_openings(piece)
            if bridged is not None:
                closed, pairs = bridged
                try:
                    parts.append((validate_solid(closed, name=f"{label}[{index}]"), True,
                                  f"closed once {pairs} pair(s) of facing openings got the "
                                  "walls between them"))
                except InvalidMeshError:
                    pass
                else:
                    notes.append(f"{where}: {pairs} pair(s) of facing openings had no walls "
                                 "between them; added the walls")
                    continue
        notes.append(f"{where}: a surface (triangles, as OMPL.app and FCL see them): "
                     f"{problem}")
        parts.append((piece, False, problem))
    return parts
