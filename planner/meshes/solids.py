"""Solids: whether a closed mesh bounds one, and the operations on solids.

Entry points:

- :func:`validate_solid` checks that a mesh bounds a solid (closed, manifold, consistently
  wound, finite, positive volume, winding number never negative) and returns a cleaned
  copy, or raises :class:`~planner.errors.InvalidMeshError` with a one-line reason.
- :func:`split_solid` splits a valid solid into bodies (an outer shell plus the cavity
  shells inside it), the units that :mod:`planner.decompose` works on.
- :func:`mirror` gives the point reflection ``-M`` used for C-obstacles ``O ⊕ (-R)``.
- :func:`winding_numbers`: generalised winding numbers by solid angles (libigl's direct
  sum). It shares no code with the native core on purpose: the validators (FCL
  containment) and the tests use it as an independent reference; heavy work asks the
  core's exact one (:func:`planner._minkowski_core.winding_numbers`).

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
from typing import Any

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from planner.blas import single_blas_thread
from planner.errors import InvalidMeshError
from planner.tolerances import scale_of, tol

from .checked import remember
from .topology import (
    checked_arrays,
    clean_faces,
    closed_candidate,
    compact,
    components,
    edge_stats,
    face_areas,
    face_graph,
    faces_by_label,
    merge_vertices,
    orient_consistently,
    shell_edge_stats,
    signed_volumes,
    unshare_vertices,
)

__all__ = ["SOLID_REASON", "clean", "mirror", "not_solid_reason", "obj_hint", "orient_shells",
           "split_solid", "validate_solid", "winding_numbers"]

SOLID_REASON = "closed and its winding number never negative"
"""Why a mesh that passes :func:`validate_solid` is a solid (for reports)."""

log = logging.getLogger(__name__)


def not_solid_reason(error: InvalidMeshError) -> str:
    """Why a mesh is no solid, from :func:`validate_solid`'s error, without its label and
    the advice on fixing it."""
    return without_advice(str(error).split(": ", 1)[-1])


def without_advice(message: str) -> str:
    """An error message up to its advice: to the first ``"; "`` outside parentheses (the
    reason may hold one: "not watertight (3 boundary edges, 0 non-manifold edges; 1
    zero-area triangles)")."""
    depth = 0
    for at, char in enumerate(message):
        depth += {"(": 1, ")": -1}.get(char, 0)
        if depth == 0 and message.startswith("; ", at):
            return message[:at]
    return message


@single_blas_thread
def validate_solid(mesh, *, name: str = "mesh") -> trimesh.Trimesh:
    """Check that a mesh bounds a solid and return a cleaned copy.

    Cleaning, all harmless for a valid solid: float64 vertices; unreferenced vertices
    dropped; vertices closer than ``tol.merge_rel * scale`` merged; collapsed and
    repeated faces dropped; zero-area faces and back-to-back coincident face pairs
    dropped when the surface stays closed without them; winding made consistent;
    shells that are inside out (negative volume, not nested in another shell) flipped,
    with a log message. The degenerate faces dropped, faces turned and shells flipped
    are counted in ``metadata[SOLID_CHANGES]`` (:data:`SOLID_CHANGES`). The input is
    never modified.

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
    vertices, faces = checked_arrays(mesh, label)
    bad = ~np.all(np.isfinite(vertices), axis=1)
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    if (bad & used).any():
        first = int(np.flatnonzero(bad & used)[0])
        raise InvalidMeshError(
            f"{label}: {int((bad & used).sum())} vertices have NaN or infinite coordinates "
            f"(first: vertex {first}); fix the exporter or remove them"
        )
    vertices, faces = compact(vertices, faces)
    tidy = _tidy_windings(vertices, faces, label)
    if tidy is not None:
        return _solid(mesh, name, vertices, faces, tidy, {})
    cleaned, report = clean(vertices, faces, label)
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
            f"planner.meshes.repair_mesh{_loader_hint(mesh)}"
        )
    faces = orient_shells(vertices, faces, label, report["scale"], report)
    overlaps = _self_overlaps(vertices, faces, report["scale"])
    if overlaps:
        raise InvalidMeshError(
            f"{label}: surface overlaps itself ({overlaps} pairs of coplanar faces facing "
            f"opposite ways overlap); typically polygons triangulated wrongly by the "
            f"exporter{obj_hint(mesh)}"
        )
    windings = _check_winding(vertices, faces, label)
    if report["flipped_shells"]:  # said once the result is a solid
        log.info("%s: %d of %d closed shell(s) were inside out; flipped them", label,
                 report["flipped_shells"], report["shells"])
    if report["fixed_winding_faces"]:
        log.info("%s: %d face(s) were wound against their neighbours; turned them", label,
                 report["fixed_winding_faces"])
    if report["merged_vertices"] or report["removed_faces"]:
        log.debug(
            "%s: merged %d vertices, removed %d faces",
            label, report["merged_vertices"], report["removed_faces"],
        )
    return _solid(mesh, name, vertices, faces, windings, _solid_changes(report))


def _solid_changes(report: dict[str, Any]) -> dict[str, int]:
    """What the cleaning's ``report`` changed to make a solid (:data:`SOLID_CHANGES`):
    the counts of :data:`_CHANGE_KEYS` that are not zero."""
    return {key: report[key] for key in _CHANGE_KEYS if report[key]}


def _solid(mesh, name: str, vertices: np.ndarray, faces: np.ndarray,
           windings: tuple[int, int, Any], changes: dict[str, int]) -> trimesh.Trimesh:
    """The validated solid: a new mesh with the input's metadata, its name, what was
    changed to make it one (:data:`SOLID_CHANGES`), its winding counts and the core's
    checked solid (:func:`_check_winding`'s ``windings``)."""
    faces_inside, crossings, checked = windings
    result = trimesh.Trimesh(vertices, faces, process=False)
    result.metadata.update(getattr(mesh, "metadata", {}) or {})
    result.metadata["name"] = name
    result.metadata[SOLID_CHANGES] = changes
    result.metadata[FACES_INSIDE] = faces_inside
    result.metadata[FACE_CROSSINGS] = crossings
    remember(result, checked, solid=True)
    return result


def _tidy_windings(vertices: np.ndarray, faces: np.ndarray, label: str
                   ) -> tuple[int, int, Any] | None:
    """:func:`_check_winding`'s result for a mesh that is already a tidy solid: one the
    cleaning (:func:`clean`, :func:`orient_shells`, :func:`_self_overlaps`) would not
    change, as the core checks with the same tolerances, each a little looser (see
    ``minkowski_core/src/exact/tidy.rs``); ``None`` for any other mesh, which the full
    cleaning and checks then take. One native call instead of a few dozen array passes:
    a box is validated in about a tenth of the time, the IndustReal small gear in 0.6 of
    it (its winding numbers are most of what is left)."""
    from planner._minkowski_core import tidy_solid_windings  # noqa: PLC0415

    scale = scale_of(vertices)
    if not scale > 0:
        return None
    limits = (tol.merge_rel * scale, tol.degenerate_area_rel * scale**2,
              tol.zero_volume_rel * scale**3, tol.fold_angle, tol.coplanar_rel * scale)
    found = tidy_solid_windings(vertices, faces, limits, label)
    if found is None:
        return None
    fronts, _, crossings_inside, checked = found
    return int((fronts != 0).sum()), crossings_inside, checked


def obj_hint(mesh) -> str:
    """The advice for a mesh whose polygons may have been fanned wrongly: only for an OBJ
    file that was not read by :func:`planner.meshes.load_obj` (which triangulates n-gons
    in their plane)."""
    metadata = getattr(mesh, "metadata", None) or {}
    path = str(metadata.get("file_path", ""))
    if "polygon_problems" in metadata or (path and not path.lower().endswith(".obj")):
        return ""
    return " or loader (an OBJ with n-gons: read it with planner.meshes.load_obj)"


def _loader_hint(mesh) -> str:
    """The advice for an open mesh that may be an OBJ's polygons fanned wrongly by another
    loader (trimesh's): as :func:`obj_hint`'s."""
    return ("; if it was read from an OBJ file with polygons by another loader, read it with "
            "planner.load_mesh (which triangulates them in their plane)") if obj_hint(mesh) else ""


FACES_INSIDE = "faces_inside"
"""Key of a solid's ``metadata`` (from :func:`validate_solid`): how many of its faces have
the solid in front of them too (winding number above 0 there: shells that touch or
overlap), so are not part of its boundary."""


SOLID_CHANGES = "solid_changes"
"""Key of a solid's ``metadata`` (from :func:`validate_solid`): what it changed to make a
solid, as counts (``{"removed_collapsed_faces": 1, "fixed_winding_faces": 1}``, the keys
of :data:`_CHANGE_KEYS`; empty when the input was a tidy solid), which the callers report
as changes made to make a solid."""

_CHANGE_KEYS = ("removed_collapsed_faces", "removed_degenerate_faces",
                "removed_duplicate_faces", "removed_back_to_back_faces",
                "removed_reversed_copies", "fixed_winding_faces", "flipped_shells")
"""The cleaning's counts that are changes to the input's solid: degenerate faces dropped
(a repeated vertex, also once vertices closer than the merge tolerance are welded; zero
area), repeated faces and back-to-back pairs (a fin of no thickness) dropped, a face's
reversed copy dropped (where dropping both would open the surface), faces wound
against their neighbours turned and shells exported inside out flipped (the keys
:func:`planner.meshes.repair_mesh` reports them by too)."""


FACE_CROSSINGS = "face_crossings"
"""Key of a solid's ``metadata`` (from :func:`validate_solid`): along how many segments
its faces cross each other with the solid on both sides of both (shells that overlap):
there, too, parts of faces lie inside the solid, though no face need have it in front of
its samples (an L made of two bars overlapping at its corner)."""


def _check_winding(vertices: np.ndarray, faces: np.ndarray, label: str
                   ) -> tuple[int, int, Any]:
    """Raise unless the closed, consistently wound surface bounds a solid: its exact
    winding number (the core's) is never negative, neither in front of a face nor where
    faces cross (see the module's conventions). Returns how many faces have the solid in
    front of them too (:data:`FACES_INSIDE`), along how many segments faces cross inside
    it (:data:`FACE_CROSSINGS`), and the core's checked solid (:mod:`.checked`)."""
    from planner._minkowski_core import solid_windings  # noqa: PLC0415

    untold = np.iinfo(np.int64).min
    fronts, wedges, crossings_inside, checked = solid_windings(vertices, faces, label)
    inverted = int(((fronts < 0) & (fronts != untold)).sum())
    inverted_wedges = int(((wedges < 0) & (wedges != untold)).sum())
    unknown = int((fronts == untold).sum() + (wedges == untold).sum())
    if checked is not None and not (inverted or inverted_wedges or unknown):
        return int((fronts != 0).sum()), crossings_inside, checked
    told = np.concatenate([fronts[fronts != untold], wedges[wedges != untold]])
    detail = []
    if inverted or inverted_wedges:
        where = f"{inverted} of {len(faces)} faces"
        if inverted_wedges:
            where += f" and {inverted_wedges} of {len(wedges)} crossings of faces"
        detail.append(f"{where} have the inside in front of them (winding number "
                      f"{int(told.min())} there: inverted faces, or shells glued inside out)")
    if unknown:
        detail.append(f"{unknown} places on coincident faces could not be told")
    raise InvalidMeshError(
        f"{label}: closed but not a solid: {'; '.join(detail)}; it can only be used as a "
        f"surface (triangles, as FCL sees them)"
    )


def clean(vertices, faces, label):
    """Shared cleaning of validate_solid and repair_mesh (no hole filling)."""
    scale = scale_of(vertices)
    if scale == 0:
        raise InvalidMeshError(f"{label}: zero volume: all vertices coincide")
    vertices, faces, merged = merge_vertices(vertices, faces, tol.merge_rel * scale)
    faces, collapsed, duplicates, opposite = clean_faces(faces)
    if len(faces) == 0:
        raise InvalidMeshError(f"{label}: zero volume: every triangle is degenerate")
    degenerate = face_areas(vertices, faces) < tol.degenerate_area_rel * scale**2
    faces, n_deg, n_opp, n_copies, stats = closed_candidate(faces, degenerate, opposite)
    vertices, faces = compact(vertices, faces)
    touching = 0
    if stats == (0, 0) and edge_stats(faces)[1]:
        # closed shells touching along edges: separate them
        touching = edge_stats(faces)[1]
        vertices, faces = unshare_vertices(vertices, faces, shell_edge_stats(faces)[2])
    report = {
        "scale": scale,
        "merged_vertices": int(merged),
        "removed_collapsed_faces": collapsed,
        "removed_duplicate_faces": duplicates,
        "removed_degenerate_faces": n_deg,
        "removed_back_to_back_faces": n_opp,
        "removed_reversed_copies": n_copies,
        "removed_faces": collapsed + duplicates + n_deg + n_opp + n_copies,
        "degenerate_faces": int(degenerate.sum()) - n_deg,
        "back_to_back_faces": int(opposite.sum()) - n_opp - 2 * n_copies,
        "separated_touching_edges": int(touching),
        "edge_stats": stats,
    }
    return (vertices, faces), report


def orient_shells(vertices, faces, label, scale, report):
    """Make winding consistent and orient every closed shell (outward bodies, inward
    cavities). Updates ``report`` and returns the faces. Raises for non-orientable or
    flat shells."""
    faces, flipped, orientable = orient_consistently(faces)
    if not orientable:
        raise InvalidMeshError(
            f"{label}: surface is not orientable (inconsistent winding that cannot be "
            f"fixed, e.g. a Moebius-like strip); fix the model"
        )
    pairs, _ = face_graph(faces)
    count, labels = components(len(faces), pairs)
    # a shell whose winding had to be fixed has no trustworthy orientation: it gets the
    # one its nesting depth implies
    unknown = {int(k) for k in np.unique(labels[flipped])}
    known = np.array([k not in unknown for k in range(count)], dtype=bool)
    volumes = signed_volumes(vertices, faces, labels, count)
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
    # what changed against the input: whole shells exported inside out, and faces of the
    # other shells wound against their neighbours (those the shell's turn did not undo)
    turned = (flipped ^ flip_shell[labels]) & ~known[labels]
    report["fixed_winding_faces"] = report.get("fixed_winding_faces", 0) + int(turned.sum())
    report["flipped_shells"] = int((flip_shell & known).sum())
    report["shells"] = int(count)
    report["cavities"] = int(
        (np.where(flip_shell, -volumes, volumes) < 0).sum()
    )
    return faces


def _self_overlaps(vertices: np.ndarray, faces: np.ndarray, scale: float) -> int:
    """Number of face pairs of one closed shell that face opposite ways in one plane
    and overlap there: the surface covers part of a plane twice, as a fanned non-convex
    polygon does (its signed volume stays right, so nothing else notices).

    Faces of different shells may touch this way (two bodies resting on each other).
    """
    pairs, _ = face_graph(faces)
    count, labels = components(len(faces), pairs)
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
    margin = tol.touch_rel * scale
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


def winding_numbers(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Generalised winding number of points with respect to a triangle surface.

    The sum of the triangles' signed solid angles / 4π, computed by libigl's
    ``igl.winding_number`` (the direct sum, in C++ over threads). For a valid solid it is
    1 inside, 0 outside and ~0.5 on the surface; it adds up over shells (cavities cancel)
    and, unlike ray parity, is not confused by coincident faces of bodies that touch.
    ``inside = winding_numbers(p, mesh.triangles) > 0.5``. It shares no code with the
    native core on purpose: the validators (FCL containment) and the tests use it as an
    independent reference. Not libigl's ``fast_winding_number``, which approximates far
    triangles by dipoles: containment here must not be approximate. (Measured on the
    IndustReal large gear, 50,332 triangles, 400 points: 0.23 s, 5x faster than the numpy
    sum it replaced, which agreed to 2e-14; ``tests/benchmarks/bench_libraries.py``.)

    Args:
        points: ``(n, 3)`` query points.
        triangles: ``(m, 3, 3)`` triangle corners (e.g. ``mesh.triangles``).

    Returns:
        ``(n,)`` float64 winding numbers.
    """
    import igl  # noqa: PLC0415 (lazy: the CLI starts without it)

    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    triangles = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    if len(points) == 0 or len(triangles) == 0:
        return np.zeros(len(points))
    corners = np.ascontiguousarray(triangles.reshape(-1, 3))
    faces = np.arange(len(corners), dtype=np.int64).reshape(-1, 3)
    return np.asarray(igl.winding_number(corners, faces, points), dtype=np.float64)


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
    shells = faces_by_label(labels, count)
    size = np.abs(volumes)
    depth = {}
    for i in which:
        candidates = np.flatnonzero(
            (size > size[i]) & np.all(lo <= lo[i], axis=1) & np.all(hi >= hi[i], axis=1)
        )
        depth[i] = sum(
            _inside_shell(vertices, faces, shells[i], shells[j]) for j in candidates
        )
    return depth


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
    pairs, _ = face_graph(faces)
    count, labels = components(len(faces), pairs)
    # renumber components by first face so the order is deterministic
    _, first = np.unique(labels, return_index=True)
    rank = np.zeros(count, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(count)
    labels = rank[labels]
    volumes = signed_volumes(vertices, faces, labels, count)
    shells = faces_by_label(labels, count)
    owner = np.arange(count)
    cavities = np.flatnonzero(volumes <= 0)
    if len(cavities):
        lo = np.stack([vertices[faces[m]].reshape(-1, 3).min(axis=0) for m in shells])
        hi = np.stack([vertices[faces[m]].reshape(-1, 3).max(axis=0) for m in shells])
        for k in cavities:
            # the smallest outward shell around the cavity owns it
            candidates = np.flatnonzero(
                (volumes > -volumes[k])
                & np.all(lo <= lo[k], axis=1)
                & np.all(hi >= hi[k], axis=1)
            )
            for j in candidates[np.argsort(volumes[candidates], kind="stable")]:
                if _inside_shell(vertices, faces, shells[k], shells[j]):
                    owner[k] = j
                    break
    by_body = faces_by_label(owner[labels], count)
    bodies = []
    for j in np.flatnonzero(volumes > 0):
        v, f = compact(vertices, faces[np.sort(by_body[j])])
        bodies.append(trimesh.Trimesh(v, f, process=False))
    return bodies
