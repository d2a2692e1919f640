"""Exact-source sums whose boundary cells are resolved by planes: flat parts come out as
their exact faces (few triangles, sharp edges and corners where the true sum has them);
where an exact edge runs into the sampled band the band chamfers it, closed and within the
bound.

References: manifold3d's sum (exact for these pairs: B contains the origin), the FCL
membership oracle (tests/oracle.py) and closed forms.
"""

from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh

import planner
from tests import oracle, shapes


def exact_sum(a, b, rel_eps=0.005):
    lo, hi = a.bounds[0] + b.bounds[0], a.bounds[1] + b.bounds[1]
    r = planner.minkowski_sum(a, b, exact=True, eps=rel_eps * float(np.linalg.norm(hi - lo)),
                              progress=False)
    assert r.mesh.is_watertight and r.mesh.is_winding_consistent and r.mesh.volume > 0
    return r


def manifold_sum(a, b) -> trimesh.Trimesh:
    m = shapes.to_manifold(a).minkowski_sum(shapes.to_manifold(b))
    return shapes.from_manifold(m, "manifold3d sum", allow_degenerate=True)


def feature_edges(mesh: trimesh.Trimesh, angle_deg: float = 10.0) -> np.ndarray:
    """Segments (n, 2, 3) where two faces meet at more than ``angle_deg``."""
    sharp = mesh.face_adjacency_angles > np.radians(angle_deg)
    return mesh.vertices[mesh.face_adjacency_edges[sharp]]


def distance_to_edges(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Each point's distance to the nearest of the segments."""
    a, d = segments[:, 0], segments[:, 1] - segments[:, 0]
    rel = points[:, None, :] - a[None]
    t = np.clip(np.einsum("pse,se->ps", rel, d) / np.einsum("se,se->s", d, d), 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * d[None], axis=2).min(axis=1)


def test_box_sum_is_its_six_faces():
    a = shapes.box((2.0, 1.0, 1.5))
    b = shapes.box((0.6, 0.4, 0.2))
    r = exact_sum(a, b)
    assert len(r.mesh.faces) == 12
    assert r.stats["band_cells"] == 0 and r.stats["planar_cells"] > 0
    # exact where resolved by planes, and nothing was sampled or missed
    assert r.stats["bound_by_region"] == {"planes": 0.0, "sampled": 0.0, "missed": 0.0}
    corners = np.array([[x, y, z] for x in (-1.3, 1.3) for y in (-0.7, 0.7) for z in (-0.85, 0.85)])
    assert np.abs(np.sort(r.mesh.vertices, axis=0) - np.sort(corners, axis=0)).max() < 1e-12


@pytest.mark.parametrize("pair", ["L-bracket ⊕ cube", "L-bracket ⊕ jack", "jack ⊕ tetrahedron",
                                  "cube ⊕ octahedron"])
def test_flat_pairs_are_exact_with_their_sharp_edges(pair):
    make = {
        "L-bracket ⊕ cube": (shapes.l_bracket, lambda: shapes.box((1.0, 1.0, 1.0))),
        "L-bracket ⊕ jack": (shapes.l_bracket, shapes.jack),
        # the jack's concave edges meet the tetrahedron's faces: vertices where four or
        # more planes meet, resolved by their arrangement in the cell
        "jack ⊕ tetrahedron": (shapes.jack, shapes.tetrahedron),
        "cube ⊕ octahedron": (lambda: shapes.box((1.0, 1.0, 1.0)), _octahedron),
    }[pair]
    a, b = make[0](), make[1]()
    r = exact_sum(a, b)
    truth = manifold_sum(a, b)
    assert r.mesh.volume == pytest.approx(truth.volume, rel=1e-9)
    assert r.stats["band_cells"] == 0, "every boundary cell resolved by planes"
    assert len(r.mesh.faces) <= 3 * len(truth.faces)
    # each plane's regions triangulated once, straight creases without the cell walls'
    # vertices: nothing left to collapse afterwards
    assert r.stats["planar_fanned"] == 0 and r.stats["planar_straight_dropped"] > 0
    assert r.stats["triangles_extracted"] == len(r.mesh.faces)
    # every true sharp edge is an edge of ours: points along it lie on our edges
    edges = feature_edges(truth)
    t = np.linspace(0.05, 0.95, 7)
    starts, runs = edges[:, None, 0], edges[:, None, 1] - edges[:, None, 0]
    along = (starts + t[None, :, None] * runs).reshape(-1, 3)
    ours = r.mesh.vertices[r.mesh.edges_unique]
    assert distance_to_edges(along, ours).max() < 1e-9 * truth.scale
    d1, d2 = oracle.sampled_hausdorff(r.mesh, truth, n=4000, seed=0)
    assert max(d1, d2) < 1e-9 * truth.scale


def _octahedron() -> trimesh.Trimesh:
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float) * 0.4
    return trimesh.convex.convex_hull(v)


def test_cube_plus_octahedron_has_the_closed_form_volume():
    # the sum of the unit cube and the octahedron of radius s: the cube's volume, its faces
    # swept by s, its edges swept by the octahedron's rhombic sections, and the octahedron
    s = 0.4
    r = exact_sum(shapes.box((1.0, 1.0, 1.0)), _octahedron())
    exact = 1.0 + 6.0 * s + 12.0 * (s * s) / 2.0 * 2.0 / 2.0 + 4.0 / 3.0 * s ** 3
    assert r.stats["band_cells"] == 0
    assert r.mesh.volume == pytest.approx(exact, rel=1e-12)


def test_a_fine_torus_sum_is_its_facets_with_a_few_sampled_cells_chamfering_its_edges():
    # the fine torus's facets meet the ball's near its vertices: a cell with more planes
    # than a cut takes, even split below the lattice, is sampled; the exact edges that run
    # into that band are chamfered there within the grid's bound, the rest are exact
    a, b = shapes.torus(10.0, 3.0, 64, 32), shapes.icosphere(2, 0.9)
    r = exact_sum(a, b)
    assert r.stats["planar_cells"] > 1000 and 0 < r.stats["band_cells"] < 50
    truth = manifold_sum(a, b)
    assert len(r.mesh.faces) <= len(truth.faces), "its facets, not a sampled band"
    assert r.mesh.body_count == 1 and r.mesh.euler_number == 0
    d1, d2 = oracle.sampled_hausdorff(r.mesh, truth, n=6000, seed=1)
    assert max(d1, d2) <= r.error_bound
    assert abs(r.mesh.volume - truth.volume) <= 1e-6 * truth.volume


def agree_away_from_surface(r, a, b, n, seed):
    """Random points farther than the bound from our surface: inside ours exactly when in
    A ⊕ B (FCL oracle). Returns how many were compared."""
    rng = np.random.default_rng(seed)
    lo, hi = a.bounds[0] + b.bounds[0], a.bounds[1] + b.bounds[1]
    pts = rng.uniform(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo), size=(n, 3))
    pts = pts[oracle.surface_distance(r.mesh, pts) > r.error_bound]
    ours, truth = oracle.points_in_mesh(r.mesh, pts), oracle.in_minkowski_sum(pts, a, b)
    assert (ours == truth).all(), f"{(ours != truth).sum()} of {len(pts)} disagree"
    assert 0.05 < truth.mean() < 0.95
    return len(pts)


def test_a_coarse_torus_operand_is_resolved_by_its_facets_and_agrees_with_the_oracle():
    # the small torus's facets are larger than the cells: every boundary cell of the sum
    # is cut by a few of them, so the sum is its exact facets, not a sampled band
    a, b = shapes.jack(), shapes.torus(1.0, 0.3, 24, 12)
    r = exact_sum(a, b)
    assert r.stats["band_cells"] == 0 and r.stats["planar_cells"] > 0
    assert r.mesh.body_count == 1 and r.mesh.euler_number == 2
    # the regions about the torus's hole have holes: bridged, they are triangulated once
    assert r.stats["planar_fanned"] == 0 and r.stats["triangles_extracted"] == len(r.mesh.faces)
    # (manifold3d is no reference here: the torus does not contain the origin)
    assert agree_away_from_surface(r, a, b, 3000, seed=2) > 1000


def test_two_grates_sum_to_their_exact_box_and_agree_with_the_oracle():
    # non-convex ⊕ non-convex with interior facets everywhere (Varadhan & Manocha's kind);
    # each grate's holes are narrower than the other plate, so the sum is a box
    a, b = shapes.grate(5, 4.0, 0.4, 0.15), shapes.grate(8, 3.0, 0.3, 0.1)
    r = exact_sum(a, b, rel_eps=0.005)
    assert r.mesh.body_count == 1
    assert len(r.mesh.faces) == 12 and r.stats["planar_cells"] > 0
    assert r.stats["planar_fanned"] == 0, "the faces' regions with holes are bridged"
    lo, hi = r.mesh.bounds
    assert abs(r.mesh.volume - np.prod(hi - lo)) < 1e-9 * np.prod(hi - lo)
    assert np.allclose(hi - lo, a.extents + b.extents, rtol=0, atol=1e-12)
    assert agree_away_from_surface(r, a, b, 3000, seed=4) > 1000


@pytest.mark.parametrize("rel_eps", [0.005, 0.01])
def test_a_crevice_thinner_than_the_weld_is_closed_within_the_bound_without_sampling(rel_eps):
    # the part's tab hole (radius 0.5, 32 sides) nearly closes under the ball (radius 0.5):
    # the sum keeps two conical crevices on the hole's axis, about 0.02 wide at their mouths
    # and closing to nothing. Where the exact polygons of the cells along them meet, the
    # crevice is thinner than the weld tolerance and leaves holes narrower than the grid's
    # bound; they are closed (the bound covers their diameter) instead of sampled around,
    # where the lattice would miss the crevice and the bound grow past the grid's
    a, b = shapes.nonconvex_part_2k(), shapes.icosphere(2, 0.5)
    r = exact_sum(a, b, rel_eps)
    assert r.stats["holes_closed"] > 0 and r.stats["complex_cells"] == 0
    # (at 1% the first grid's lattice misses boundary near a thin feature, and it is
    # halved once)
    assert r.stats["refinements"] == (0 if rel_eps == 0.005 else 1)
    # nothing is sampled around: the join is closed at once. (Its T-junctions are split
    # with no new vertex; split by fans about the triangles' centroids, as they were
    # before, this part had sheets within a weld to part, and it has none now.)
    assert r.stats["planes_fallback_edges"] == 0
    # any sheets within a weld are parted, so a reader welding by position (STL) keeps
    # them apart: the file reads back closed
    float32_steps = 16 * np.finfo(np.float32).eps * np.abs(r.mesh.vertices).max()
    assert 0 <= r.stats["sheets_apart"] <= max(1e-3 * r.stats["h"], float32_steps)
    read = trimesh.load_mesh(io.BytesIO(r.mesh.export(file_type="stl")), file_type="stl")
    assert read.is_watertight and read.is_winding_consistent
    # the closed holes are what the plane-resolved part's bound holds for, within the grid's
    by_region = r.stats["bound_by_region"]
    assert 0.0 < by_region["planes"] <= r.error_bound and by_region["missed"] <= r.error_bound
    assert r.error_bound <= 2.0 * r.stats["eps"]
    # the crevice is there in the true sum: free points at its mouth
    mouth = np.array([[-4.30, 0.60, -3.60], [-4.30, 0.60, -2.45]])
    assert not oracle.in_minkowski_sum(mouth, a, b).any()
    d1, d2 = oracle.sampled_hausdorff(r.mesh, manifold_sum(a, b), n=6000, seed=5)
    assert max(d1, d2) <= r.error_bound
    assert agree_away_from_surface(r, a, b, 3000, seed=6) > 1000
