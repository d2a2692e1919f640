"""Explicit, best-effort repair of messy real-world meshes into solids.

Entry point: :func:`repair_mesh` (merge vertices, drop degenerate and duplicate faces,
read double-sided surfaces one-sided, fix winding, fill simple holes, orient shells),
which returns the repaired solid and a report of what it changed.
"""

from __future__ import annotations

import logging

import numpy as np
import trimesh

from planner.blas import single_blas_thread
from planner.errors import InvalidMeshError
from planner.tolerances import scale_of, tol

from .solids import clean, obj_hint, orient_shells, validate_solid
from .topology import (
    boundary_loops,
    checked_arrays,
    clean_faces,
    compact,
    group_rows,
    merge_vertices,
    orient_consistently,
    shell_edge_stats,
    unshare_vertices,
)
from .triangulation import ear_clip

__all__ = ["repair_mesh"]

log = logging.getLogger(__name__)


@single_blas_thread
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
        ``removed_back_to_back_faces``, ``removed_reversed_copies``, ``single_sided_faces``,
        ``fixed_winding_faces``, ``filled_holes``, ``added_faces``, ``flipped_shells``,
        ``shells``) and the final ``volume``.

    Raises:
        InvalidMeshError: the result is still not a watertight, orientable solid
            (the message says what is left).
    """
    label = f"mesh {name!r}"
    vertices, faces = checked_arrays(mesh, label)
    finite = np.all(np.isfinite(vertices), axis=1)
    good_faces = finite[faces].all(axis=1)
    report: dict = {"input_vertices": len(vertices), "input_faces": len(faces)}
    report["removed_nonfinite_faces"] = int((~good_faces).sum())
    faces = faces[good_faces]
    if len(faces) == 0:
        raise InvalidMeshError(f"{label}: nothing to repair: no faces with finite vertices")
    try:
        return _repaired(vertices, faces, mesh, name, label, report)
    except InvalidMeshError as error:
        dropped = report["removed_nonfinite_faces"]
        if not dropped:
            raise
        raise InvalidMeshError(f"{error} (after removing the {dropped} faces with NaN or "
                               f"infinite vertex coordinates)") from None


def _repaired(vertices: np.ndarray, faces: np.ndarray, mesh, name: str, label: str,
              report: dict) -> tuple[trimesh.Trimesh, dict]:
    """:func:`repair_mesh` of the finite faces."""
    vertices, faces = compact(vertices, faces)
    scale = scale_of(vertices)
    vertices, faces, merged = merge_vertices(vertices, faces, tol.merge_rel * scale)

    attempts = [False]
    _, _, _, opposite = clean_faces(faces)
    if opposite.any():
        attempts.append(True)  # fall back to reading a double-sided surface one-sided
    best = None
    for single_sided in attempts:
        result = _repair_attempt(vertices, faces, label, single_sided)
        if best is None or result[3] < best[3]:
            best = result
        if result[3] == 0:
            break
    assert best is not None  # attempts is never empty
    vertices, faces, attempt, bad, shells = best
    report.update(attempt)
    if bad:
        raise InvalidMeshError(
            f"{label}: could not repair: {attempt['edge_stats'][0]} boundary edges and "
            f"{attempt['edge_stats'][1]} non-manifold edges remain after filling "
            f"{attempt['filled_holes']} holes; fix the model{obj_hint(mesh)}"
        )
    vertices, faces = unshare_vertices(vertices, faces, shells)
    faces = orient_shells(vertices, faces, label, scale, report)
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
        faces, _, _, opposite = clean_faces(faces)
        first = group_rows(np.sort(faces, axis=1))[2]
        keep = np.zeros(len(faces), dtype=bool)
        keep[first] = True
        kept = int((opposite & ~keep).sum())
        faces = faces[keep]
    (vertices, faces), report = clean(vertices, faces, label)
    report["single_sided_faces"] = kept
    faces, flipped, _ = orient_consistently(faces)
    report["fixed_winding_faces"] = int(flipped.sum())
    # Hole filling by hand: trimesh.repair.fill_holes fills only triangular and quad
    # holes, larger ones only as fans (use_fan), wrong for a non-convex hole: an L-shaped
    # one stays open either way (tests/benchmarks/bench_libraries.py); pymeshfix is
    # GPL-3.0 and rebuilds the whole mesh (one watertight body, self-intersections and
    # small components removed), which moves geometry that repair must keep.
    loops, _ = boundary_loops(faces)
    added = []
    for loop in loops:
        hole = loop[::-1]  # the fill traverses the boundary edges the other way
        local, _ = ear_clip(vertices[hole])
        added.append(np.asarray(hole, dtype=np.int64)[local])
    report["filled_holes"] = len(added)
    report["added_faces"] = int(sum(len(a) for a in added))
    if added:
        faces = np.concatenate([faces, *added])
    boundary, nonmanifold, shells = shell_edge_stats(faces)
    report["edge_stats"] = (boundary, nonmanifold)
    return vertices, faces, report, boundary + nonmanifold, shells
