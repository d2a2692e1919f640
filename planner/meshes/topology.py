"""Index bookkeeping of triangle meshes: grouping equal rows, edge usage, boundary loops,
face adjacency and components, consistent winding, vertex merging, face cleaning.

Everything here works on plain ``(n, 3)`` float64 vertex and ``(m, 3)`` int64 face arrays
and knows nothing of solids; :mod:`planner.meshes.solids` and :mod:`planner.meshes.repair`
build on it.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy import sparse
from scipy.sparse import csgraph
from scipy.spatial import cKDTree

from planner.errors import InvalidMeshError

__all__ = [
    "boundary_loops",
    "checked_arrays",
    "clean_faces",
    "closed_candidate",
    "reversed_copies",
    "compact",
    "components",
    "edge_stats",
    "face_areas",
    "face_graph",
    "group_rows",
    "faces_by_label",
    "merge_vertices",
    "orient_consistently",
    "shell_edge_stats",
    "signed_volumes",
    "unshare_vertices",
]


def checked_arrays(mesh, label: str):
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
    _check_magnitude(vertices, faces, label)
    return vertices, faces


def _check_magnitude(vertices: np.ndarray, faces: np.ndarray, label: str) -> None:
    """Raise when a vertex the faces use has a finite coordinate beyond
    :data:`MAX_COORDINATE` (non-finite ones are each caller's to report or drop)."""
    if not np.any(np.abs(vertices) > MAX_COORDINATE):
        return
    used = vertices[np.unique(faces)]
    largest = np.abs(used[np.isfinite(used)]).max(initial=0.0)
    if largest > MAX_COORDINATE:
        raise InvalidMeshError(
            f"{label}: coordinates up to {largest:.3g} exceed {MAX_COORDINATE:g}, beyond what "
            f"volumes and distances can be computed with; rescale the model"
        )


MAX_COORDINATE = 1e30
"""The largest coordinate a mesh may have (any unit): the checks and the core compute
volumes (cubes of lengths) and squared distances of sums, which overflow float64 near
1e100 (a box scaled by 1e150 did); 1e30 keeps them far from that and any real part (a
light year is 1e25 millimetres) inside it."""


def compact(vertices: np.ndarray, faces: np.ndarray):
    """Drop unreferenced vertices (keeping order)."""
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[faces]


def merge_vertices(vertices: np.ndarray, faces: np.ndarray, distance: float):
    """Merge vertices closer than ``distance`` (clusters, transitively), keeping the first
    vertex of each cluster. Returns ``(vertices, faces, merged_count)``.

    Kept by hand, measured (``tests/benchmarks/bench_libraries.py``): trimesh's
    ``merge_vertices`` is as fast (0.9x to 1.3x this on the IndustReal large gear's 25k
    vertices) but rounds coordinates to a fixed absolute grid (``tol.merge = 1e-8``), so
    two vertices 2e-12 apart on either side of a grid line stay apart, and its tolerance does
    not follow the part's size; ``trimesh.grouping.clusters`` is these same cKDTree pairs
    and components, returning groups that still need this renumbering.
    """
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


def clean_faces(faces: np.ndarray):
    """Drop collapsed faces (repeated index) and repeated copies of same-wound faces.

    Returns ``(faces, collapsed, duplicates, opposite_mask)`` where ``opposite_mask``
    marks faces that have a coincident face of opposite winding."""
    collapsed = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (
        faces[:, 2] == faces[:, 0]
    )
    faces = faces[~collapsed]
    canonical = _canonical_rotation(faces)
    first = group_rows(canonical)[2]
    keep = np.zeros(len(faces), dtype=bool)
    keep[first] = True
    duplicates = int(len(faces) - keep.sum())
    faces = faces[np.sort(np.flatnonzero(keep))]
    inverse, counts, _ = group_rows(np.sort(faces, axis=1))
    opposite = counts[inverse] > 1
    return faces, int(collapsed.sum()), duplicates, opposite


def face_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    tri = vertices[faces]
    return 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)


def closed_candidate(faces, degenerate, opposite):
    """Pick the least invasive removal of degenerate / back-to-back faces that leaves a
    closed manifold surface: both faces of each back-to-back pair (a fin of no
    thickness), or only the later of each (a face and its reversed copy). Returns
    ``(faces, removed_degenerate, removed_opposite, removed_copies, stats)``; ``stats``
    are the edge stats of the returned faces."""
    copies = reversed_copies(faces, opposite)
    n_deg, n_opp, n_copies = int(degenerate.sum()), int(opposite.sum()), int(copies.sum())
    options = [
        (degenerate | opposite, n_deg, n_opp, 0),
        (degenerate, n_deg, 0, 0),
        (opposite, 0, n_opp, 0),
        (degenerate | copies, n_deg, 0, n_copies),
        (copies, 0, 0, n_copies),
        (np.zeros(len(faces), dtype=bool), 0, 0, 0),
    ]
    best = None
    for drop, *removed in options:
        if any(removed) and drop.all():
            continue
        candidate = faces[~drop]
        stats = shell_edge_stats(candidate)[:2]
        if stats[0] == 0 and stats[1] == 0:
            return (candidate, *removed, stats)
        score = stats[0] + stats[1]
        if best is None or score < best[0]:
            best = (score, candidate, *removed, stats)
    assert best is not None  # the last option drops nothing and always scores
    return best[1:]


def reversed_copies(faces: np.ndarray, opposite: np.ndarray) -> np.ndarray:
    """Of each face and its reversed copy (``opposite``, from :func:`clean_faces`), the
    later one."""
    copies = opposite.copy()
    copies[group_rows(np.sort(faces, axis=1))[2]] = False
    return copies


def group_rows(rows: np.ndarray):
    """Group equal rows of an integer array (``trimesh.grouping.unique_rows``, which packs
    a row into one integer where it fits: 2x to 3x faster than the lexsort this replaced,
    on the 151k edges of the IndustReal large gear; ``tests/benchmarks/bench_libraries.py``).

    Returns ``(inverse, counts, first)``: each row's group id (groups in an arbitrary but
    deterministic order), the size of each group, and the first row index of each group.
    """
    rows = np.asarray(rows)
    if len(rows) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    first, inverse = trimesh.grouping.unique_rows(rows)
    inverse = np.asarray(inverse, dtype=np.int64).reshape(-1)
    return inverse, np.bincount(inverse, minlength=len(first)), np.asarray(first, np.int64)


def edge_stats(faces: np.ndarray):
    """Edge usage of a triangle list.

    Returns ``(boundary, nonmanifold, consistent)``: the number of undirected edges used
    by one face, by more than two faces, and whether no directed edge is used twice
    (every interior edge is traversed once in each direction).
    """
    if len(faces) == 0:
        return 0, 0, True
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    undirected = np.sort(directed, axis=1)
    counts = group_rows(undirected)[1]
    dcounts = group_rows(directed)[1]
    return int((counts == 1).sum()), int((counts > 2).sum()), bool((dcounts == 1).all())


def boundary_loops(faces: np.ndarray) -> tuple[list[list[int]], int]:
    """Closed loops of boundary edges (edges used by one face).

    A loop is a cycle through vertices that each lie on exactly two boundary edges; it
    runs the way most of its edges are traversed by their faces (all of them on a
    consistently wound mesh). Returns ``(loops, tangled)``: the loops, each a list of
    vertex indices, and how many boundary edges lie on no loop (they meet a vertex with
    more than two boundary edges: a pinch, or holes that touch). Used by hole filling
    (:func:`planner.meshes.repair_mesh`) and by OMPL.app's facing openings.

    Kept by hand, measured (``tests/benchmarks/bench_libraries.py``): trimesh finds
    boundary cycles only inside ``repair.fill_holes``, with networkx's ``cycle_basis``
    (networkx is no dependency here): 1.2x this on the IndustReal large gear with 1,000
    faces removed, and its cycles are undirected, with pinches split or joined
    arbitrarily (976 cycles where this finds 533 loops and sets 1,342 edges apart).
    """
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    inverse, counts, _ = group_rows(np.sort(directed, axis=1))
    boundary = directed[counts[inverse] == 1]
    neighbours: dict[int, list[int]] = {}
    for a, b in boundary.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    forward = {(int(a), int(b)) for a, b in boundary}
    loops: list[list[int]] = []
    seen: set[int] = set()
    for start in sorted(neighbours):
        if start in seen or len(neighbours[start]) != 2:
            continue
        loop = _walk_loop(neighbours, start, seen)
        if loop is None:
            continue
        steps = zip(loop, loop[1:] + loop[:1], strict=True)
        along = sum((a, b) in forward for a, b in steps)
        loops.append(loop if 2 * along >= len(loop) else loop[::-1])
    return loops, len(boundary) - sum(len(loop) for loop in loops)


def _walk_loop(neighbours: dict[int, list[int]], start: int, seen: set[int]) -> list[int] | None:
    """The cycle of boundary edges through ``start``, or ``None`` when it reaches a
    vertex that is not on exactly two boundary edges. Marks its vertices in ``seen``."""
    loop, previous, current = [start], -1, start
    seen.add(start)
    while True:
        a, b = neighbours[current]
        following = b if a == previous else a
        if following == start:
            return loop if len(loop) >= 3 else None
        if following in seen or len(neighbours[following]) != 2:
            return None
        loop.append(following)
        seen.add(following)
        previous, current = current, following


def shell_edge_stats(faces: np.ndarray):
    """Edge usage counted shell by shell.

    Shells are the face components connected over edges used by exactly two faces.
    Closed shells that touch along an edge (two boxes sharing an edge, after vertex
    merging) make that edge non-manifold for the mesh, but each shell on its own is
    closed: such a mesh is a valid union of solids. Returns ``(boundary, nonmanifold,
    labels)`` counted per shell, and each face's shell label.
    """
    if len(faces) == 0:
        return 0, 0, np.zeros(0, dtype=np.int64)
    pairs, _ = face_graph(faces)
    _, labels = components(len(faces), pairs)
    undirected = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keyed = np.column_stack([np.repeat(labels, 3), undirected])
    counts = group_rows(keyed)[1]
    return int((counts == 1).sum()), int((counts > 2).sum()), labels


def unshare_vertices(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray):
    """Give every shell its own copy of the vertices it shares with other shells, so
    shells that touch along edges become separate, index-manifold components."""
    pairs = np.column_stack([faces.ravel(), np.repeat(labels, 3)])
    pairs = pairs[group_rows(pairs)[2]]
    if len(np.unique(pairs[:, 0])) == len(pairs):
        return vertices, faces  # no vertex is shared between shells
    # one new vertex per (vertex, shell) pair
    keys = faces.ravel() * (labels.max() + 1) + np.repeat(labels, 3)
    uniq, inverse = np.unique(keys, return_inverse=True)
    new_vertices = vertices[uniq // (labels.max() + 1)]
    return new_vertices, inverse.reshape(-1, 3)


def face_graph(faces: np.ndarray):
    """Face adjacency over edges shared by exactly two faces.

    Returns ``(pairs, same)``: ``(k, 2)`` adjacent face indices and whether the two faces
    traverse their shared edge in the same direction (inconsistent winding).
    """
    nf = len(faces)
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    owner = np.repeat(np.arange(nf), 3)
    undirected = np.sort(directed, axis=1)
    inverse, counts, _ = group_rows(undirected)
    keep = counts[inverse] == 2
    order = np.argsort(inverse[keep], kind="stable")
    rows = np.flatnonzero(keep)[order].reshape(-1, 2)
    pairs = owner[rows]
    same = np.all(directed[rows[:, 0]] == directed[rows[:, 1]], axis=1)
    return pairs, same


def components(nf: int, pairs: np.ndarray):
    graph = sparse.coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(nf, nf)
    ).tocsr()
    count, labels = csgraph.connected_components(graph, directed=False)
    return count, labels


def orient_consistently(faces: np.ndarray):
    """Flip faces so that adjacent faces traverse shared edges in opposite directions.

    Works per connected component (over manifold edges), keeping each component's
    first face as it is. Returns ``(faces, flipped_mask, orientable)``.

    Kept by hand, measured (``tests/benchmarks/bench_libraries.py``):
    ``trimesh.repair.fix_winding`` takes 30x to 50x this on the IndustReal large gear (50k
    faces, a tenth flipped; a Python loop over networkx's BFS edges), needs networkx, and
    says nothing when a surface cannot be oriented, which this reports.
    """
    nf = len(faces)
    pairs, same = face_graph(faces)
    if not same.any():
        return faces, np.zeros(nf, dtype=bool), True
    # one breadth-first spanning forest: a virtual node nf links the first face of every
    # component; a face must be flipped iff the number of "same direction" edges on its
    # tree path to the root is odd (accumulated by pointer jumping, vectorised)
    count, labels = components(nf, pairs)
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
    _, still_same = face_graph(fixed)
    return fixed, flip, not still_same.any()


def signed_volumes(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray, count: int):
    """Signed volume enclosed by the faces of each component label."""
    centre = vertices.mean(axis=0)
    tri = vertices[faces] - centre
    six_v = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
    return np.bincount(labels, weights=six_v, minlength=count) / 6.0


def faces_by_label(labels: np.ndarray, count: int) -> list[np.ndarray]:
    """Face indices of each label, ``O(n log n)``."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(count + 1))
    return [order[bounds[k]:bounds[k + 1]] for k in range(count)]
