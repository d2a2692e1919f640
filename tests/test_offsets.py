"""Offsets and morphology against closed forms and exact distances: a grown box and a grown
regular tetrahedron against Steiner's formula, an eroded box against the shrunken box, a
torus that keeps its hole while the radius is below the hole's and loses it after, an
opening that removes a fin thinner than twice the radius, and the two-sided bound checked
point by point against the exact distance to the solid."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree
from shapes import box, from_manifold, to_manifold

import planner
from planner.cli import main
from planner.errors import (
    EmptyResultError,
    GeometryError,
    InvalidParameterError,
    ResourceLimitError,
)
from planner.meshes.closest import mesh_distance
from planner.meshes.solids import FACES_INSIDE, validate_solid
from planner.offsets_convex import CLOSED, ROUNDED


def _steiner(mesh: trimesh.Trimesh, r: float) -> float:
    """Volume of a convex polytope grown by ``r``: V + A r + (1/2) Σ_e L_e (π − θ_e) r²
    + (4/3) π r³, with θ_e the dihedral angle at edge e."""
    edges = mesh.face_adjacency_edges
    lengths = np.linalg.norm(mesh.vertices[edges[:, 0]] - mesh.vertices[edges[:, 1]], axis=1)
    exterior = mesh.face_adjacency_angles  # π − θ_e (0 for coplanar faces)
    mean = 0.5 * float(np.sum(lengths * exterior))
    return mesh.volume + mesh.area * r + mean * r * r + 4.0 / 3.0 * math.pi * r ** 3


def _volume_slack(result, area: float) -> float:
    """How far the volume may be off: the surface lies within the bound of the true one."""
    return area * result.error_bound * 1.05


@pytest.mark.parametrize("method", ["hull", "ball", "cells"])
@pytest.mark.parametrize("shape", ["box", "tetrahedron"])
def test_a_grown_convex_solid_has_steiners_volume(shape, method):
    if shape == "box":
        solid = trimesh.creation.box([2.0, 1.0, 0.5])
    else:
        solid = trimesh.Trimesh([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]],
                                [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    r = 0.3
    result = planner.offset(solid, r, eps=0.03, method=method)
    assert result.stats["method"] == method
    exact = _steiner(solid, r)
    grown_area = float(result.mesh.area)
    assert result.mesh.is_watertight and result.mesh.volume > 0
    assert abs(result.mesh.volume - exact) <= _volume_slack(result, grown_area), (
        result.mesh.volume, exact, result.error_bound)


def test_an_eroded_box_is_the_shrunken_box():
    result = planner.offset(trimesh.creation.box([2.0, 1.0, 1.0]), -0.2, eps=0.02)
    np.testing.assert_allclose(result.mesh.bounds, [[-0.8, -0.3, -0.3], [0.8, 0.3, 0.3]],
                               atol=result.error_bound)
    exact = 1.6 * 0.6 * 0.6
    assert abs(result.mesh.volume - exact) <= _volume_slack(result, 2 * (0.96 + 0.36 + 0.96))


def test_an_eroded_box_is_resolved_by_its_face_planes_exactly():
    # every cell of the shrunken box's boundary lies in the column over one to three faces:
    # cut by their offset planes at its size, nothing sampled
    result = planner.offset(trimesh.creation.box([2.0, 1.0, 1.0]), -0.2, method="cells")
    assert result.stats["planar_pieces"] > 0 and result.stats["band_cells"] == 0
    assert len(result.mesh.faces) == 12
    corners = np.abs(result.mesh.vertices)
    assert np.allclose(corners, [0.8, 0.3, 0.3], rtol=0, atol=1e-12)
    assert abs(result.mesh.volume - 1.6 * 0.6 * 0.6) < 1e-12


@pytest.mark.parametrize("method", ["hull", "ball", "cells"])
def test_a_grown_box_has_exact_flat_faces_joined_to_its_round_edges(method):
    # the cell source (its face columns cut by their offset planes), the convex path
    # (the hull of the corners' balls, with a ball point along every face normal) and
    # the sum with the inscribed ball (the face normals among its vertices)
    half, r = 0.5, 0.25
    result = planner.offset(trimesh.creation.box([1.0, 1.0, 1.0]), r, eps=0.02, method=method)
    assert result.mesh.is_watertight
    if method == "hull":
        assert result.stats["convex"] and result.stats["band_cells"] == 0
    elif method == "ball":
        assert result.stats["ball"]["with_face_normals"]
    else:
        assert result.stats["planar_pieces"] > 0
    tris = result.mesh.triangles
    centroids = tris.mean(axis=1)
    # the triangles over the middle of a face (in its column by more than the bound) lie
    # on the offset plane to rounding, corners and all: not within the grid's bound only
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        over = np.all(np.abs(centroids[:, others]) < half - 2 * result.error_bound, axis=1)
        over &= np.abs(centroids[:, axis]) > half
        assert over.sum() >= 2
        np.testing.assert_allclose(np.abs(tris[over][:, :, axis]), half + r, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", ["hull", "ball", "cells"])
def test_every_output_point_is_within_the_bound_of_the_true_offset_surface(method):
    solid = trimesh.creation.box([1.0, 1.0, 1.0])
    r = 0.25
    result = planner.offset(solid, r, eps=0.03, method=method)
    points, _ = trimesh.sample.sample_surface(result.mesh, 4000, seed=0)
    # the exact distance to the box (a solid: 0 inside)
    outside = np.maximum(np.abs(points) - 0.5, 0.0)
    distance = np.linalg.norm(outside, axis=1)
    assert np.all(np.abs(distance - r) <= result.error_bound + 1e-12)


def test_a_convex_offset_needs_no_grid_and_its_bound_holds_both_ways():
    """One convex body (a random hull of 40 points): grown, its facets, edges and
    corners moved out and tessellated — every output point within the bound of r from
    the solid, the round parts' points split between the two sides, the bound within
    eps; eroded, the face planes moved inward — every output vertex exactly |r| inside.
    Against exact distances to the solid (trimesh's closest points) and the solid's own
    face planes."""
    from shapes import random_convex

    solid = random_convex(40, (1.0, 0.8, 0.6), seed=3)
    r, eps = 0.15, 0.004
    grown = planner.offset(solid, r, eps=eps)
    assert grown.stats["convex"] and grown.stats["h"] == 0.0
    assert grown.mesh.is_watertight and grown.mesh.is_winding_consistent
    assert 0.0 < grown.error_bound <= eps
    points = np.vstack([grown.mesh.vertices,
                        trimesh.sample.sample_surface(grown.mesh, 4000, seed=2)[0]])
    distance = mesh_distance(solid.vertices, solid.faces, points)
    assert np.all(np.abs(distance - r) <= grown.error_bound + 1e-9)
    # the chords' sag split: about half of the bound out, half in
    assert distance.max() - r > 0.3 * grown.error_bound
    assert r - distance.min() > 0.3 * grown.error_bound
    eroded = planner.offset(solid, -0.05, eps=eps)
    normals = solid.face_normals
    offsets = np.einsum("ij,ij->i", normals, solid.triangles[:, 0])
    depth = (offsets[None, :] - eroded.mesh.vertices @ normals.T).min(axis=1)
    np.testing.assert_allclose(depth, 0.05, rtol=0, atol=1e-9)
    assert eroded.error_bound < 1e-8


def _cube_with_a_needle(side: float) -> trimesh.Trimesh:
    """A cube whose face x = side/2 is split at the middle of its edge with the face
    y = side/2, the gap closed by a zero-area triangle along that edge (a needle with no
    normal of its own): still one closed, convex solid."""
    m = trimesh.creation.box((side, side, side))
    v, f = np.array(m.vertices), [list(x) for x in m.faces]
    edges = {}
    for i, tri in enumerate(f):
        for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges[e] = i
    # an edge on the convex crease between two faces, not a face diagonal
    (p, q), j = next((e, edges[(e[1], e[0])]) for e in edges if (e[1], e[0]) in edges
                     and np.count_nonzero(v[e[0]] != v[e[1]]) == 1)
    mid = len(v)
    v = np.vstack([v, 0.5 * (v[p] + v[q])])
    tri = f[j]
    k = tri.index(q)
    q_, p_, r_ = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
    f[j] = [q_, mid, r_]
    f.append([mid, p_, r_])
    f.append([p, mid, q])
    return trimesh.Trimesh(v, np.array(f), process=False)


@pytest.mark.parametrize("side", [1.0, 1000.0])
def test_a_convex_solid_with_a_zero_area_sliver_is_eroded_by_its_hulls_planes(side):
    """A needle triangle has no reliable plane: the erosion takes the hull's facets, each
    moved to bound every vertex, so the cube shrinks by 2 r on each axis."""
    r = 0.1 * side
    eroded = planner.offset(_cube_with_a_needle(side), -r, eps=0.01 * side)
    assert eroded.stats.get("convex") == "hull's facet planes moved inward"
    half = side / 2 - r
    np.testing.assert_allclose(eroded.mesh.bounds, [[-half] * 3, [half] * 3], rtol=0,
                               atol=1e-9 * side)
    assert eroded.mesh.volume == pytest.approx((2 * half) ** 3, rel=1e-9)
    grown = planner.offset(_cube_with_a_needle(side), r, eps=0.01 * side)
    assert grown.stats.get("convex") and grown.mesh.is_watertight
    assert grown.mesh.bounds[1][0] == pytest.approx(side / 2 + r, rel=1e-12)


def test_a_solid_convex_up_to_rounding_is_offset_by_its_hull_within_the_bound():
    """Corners of a convex solid rounded to 1e-3 (as CAD exports round theirs): no longer
    exactly convex, so the bound adds how far the hull lies from the largest polytope of its
    planes that the solid is shown to contain; both ways against the exact distance to the
    rounded solid itself, and a dent deeper than eps is left to the cell source."""
    from shapes import random_convex

    exact = random_convex(40, (10.0, 8.0, 6.0), seed=5)
    rounded = trimesh.Trimesh(np.round(exact.vertices, 3), exact.faces, process=False)
    r, eps = 0.5, 0.05
    grown = planner.offset(rounded, r, eps=eps)
    assert grown.stats["convex"] and 0 < grown.stats["hull_depth"] <= 2e-3
    assert grown.error_bound <= eps
    points = np.vstack([grown.mesh.vertices,
                        trimesh.sample.sample_surface(grown.mesh, 4000, seed=4)[0]])
    _, distance, _ = trimesh.proximity.closest_point(rounded, points)
    assert np.all(np.abs(distance - r) <= grown.error_bound)
    eroded = planner.offset(rounded, -r, eps=eps)
    assert eroded.stats["convex"]
    inside = eroded.mesh.vertices
    _, depth, _ = trimesh.proximity.closest_point(rounded, inside)
    assert np.all(rounded.contains(inside)) and np.all(np.abs(depth - r) <= eroded.error_bound)
    # a dent of 0.3 in one face: deeper than eps (0.25 here, a coarse grid), so no hull path
    dented = rounded.copy()
    centre = dented.triangles_center[0]
    dented.vertices = np.vstack([dented.vertices, centre - 0.3 * dented.face_normals[0]])
    dented = trimesh.Trimesh(dented.vertices, np.vstack([
        np.delete(dented.faces, 0, axis=0),
        [[dented.faces[0][0], dented.faces[0][1], len(dented.vertices) - 1],
         [dented.faces[0][1], dented.faces[0][2], len(dented.vertices) - 1],
         [dented.faces[0][2], dented.faces[0][0], len(dented.vertices) - 1]]]), process=False)
    assert "convex" not in planner.offset(dented, r, eps=0.25).stats


def _nudged_cube() -> trimesh.Trimesh:
    """A unit cube with one corner moved 1e-7 out of its face: the hull's two facets
    there meet at about 1e-7 rad."""
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    vertices = np.array(box.vertices)
    vertices[int(np.argmax(vertices @ [1.0, 1.0, 1.0]))] += [1e-7, 0.0, 0.0]
    return trimesh.Trimesh(vertices, box.faces, process=False)


def _assert_within_bound_both_ways(solid: trimesh.Trimesh, r: float, grown) -> None:
    """Output points (corners and samples) within the bound of ``r`` from the solid (the
    exact point-to-triangle distance)."""
    points = np.vstack([grown.mesh.vertices,
                        trimesh.sample.sample_surface(grown.mesh, 4000, seed=5)[0]])
    distance = mesh_distance(solid.vertices, solid.faces, points)
    assert np.all(np.abs(distance - r) <= grown.error_bound + 1e-12)


def test_facets_meeting_almost_flat_are_welded_into_the_bound():
    """The nudged cube grown by r = 0.1: its two facets' corners moved out lie about 1e-8
    apart, closer than a float32 file keeps apart; they are welded, the bound adds the
    move, and no two output points are closer than the weld distance."""
    nudged, r = _nudged_cube(), 0.1
    grown = planner.offset(nudged, r, eps=1e-3)
    assert grown.stats["convex"] == ROUNDED and 0 < grown.stats["round_welded"] < 1e-7
    assert grown.mesh.is_watertight and grown.mesh.is_winding_consistent
    assert 0 < grown.error_bound <= 1e-3
    _assert_within_bound_both_ways(nudged, r, grown)
    closest, _ = cKDTree(grown.mesh.vertices).query(grown.mesh.vertices, k=2)
    assert closest[:, 1].min() > 1e-7


def test_the_hull_of_the_corners_balls_takes_what_the_core_refuses(monkeypatch):
    """The fallback alone (the core's tessellation refused): the hull of the corners'
    icosphere balls, within its bound of the exact distance."""
    from planner import offsets_convex

    monkeypatch.setattr(offsets_convex, "_rounded", lambda *args: None)
    nudged, r = _nudged_cube(), 0.1
    grown = planner.offset(nudged, r, eps=1e-3)
    assert grown.stats["convex"] == "hull of the vertices' tessellated balls"
    assert grown.mesh.is_watertight and 0 < grown.error_bound <= 1e-3
    _assert_within_bound_both_ways(nudged, r, grown)


def test_a_non_convex_solid_is_offset_by_the_sum_with_an_inscribed_ball():
    from shapes import l_bracket

    result = planner.offset(l_bracket(), 0.1, eps=0.05)
    assert "convex" not in result.stats and result.stats["method"] == "ball"
    ball = result.stats["ball"]
    assert 0 < ball["delta"] <= 0.5 * 0.05 and ball["with_face_normals"]
    assert result.stats["bound_by_region"]["round"] == ball["delta"]
    cells = planner.offset(l_bracket(), 0.1, eps=0.05, method="cells")
    assert cells.stats["method"] == "cells" and cells.stats["band_cells"] > 0


@pytest.mark.parametrize("method", ["ball", "cells"])
@pytest.mark.parametrize("r", [0.2, -0.15])
def test_a_non_convex_offset_is_within_its_bound_of_the_exact_distance(method, r):
    # concave edges and corners: the boundary's crossings there come from several
    # triangles' neighbourhoods at once (their closed-form intervals, merged); eroded,
    # every point inside the bracket at |r| from its boundary, within the bound
    from shapes import l_bracket

    bracket = l_bracket(length=2.0, height=1.5, thickness=0.5, depth=1.0)
    result = planner.offset(bracket, r, eps=0.04, method=method)
    assert result.stats["method"] == method
    assert result.mesh.is_watertight and result.mesh.is_winding_consistent
    assert result.mesh.volume > 0 and math.isfinite(result.error_bound)
    points = np.vstack([result.mesh.vertices,
                        trimesh.sample.sample_surface(result.mesh, 4000, seed=1)[0]])
    _, distance, _ = trimesh.proximity.closest_point(bracket, points)
    inside = bracket.contains(points)
    if r > 0:
        distance = np.where(inside, 0.0, distance)
    else:
        assert np.all(inside | (distance <= 1e-9))
    assert np.max(np.abs(distance - abs(r))) <= result.error_bound
    # the other way: points at exactly |r| from the bracket, near its faces, edges and
    # corners, lie within the bound of the output surface
    probes = _on_the_offset(bracket, r, 3000, seed=4)
    assert len(probes) > 200
    _, to_output, _ = trimesh.proximity.closest_point(result.mesh, probes)
    assert np.max(to_output) <= result.error_bound


def test_two_corners_nearly_touching_keep_the_bound_as_stated():
    """Two cubes corner to corner along (1, 1, 1), their grown corners' balls overlapping
    by less than the ball's chord: the true offset is one body, the sum with the
    inscribed ball may leave them apart. What the bound states still holds: every
    output point's distance to the solid within it of r, every point at distance r
    within it of the output."""
    a = trimesh.creation.box([1.0, 1.0, 1.0])
    b = a.copy()
    b.apply_translation(np.full(3, 1.0 + 2 * 0.296 / math.sqrt(3.0)))
    pair = trimesh.util.concatenate([a, b])
    r = 0.3
    result = planner.offset(pair, r, eps=0.03, method="ball")
    points = np.vstack([result.mesh.vertices,
                        trimesh.sample.sample_surface(result.mesh, 4000, seed=2)[0]])
    _, distance, _ = trimesh.proximity.closest_point(pair, points)
    distance = np.where(pair.contains(points), 0.0, distance)
    assert np.max(np.abs(distance - r)) <= result.error_bound
    probes = _on_the_offset(pair, r, 3000, seed=5)
    _, to_output, _ = trimesh.proximity.closest_point(result.mesh, probes)
    assert np.max(to_output) <= result.error_bound


def test_an_erosion_to_sheets_thinner_than_the_weld_states_a_bound_reaching_them():
    """An L of two bars 0.2 thick eroded by just under 0.1 leaves sheets 2e-7 thick along
    its arms. At eps 0.02 the extraction welds their two sides together, and they come
    apart into slivers, which are dropped: the bound must then reach over where they were
    (it stated 0.02, the sheets lying 0.4 from the output)."""
    bars = box((0.8, 0.2, 0.3)), box((0.2, 0.4, 0.3), center=(0.3, 0.1, 0.0))
    solid = from_manifold(to_manifold(bars[0]) + to_manifold(bars[1]), "L")
    r = 0.0999999
    result = planner.offset(solid, -r, eps=0.02, method="ball")
    assert result.stats["slivers_apart"] > 0
    mid_arm = np.array([[-0.2, 0.1 - r, 0.0]])  # on the true erosion's boundary: r deep
    depth = float(mesh_distance(solid.vertices, solid.faces, mid_arm)[0])
    assert depth == pytest.approx(r, abs=1e-9)
    _, to_output, _ = trimesh.proximity.closest_point(result.mesh, mid_arm)
    assert to_output[0] > 0.3  # (the sheet is gone from the output)
    assert to_output[0] <= result.error_bound


@pytest.mark.parametrize("method", ["ball", "cells"])
@pytest.mark.parametrize("r, genus", [(0.15, 1), (0.9, 0)])
def test_a_torus_keeps_its_hole_until_the_radius_fills_it(r, genus, method):
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3,
                                   major_sections=24, minor_sections=12)
    # the hole's radius is about 0.7
    result = planner.offset(torus, r, eps=0.05, method=method)
    euler = result.mesh.euler_number
    assert result.mesh.is_watertight and euler == 2 - 2 * genus, euler
    # the bound by region kind, none above the total: the cell source's round parts
    # sampled at the grid's, the ball's its chord
    by_region = result.stats["bound_by_region"]
    kind = "sampled" if method == "cells" else "round"
    assert 0.0 < by_region[kind] and max(by_region.values()) <= result.error_bound


def test_an_opening_removes_a_fin_thinner_than_twice_the_radius():
    body = trimesh.creation.box([1.0, 1.0, 1.0])
    fin = trimesh.creation.box([0.7, 0.1, 0.6])
    fin.apply_translation([0.7, 0.0, 0.0])  # 0.1 thin in y, sticking out to x = 1.05
    finned = trimesh.boolean.union([body, fin], engine="manifold")
    assert finned.bounds[1][0] == pytest.approx(1.05)
    opened = planner.opening(finned, 0.12, eps=0.05)
    # no feature's thickness is near 2 r = 0.24 (the fin 0.1, the body 1): the stages'
    # bounds add up here (in general an opening's bound is unknown: error_bound is inf)
    assert opened.error_bound == math.inf
    slack = sum(opened.stats["stage_bounds"])
    assert opened.mesh.bounds[1][0] <= 0.5 + slack  # the fin is gone
    assert opened.mesh.volume < 1.0  # and the body's edges are rounded off
    closed = planner.closing(finned, 0.12, eps=0.05)
    assert closed.mesh.bounds[1][0] >= 1.05 - sum(closed.stats["stage_bounds"])


def test_eroding_a_float32_box_by_half_its_thickness_leaves_a_sheet_said_as_nothing(
        tmp_path, caplog):
    # a float32 file rounds 0.2 up by 3e-9: the erosion by 0.2 leaves a sheet 6e-9 thick,
    # which the hull answers at once (before, the ball ran 25 s and warned of its bound)
    trimesh.creation.box([1.0, 0.6, 0.4]).export(tmp_path / "box.stl")
    box = trimesh.load(tmp_path / "box.stl")
    thickness = float(np.ptp(box.vertices[:, 2]))
    assert 0.4 < thickness < 0.4 + 1e-8
    with pytest.raises(EmptyResultError, match="flat sheet at most") as empty:
        planner.offset(box, -0.2)
    sheet = float(str(empty.value).split("at most ")[1].split()[0])
    assert sheet == pytest.approx(thickness - 0.4, rel=1e-3)
    assert "bound" not in caplog.text
    # a hair less leaves a thin box, meshed
    thin = planner.offset(box, -0.19999)
    assert thin.stats["method"] == "hull"
    assert np.ptp(thin.mesh.vertices[:, 2]) == pytest.approx(thickness - 0.39998, abs=1e-9)


def test_bad_radii_and_an_erosion_that_leaves_nothing_are_clear_errors(caplog):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    with pytest.raises(InvalidParameterError, match="non-zero finite"):
        planner.offset(box, 0.0)
    with pytest.raises(InvalidParameterError, match="non-zero finite"):
        planner.offset(box, math.nan)
    for not_a_number in ("0.1", True):
        with pytest.raises(InvalidParameterError, match="non-zero finite"):
            planner.offset(box, not_a_number)
    with pytest.raises(EmptyResultError, match="nothing is left"):
        planner.offset(box, -0.6, eps=0.05)
    with pytest.raises(EmptyResultError, match="nothing is left"):
        planner.opening(box, 0.6, eps=0.05)
    from shapes import l_bracket  # not convex: the sum with the ball's complement

    with pytest.raises(EmptyResultError, match="nothing is left"):
        planner.offset(l_bracket(), -0.6, eps=0.05, method="ball")
    with pytest.raises(EmptyResultError, match="nothing is left"):
        planner.offset(l_bracket(), -0.6, eps=0.05)
    # the empty answer is said once, not first warned of as a faulty solid
    assert "no clean solid" not in caplog.text
    with pytest.raises(InvalidParameterError, match="method"):
        planner.offset(box, 0.1, method="sample")
    with pytest.raises(InvalidParameterError, match="not convex"):
        planner.offset(l_bracket(), 0.1, method="hull")
    # an eps past a quarter of the result's size (the grid could miss all of it) is
    # refused naming the largest taken; at that largest there is a surface
    bracket = l_bracket()
    diagonal = float(np.linalg.norm(bracket.extents + 0.2))
    with pytest.raises(InvalidParameterError, match=f"use eps <= {0.25 * diagonal:.3g}"):
        planner.offset(bracket, 0.1, eps=0.3 * diagonal)
    coarse = planner.offset(bracket, 0.1, eps=0.249 * diagonal)
    assert coarse.mesh.is_watertight and coarse.error_bound <= 0.5 * diagonal


@pytest.mark.parametrize("subdivisions_max", [0, 2])
def test_the_inscribed_ball_lies_between_the_spheres_it_states(subdivisions_max):
    """Every vertex of the polytope on the sphere of radius r (so it lies inside the
    ball), every facet plane at least r - delta from the centre and one exactly there
    (so the ball of radius r - delta lies inside it); the solid's few face normals are
    vertices, many are not taken."""
    from planner.offsets_ball import inscribed_ball
    from planner.offsets_convex import unit_ball

    r = 0.7
    delta_max = r * (1.0 - unit_ball(subdivisions_max)[1]) * 1.0001
    few = trimesh.creation.box([1.0, 2.0, 3.0]).face_normals
    ball = inscribed_ball(r, delta_max, few)
    assert ball is not None and ball.subdivisions == subdivisions_max and ball.with_normals
    np.testing.assert_allclose(np.linalg.norm(ball.mesh.vertices, axis=1), r, rtol=1e-12)
    assert all(np.any(np.all(np.isclose(ball.mesh.vertices, r * n, atol=1e-12), axis=1))
               for n in few)
    distances = np.einsum("ij,ij->i", ball.mesh.face_normals, ball.mesh.triangles[:, 0])
    assert distances.min() == pytest.approx(r - ball.delta, abs=1e-12)
    assert ball.mesh.is_watertight and ball.mesh.volume > 0 and 0 < ball.delta <= delta_max
    many = trimesh.creation.icosphere(subdivisions=4).face_normals
    assert not inscribed_ball(r, delta_max, many).with_normals


def test_face_directions_merge_a_float32_files_copies_and_skip_zero_area_triangles(tmp_path):
    """A rotated L-bracket written as STL (float32 corners): its 80 triangles have six
    directions, each normal's copies a few 1e-7 apart; a zero-area triangle has none."""
    from shapes import l_bracket

    from planner.offsets_ball import face_directions

    bracket = l_bracket()
    bracket.apply_transform(trimesh.transformations.rotation_matrix(0.7, [1.0, 2.0, 3.0]))
    bracket = bracket.subdivide().subdivide()
    bracket.export(tmp_path / "bracket.stl")
    read = planner.load_mesh(tmp_path / "bracket.stl")
    assert len(np.unique(np.round(read.face_normals, 12), axis=0)) > 6  # the copies
    directions = face_directions(read)
    assert len(directions) == 6
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, rtol=1e-12)
    assert len(face_directions(_cube_with_a_needle(1.0))) == 6
    grown = planner.offset(_cube_with_a_needle(1.0), 0.1, eps=0.01, method="ball")
    assert grown.mesh.is_watertight and grown.stats["ball"]["with_face_normals"]



@pytest.mark.parametrize("seed", range(5))
def test_representatives_keep_each_point_unless_a_kept_earlier_one_is_near(seed):
    """The clusters' representatives against their definition, walked point by point."""
    from planner.offsets_convex import representatives

    rng = np.random.default_rng(seed)
    points = rng.random((300, 3))
    radius = 0.05 + 0.05 * seed
    kept: list[int] = []
    for i, p in enumerate(points):
        if all(np.linalg.norm(points[k] - p) > radius for k in kept):
            kept.append(i)
    assert representatives(points, radius).tolist() == kept
    assert 1 < len(kept) < 300
    assert representatives(points, 1e-9).tolist() == list(range(300))

def _on_the_offset(solid: trimesh.Trimesh, r: float, count: int, seed: int) -> np.ndarray:
    """Points exactly at distance ``|r|`` from the solid's boundary (outside for ``r > 0``,
    inside otherwise), near faces, edges and corners alike: random points moved along
    the line from their nearest boundary point to that distance, kept where that point
    stays the nearest."""
    rng = np.random.default_rng(seed)
    lo, hi = solid.bounds
    points = rng.uniform(lo - 2 * abs(r), hi + 2 * abs(r), size=(count, 3))
    inside = solid.contains(points)
    points = points[inside if r < 0 else ~inside]
    nearest, distance, _ = trimesh.proximity.closest_point(solid, points)
    keep = distance > 1e-6
    away = (points[keep] - nearest[keep]) / distance[keep, None]
    moved = nearest[keep] + abs(r) * away
    _, check, _ = trimesh.proximity.closest_point(solid, moved)
    return moved[np.abs(check - abs(r)) < 1e-9]


def test_the_tabled_icospheres_are_the_measured_ones():
    """The inner distance and cone angle of every unit icosphere the offsets take are
    tabled (a first offset in a process built and hulled each one up to its own): the
    table must be what qhull measures, and the vertices unit and as many as trimesh's."""
    import planner.offsets_convex as convex

    for subdivisions in range(convex.MAX_SUBDIVISIONS + 1):
        inner, angle = convex.measured_ball(subdivisions)
        assert convex.BALL_INNER[subdivisions] == pytest.approx(inner, rel=1e-12)
        assert convex.ball_cone_angle(subdivisions) == pytest.approx(angle, rel=1e-12)
        unit, own = convex.unit_ball(subdivisions)
        assert own == pytest.approx(inner, rel=1e-12)
        assert len(unit) == 10 * 4 ** subdivisions + 2
        np.testing.assert_allclose(np.linalg.norm(unit, axis=1), 1.0, atol=1e-15)


def test_the_offset_command_writes_the_mesh_and_says_its_bound(tmp_path, capsys):
    part = tmp_path / "part.stl"
    trimesh.creation.box([1.0, 1.0, 1.0]).export(part)
    grown = tmp_path / "grown.stl"
    assert main(["offset", str(part), "-r", "0.2", "-o", str(grown), "--eps", "0.04"]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"wrote {grown}") and "error bound" in line
    assert trimesh.load(grown).is_watertight
    assert f"(hull: {ROUNDED})" in line  # a box: by its hull
    assert "created folder" not in line
    # folders the output needs are made, and the line says so (a mistyped path shows)
    nested = tmp_path / "new" / "deeper" / "grown.obj"
    assert main(["offset", str(part), "-r", "0.2", "-o", str(nested), "--eps", "0.04"]) == 0
    assert capsys.readouterr().out.strip().endswith(f"; created folder {tmp_path / 'new'}")
    assert nested.exists()
    assert main(["offset", str(part), "-r", "-0.1", "-o", str(tmp_path / "shrunk.stl"),
                 "--eps", "0.04", "--method", "ball"]) == 0
    line = capsys.readouterr().out.strip()
    assert "(ball)" in line
    shrunk = trimesh.load(tmp_path / "shrunk.stl")
    assert shrunk.is_watertight and len(shrunk.faces) == 12  # the shrunken box exactly
    assert shrunk.volume == pytest.approx(0.8 ** 3, rel=1e-6)  # (STL: float32)
    assert main(["offset", str(part), "-r", "0", "-o", str(tmp_path / "x.stl")]) == 2
    assert "radius" in capsys.readouterr().err
    # an opening that leaves nothing is an answer (exit 1, no result), not bad input
    gone = tmp_path / "gone.stl"
    assert main(["offset", str(part), "-r", "0.6", "--opening", "-o", str(gone),
                 "--eps", "0.05"]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "nothing is left" in err and "nothing written" in err
    assert not gone.exists()


def test_a_real_cad_part_with_t_junctions_is_offset_as_the_assembly_reads_it():
    from conftest import asset

    hole = planner.load_mesh(asset("assemblies/factory_round_peg_8mm/meshes/"
                                   "factory_round_hole_8mm_subdiv_3x.obj"))
    assert not hole.is_watertight  # 36 T-junctions; split, it is a solid
    shrunk = planner.offset(hole, -0.0005, eps=0.0005, name="hole")
    grown = planner.offset(hole, 0.0005, eps=0.0005, name="hole")
    assert shrunk.mesh.is_watertight and grown.mesh.is_watertight
    assert 0 < shrunk.mesh.volume < grown.mesh.volume
    # by the cells, its plate's faces cut by planes in cells up to 32 wide: the cells the
    # lattice may have missed boundary in lie near those large polygons' middles, far from
    # their corners, and their reach is measured to the polygons (it had doubled the bound)
    cells = planner.offset(hole, 0.001, eps=0.0004, name="hole", method="cells")
    assert cells.stats["bound_by_region"]["missed"] <= 1.01 * 0.0004
    assert cells.error_bound <= 1.01 * 0.0004


@pytest.mark.parametrize("r", [0.001, -0.0005])
@pytest.mark.parametrize("suffix", [".stl", ".obj"])
def test_a_cad_peg_grown_or_eroded_reads_back_closed(tmp_path, r, suffix):
    """Factory's round peg offset by its hull: grown, its coplanar triangles' corners move
    to points a few 1e-9 apart; eroded, its nearly coplanar planes cross at corners 1e-10
    apart. A reader's weld joins those (STL has no connectivity; trimesh welds OBJ's
    within 1e-8): merged first, the files read back closed, and the command writes OBJ
    with 17 decimals (trimesh's default, 8, is 1e-8 m)."""
    from conftest import asset

    source = asset("assemblies/factory_round_peg_8mm/meshes/factory_round_peg_8mm_loose.obj")
    out = tmp_path / f"offset{suffix}"
    assert main(["offset", str(source), "-r", str(r), "-o", str(out)]) == 0
    read = trimesh.load(out)
    assert read.is_watertight and read.is_winding_consistent and read.volume > 0
    offset = planner.offset(planner.load_mesh(source), r, name="peg")
    assert offset.stats["method"] == "hull" and len(read.faces) == len(offset.mesh.faces)
    if suffix == ".obj":  # (17 decimals: 1e-17 m)
        from scipy.spatial import cKDTree

        moved, _ = cKDTree(offset.mesh.vertices).query(read.vertices)
        assert len(read.vertices) == len(offset.mesh.vertices) and moved.max() <= 1e-16


def test_an_eroded_bolt_thread_reads_back_closed_through_a_welding_reader(tmp_path):
    """Factory's M12 bolt eroded by 0.5 mm: its thread's crests erode to sheets a few
    1e-9 thick, whose edges left two vertices 8.75e-9 apart among slivers (no collapse
    keeps the surface a manifold there, and a move into their fans was held to a sixth of
    the slivers' heights). trimesh's load welds within 1e-8, so the file read back with
    three edges used four times; such vertices are now pushed apart (along the line
    through them, or an axis)."""
    from conftest import asset

    source = asset("assemblies/factory_nut_bolt_m12/meshes/factory_bolt_m12_loose.obj")
    out = tmp_path / "eroded.obj"
    assert main(["offset", str(source), "-r", "-0.0005", "-o", str(out)]) == 0
    read = trimesh.load(out)  # welds as a user's load does
    assert read.is_watertight and read.is_winding_consistent and read.volume > 0
    assert len(read.split(only_watertight=False)) == 1


def test_the_offset_command_refuses_an_unknown_format_before_the_work(tmp_path, capsys):
    part = tmp_path / "part.stl"
    trimesh.creation.box([1.0, 1.0, 1.0]).export(part)
    for name in ("grown.xyz", "grown"):
        assert main(["offset", str(part), "-r", "0.2", "-o", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("minkplan: error: --output") and "unknown mesh format" in err
        assert "\n" not in err and not (tmp_path / name).exists()



@pytest.mark.parametrize("seed", range(4))
def test_the_ball_points_left_out_never_change_the_grown_hull(seed):
    """Every corner-and-direction pair against the pairs whose normal cones meet: the
    same hull (same vertices, same volume) on random convex solids, a box and a needle."""
    from shapes import random_convex

    import planner.offsets_convex as convex

    solids = [random_convex(30, (1.0, 0.3, 2.0), seed=seed), trimesh.creation.box((1, 0.6, 0.4)),
              trimesh.convex.convex_hull(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1],
                                                   [40.0 + seed, 50, 50]]))]
    for solid in solids:
        hull = convex._hull_planes(solid, 1e-3)
        for subdivisions in (1, 2):
            unit, _ = convex.unit_ball(subdivisions)
            angle = convex.ball_cone_angle(subdivisions)
            corner, direction = convex._extreme_pairs(hull, unit, angle)
            assert len(corner) < len(hull.corners) * len(unit)
            left = convex.convex_hull(hull.corners[corner] + 0.2 * unit[direction])
            full = convex.convex_hull((hull.corners[:, None] + 0.2 * unit[None]).reshape(-1, 3))
            np.testing.assert_allclose(np.sort(left.points[left.vertices], axis=0),
                                       np.sort(full.points[full.vertices], axis=0), atol=1e-12)
            assert left.volume == pytest.approx(full.volume, rel=1e-12)


@pytest.mark.parametrize("subdivisions", [4, 5])
def test_a_fine_icosphere_is_grown_by_its_hull(subdivisions):
    """A try-out: icospheres of 5,120 and 20,480 triangles were refused by the hull method
    (more triangles than it took; every vertex against every plane was 1.7 GB at 20k), so
    auto took the cells: 688k triangles. Now its hull, thinned: a few thousand triangles,
    the bound holding on sampled points."""
    sphere = trimesh.creation.icosphere(subdivisions)
    grown = planner.offset(sphere, 0.2, eps=0.02)
    assert grown.stats["method"] == "hull" and grown.error_bound <= 0.02
    assert len(grown.mesh.faces) < 10_000
    points, _ = trimesh.sample.sample_surface(grown.mesh, 2000, seed=1)
    distance = np.linalg.norm(points, axis=1) - 1.0  # the unit sphere's vertices are on it
    # the icosphere lies inside the unit sphere, within its own chord of it
    inner = float(np.linalg.norm(sphere.triangles_center, axis=1).min())
    assert np.all(distance <= 0.2 + grown.error_bound + 1e-12)
    assert np.all(distance >= 0.2 - grown.error_bound - (1.0 - inner) - 1e-12)


def test_the_hull_method_says_why_it_declines(monkeypatch):
    from shapes import l_bracket

    with pytest.raises(InvalidParameterError, match=r"method = 'hull': mesh is not convex "
                       r"within eps 0\.05: some triangle lies deeper than that inside "
                       r"its hull; use method 'auto', 'ball' or 'cells'"):
        planner.offset(l_bracket(), 0.1, eps=0.05, method="hull")
    import planner.offsets_convex as convex

    monkeypatch.setattr(convex, "MAX_FACES", 100)
    why: list[str] = []
    assert convex.convex_offset(trimesh.creation.icosphere(2), 0.1, 0.01, why) is None
    assert why == ["has 320 triangles, more than the hull method takes (100)"]


def test_the_hull_planes_offsets_are_the_largest_over_every_vertex(monkeypatch):
    """The planes' offsets come from the hull's own triangles and qhull's coplanar points
    (linear), not every vertex against every plane: the same to rounding, on a fine
    icosphere, a random polytope and a float32 sphere far from the origin; and the far
    search over a large solid's nearest planes (FULL_SEARCH) finds the same depth."""
    from shapes import random_convex

    import planner.offsets_convex as convex

    sphere = trimesh.creation.icosphere(3)
    far = trimesh.Trimesh((sphere.vertices * 1e-3 + [1e3, 2e3, -5e2]).astype(np.float32)
                          .astype(np.float64), sphere.faces, process=False)
    for solid in (trimesh.creation.icosphere(4), random_convex(60, (10.0, 8.0, 6.0), seed=1),
                  far):
        vertices = np.asarray(solid.vertices)
        hull = convex._hull_planes(solid, 0.1 * solid.scale)
        exact = (vertices @ hull.normals.T).max(axis=0)
        ulps = 8 * np.spacing(np.abs(exact) + np.abs(vertices).max())
        assert np.all(np.abs(hull.offsets - exact) <= ulps), solid
    # a dent 2e-3 deep: the least depth by every plane for every triangle, against both
    # searches at an eps just above it (neither stops early)
    solid = random_convex(60, (10.0, 8.0, 6.0), seed=2)
    a, b, c = solid.faces[0]
    dent = solid.triangles_center[0] - 2e-3 * solid.face_normals[0]
    n = len(solid.vertices)
    dented = trimesh.Trimesh(np.vstack([solid.vertices, dent]), np.vstack(
        [solid.faces[1:], [[a, b, n], [b, c, n], [c, a, n]]]), process=False)
    hull = convex._hull_planes(dented, 0.1)
    corners = np.asarray(dented.vertices)[np.asarray(dented.faces)]     # (faces, 3, 3)
    below = hull.offsets[None, None, :] - corners @ hull.normals.T
    least = float(below.max(axis=1).min(axis=1).max())
    assert 1e-3 < least < 2.1e-3
    eps = least * (1 + 1e-9)
    found = convex._depth(np.asarray(dented.vertices), np.asarray(dented.faces),
                          hull.normals, hull.offsets, eps)
    assert least - 1e-12 <= found <= eps
    # a zero-area triangle along the unit cube's top edge has no normal: its first guess
    # (the first plane, x = -0.5) is 1 off, and the search finds a plane it lies on, over
    # every plane or over the nearest ones (FULL_SEARCH 0) when they include one
    cube = trimesh.creation.box()
    top = [int(np.flatnonzero(np.all(np.isclose(cube.vertices, [x, -0.5, 0.5]), axis=1))[0])
           for x in (-0.5, 0.5)]
    vertices = np.vstack([cube.vertices, cube.vertices[top].mean(axis=0)])
    faces = np.vstack([cube.faces, [[top[0], top[1], len(cube.vertices)]]])
    normals = np.vstack([-np.eye(3), np.eye(3)])
    offsets = np.full(6, 0.5)
    assert convex._depth(vertices, faces, normals, offsets, 0.01) == 0.0
    monkeypatch.setattr(convex, "FULL_SEARCH", 0)
    assert convex._depth(vertices, faces, normals, offsets, 0.01) == 0.0
    monkeypatch.setattr(convex, "NEAR_PLANES", 1)  # the first guess only: an upper bound
    assert convex._depth(vertices, faces, normals, offsets, 0.01) == 1.0


def test_the_gap_bound_holds_the_measured_gap_of_a_dented_hull():
    """A dent of up to 6e-3 in one face of a convex solid: the bound on the distance
    between its hull and the hull's planes moved in by the depth holds the measured one,
    within a small factor of the depth."""
    from scipy.spatial import HalfspaceIntersection
    from shapes import random_convex

    import planner.offsets_convex as convex

    for seed in range(6):
        solid = random_convex(60, (10.0, 8.0, 6.0 - 0.8 * seed), seed=seed)
        dent = solid.triangles_center[0] - 1e-3 * (seed + 1) * solid.face_normals[0]
        a, b, c = solid.faces[0]
        n = len(solid.vertices)
        dented = trimesh.Trimesh(np.vstack([solid.vertices, dent]), np.vstack(
            [solid.faces[1:], [[a, b, n], [b, c, n], [c, a, n]]]), process=False)
        hull = convex._hull_planes(dented, 0.1)
        centre, inradius = convex._deepest_point(hull.normals, hull.offsets)
        bound = convex._gap_bound(hull, centre, inradius)
        # H_t's own corners (not merged: the true gap)
        corners = HalfspaceIntersection(
            np.column_stack([hull.normals, hull.depth - hull.offsets]), centre).intersections
        inner = convex.hull_mesh(convex.convex_hull(corners))
        assert 1e-4 < hull.depth and convex._gap(hull.corners, inner) <= bound < 20 * hull.depth


def test_auto_takes_the_cells_for_a_solid_of_small_triangles():
    """An L-bracket cut into 5,120 triangles: at an eps where it has 1.5 times FINE_FACETS
    of them per eps² of surface the sum with the ball would sample cells full of small
    facets, so ``auto`` takes the cells; where it has half that, the ball."""
    from shapes import l_bracket

    from planner.offsets import FINE_FACETS

    bracket = l_bracket().subdivide().subdivide().subdivide().subdivide()
    assert len(bracket.faces) == 5120
    per_eps2 = len(bracket.faces) / bracket.area
    fine, coarse = (math.sqrt(share / per_eps2) for share in (1.5 * FINE_FACETS, 0.5 * FINE_FACETS))
    cells = planner.offset(bracket, 0.1, eps=fine)
    ball = planner.offset(bracket, 0.1, eps=coarse)
    assert (cells.stats["method"], ball.stats["method"]) == ("cells", "ball")
    for result in (cells, ball):
        assert result.mesh.is_watertight and result.error_bound <= 2 * result.eps


def test_writing_stl_or_ply_warns_when_vertices_fall_on_others_at_float32(tmp_path, caplog):
    from planner.output import write_mesh

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    write_mesh(box, tmp_path / "box.stl")
    assert not caplog.records
    pinched = trimesh.Trimesh(np.vstack([box.vertices, box.vertices[0] + 1e-12]),
                              np.vstack([box.faces, [[8, 1, 2]]]), process=False)
    write_mesh(pinched, tmp_path / "pinched.stl")
    assert "1 vertices fall on others at the format's float32 precision" in caplog.text
    write_mesh(pinched, tmp_path / "pinched.obj")  # every digit: no warning
    assert len(caplog.records) == 1
    write_mesh(pinched, tmp_path / "pinched.ply")  # trimesh writes PLY as float32 too
    assert len(caplog.records) == 2
    read = trimesh.load(tmp_path / "pinched.ply", process=False).vertices
    assert np.all(read[8] == read[0])  # the two 1e-12 apart fell on one float32 point


def test_an_eps_past_the_finest_ball_is_left_to_the_cells():
    """The L-bracket grown by 0.1 at eps 2e-4: the ball would need an icosphere finer
    than the finest taken (its convolution with the solid costs more than the cells:
    Factory's hole at eps 1e-7 ran past 300 s before its sum was refused); ``ball`` says
    why it cannot, ``auto`` leaves it to the cells, whose budget refuses that grid at once
    naming eps."""
    from shapes import l_bracket

    from planner.offsets_ball import MAX_SUBDIVISIONS, inscribed_ball
    from planner.offsets_convex import unit_ball

    r = 0.1
    finest = r * (1.0 - unit_ball(MAX_SUBDIVISIONS)[1])
    assert inscribed_ball(r, 0.9 * finest, np.zeros((0, 3))) is None
    eps = 1.8 * finest  # (the ball gets half of eps)
    with pytest.raises(InvalidParameterError, match="finer than the finest icosphere"):
        planner.offset(l_bracket(), r, eps=eps, method="ball")
    with pytest.raises(ResourceLimitError, match="octree needs more than .* use a larger eps"):
        planner.offset(l_bracket(), r, eps=eps)


def test_radii_out_of_scale_and_wrong_types_are_clear_errors():
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    with pytest.raises(InvalidParameterError, match="more than 1e\\+06 times"):
        planner.offset(box, 1e100)
    with pytest.raises(InvalidParameterError, match="below 1e-09"):
        planner.offset(box, -1e-100)
    with pytest.raises(InvalidParameterError, match="non-zero finite"):
        planner.offset(box, None)
    with pytest.raises(InvalidParameterError, match="must be positive"):
        planner.opening(box, -0.1)
    with pytest.raises(InvalidParameterError, match="must be positive"):
        planner.closing(box, -0.1)


def test_eroding_touching_shells_is_refused_and_growing_them_is_their_union():
    # a peg standing on a block, two closed shells touching over the peg's foot: its
    # foot faces into the block, so the triangles are not all the solid's boundary
    block = trimesh.creation.box([2.0, 2.0, 1.0])
    peg = trimesh.creation.box([0.5, 0.5, 1.0])
    peg.apply_translation([0.0, 0.0, 1.0])
    part = trimesh.util.concatenate([block, peg])
    with pytest.raises(InvalidParameterError, match="face into the solid"):
        planner.offset(part, -0.1, eps=0.05)
    with pytest.raises(InvalidParameterError, match="face into the solid"):
        planner.opening(part, 0.1, eps=0.05)
    grown = planner.offset(part, 0.1, eps=0.05)
    assert grown.mesh.is_watertight and grown.mesh.body_count == 1


def test_the_command_takes_a_negative_radius_in_scientific_notation(tmp_path, capsys):
    part = tmp_path / "box.stl"
    trimesh.creation.box([1.0, 1.0, 1.0]).export(part)
    out = tmp_path / "shrunk.stl"
    assert main(["offset", str(part), "-r", "-1e-1", "-o", str(out)]) == 0
    assert trimesh.load(out).volume == pytest.approx(0.8 ** 3, rel=1e-6)
    assert main(["offset", str(part), "-r", "-inf", "-o", str(out)]) == 2
    assert "radius" in capsys.readouterr().err


def test_an_opening_takes_one_method_for_both_stages_and_stays_inside():
    # IndustReal's gear base: the eroded stage (by the ball) has many small triangles,
    # which alone would send the growing stage to the cells; the two grids' errors then
    # fell on opposite sides and the opening stuck out of its input by 0.4 mm
    from conftest import asset

    base = planner.load_mesh(asset("assemblies/industreal_gears/meshes/industreal_gear_base.obj"))
    opened = planner.opening(base, 0.002, name="base")
    first, second = opened.stats["method"].split(" then ")
    assert first == second
    solid = planner.meshes.validate_solid(base)
    assert opened.mesh.volume < solid.volume
    # the ball's grown stage there overlaps itself: both stages are done by the cells
    planner.meshes.validate_solid(opened.mesh, name="opened")


def test_a_bound_not_below_the_radius_is_warned_of(caplog):
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    with caplog.at_level("WARNING", logger="planner.offsets"):
        planner.offset(box, 0.001, eps=0.05, method="cells")
    assert "is not below the radius" in caplog.text and "use eps below" in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING", logger="planner.offsets"):
        planner.offset(box, 0.2, eps=0.05, method="cells")
    assert "is not below the radius" not in caplog.text


def _open_box() -> trimesh.Trimesh:
    """A unit cube without its top: five squares, ten triangles, an open triangle soup."""
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    top = box.face_normals[:, 2] > 0.5
    return trimesh.Trimesh(box.vertices, box.faces[~top], process=False)


def test_a_lone_triangle_grows_into_its_parallel_body():
    """Steiner's formula for a flat convex set of area A and perimeter L: 2 A r + π L r² / 2
    + 4/3 π r³; and every output point lies within the bound of distance r from it."""
    from planner.meshes.closest import mesh_distance

    triangle = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0.3, 0.8, 0.1]], [[0, 1, 2]],
                               process=False)
    r = 0.2
    result = planner.offset(triangle, r, eps=0.01, kind="surface")
    assert (result.stats["kind"], result.stats["method"]) == ("surface", "cells")
    assert result.mesh.is_watertight and result.mesh.is_winding_consistent
    assert result.stats["inner_shells"] == 0  # no cavity: nothing said
    area, perimeter = float(triangle.area), float(np.sum(np.linalg.norm(
        triangle.vertices - np.roll(triangle.vertices, 1, axis=0), axis=1)))
    exact = 2 * area * r + 0.5 * math.pi * perimeter * r * r + 4 / 3 * math.pi * r ** 3
    assert abs(result.mesh.volume - exact) <= _volume_slack(result, float(result.mesh.area))
    points = trimesh.sample.sample_surface(result.mesh, 3000, seed=1)[0]
    distance = mesh_distance(triangle.vertices, triangle.faces, points)
    assert np.all(np.abs(distance - r) <= result.error_bound)


def test_a_closed_part_grown_as_a_surface_is_said_to_be_hollow(caplog):
    """A cube taken as its triangles and grown by less than half its side: the set within
    r of its faces, with a cube-shaped cavity inside; said at warning level."""
    with caplog.at_level(logging.WARNING, logger="planner.offsets"):
        result = planner.offset(trimesh.creation.box(), 0.1, eps=0.05, kind="surface")
    assert result.stats["inner_shells"] == 1
    assert len(result.mesh.split(only_watertight=True)) == 2
    assert "1 inner shell(s), hollow where the part is thicker than 0.2" in caplog.text
    said = caplog.text[caplog.text.index("grown by"):].splitlines()[0]
    assert said.count("(") == said.count(")"), said
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="planner.offsets"):
        full = planner.offset(trimesh.creation.box(), 0.6, eps=0.1, kind="surface")
    assert full.stats["inner_shells"] == 0 and "inner shell" not in caplog.text
    # taken as a surface by auto for a hole: the reason as said, up to its advice
    caplog.clear()
    box = trimesh.creation.box().subdivide().subdivide()  # a hole 0.25 across
    holed = trimesh.Trimesh(box.vertices, box.faces[1:], process=False)
    with caplog.at_level(logging.WARNING, logger="planner.offsets"):
        planner.offset(holed, 0.1, eps=0.05, kind="auto")
    said = caplog.text[caplog.text.index("grown by"):].splitlines()[0]
    assert "being not watertight (3 boundary edges, 0 non-manifold edges); a solid" in said


def test_a_reason_is_cut_from_its_advice_outside_its_parentheses():
    """A try-out: the hollow warning cut "not watertight (168 boundary edges, 0
    non-manifold edges; 2 zero-area triangles); close the holes ..." at the first "; ",
    leaving a parenthesis open."""
    from planner.meshes.solids import without_advice

    reason = "not watertight (168 boundary edges, 0 non-manifold edges; 2 zero-area triangles)"
    assert without_advice(f"{reason}; close the holes; or repair") == reason
    assert without_advice("no advice (here; at all)") == "no advice (here; at all)"
    assert without_advice("plain; advice") == "plain"


def test_an_open_surface_is_grown_as_the_set_within_r_of_its_triangles(tmp_path):
    """An open box (as FCL sees it: triangles) grown by r: membership of random points
    agrees with the exact distance to its triangles away from the bound's band (the box's
    inside farther than r from every wall stays out); as a file it reads back closed."""
    from oracle import points_in_mesh

    from planner.meshes.closest import mesh_distance

    soup, r = _open_box(), 0.2
    result = planner.offset(soup, r, eps=0.02, kind="auto")  # not a solid: its triangles
    assert result.stats["kind"] == "surface"
    points = np.random.default_rng(3).uniform(-0.8, 0.8, size=(4000, 3))
    distance = mesh_distance(soup.vertices, soup.faces, points)
    inside = points_in_mesh(result.mesh, points)
    clear = np.abs(distance - r) > result.error_bound
    assert np.array_equal(inside[clear], distance[clear] < r)
    assert not points_in_mesh(result.mesh, [[0.0, 0.0, 0.0]])[0]  # the box's inside
    out = tmp_path / "grown.stl"
    assert main(["offset", str(_write(soup, tmp_path / "open.stl")), "-r", str(r), "-o",
                 str(out), "--eps", "0.02", "--kind", "surface"]) == 0
    read = trimesh.load(out)
    assert read.is_watertight and read.is_winding_consistent and read.volume > 0


def _write(mesh: trimesh.Trimesh, path):
    mesh.export(path)
    return path


def test_a_surface_has_no_erosion_and_a_solid_that_is_none_says_how_to_grow_it(capsys,
                                                                               tmp_path):
    from planner.errors import InvalidMeshError

    soup = _open_box()
    with pytest.raises(InvalidParameterError, match="an erosion needs a closed solid"):
        planner.offset(soup, -0.1, kind="surface")
    for method in ("hull", "ball"):
        with pytest.raises(InvalidParameterError, match="needs a closed solid"):
            planner.offset(soup, 0.1, kind="surface", method=method)
    with pytest.raises(InvalidMeshError, match="kind='surface'"):
        planner.offset(soup, 0.1)  # a solid by default
    with pytest.raises(InvalidParameterError, match="kind = 'shell'"):
        planner.offset(soup, 0.1, kind="shell")
    path = _write(soup, tmp_path / "open.stl")
    assert main(["offset", str(path), "-r", "0.1", "-o", str(tmp_path / "x.stl")]) == 2
    assert "--kind surface" in capsys.readouterr().err
    assert not (tmp_path / "x.stl").exists()
    # its triangles grown and eroded by as much are the triangles, of no thickness
    for how in (planner.closing, planner.opening):
        with pytest.raises(InvalidParameterError, match="or closing needs a closed solid"):
            how(soup, 0.1, eps=0.05, kind="surface")
        # a closed box taken for its triangles: the message says it was asked to be
        with pytest.raises(InvalidParameterError, match=r"\(kind 'surface' asked for\)"):
            how(trimesh.creation.box(), 0.1, eps=0.05, kind="surface")


def test_a_part_far_from_the_origin_reads_back_as_written(tmp_path):
    """A sphere at x = 3000 grown by the cells: float32 cannot tell apart what lies a
    millionth of a cell apart there, so such vertices are collapsed or moved apart, by
    far less than a cell, and the STL reads back with every vertex its own and the same
    topology."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    results = []
    for shift in (0.0, 3000.0):
        moved = sphere.copy()
        moved.apply_translation([shift, 0.0, 0.0])
        result = planner.offset(moved, 0.2, eps=0.05, method="cells")
        path = tmp_path / f"grown{int(shift)}.stl"
        result.mesh.export(path)
        back = trimesh.load(path)
        assert back.is_watertight and back.is_winding_consistent
        assert len(back.vertices) == len(result.mesh.vertices)
        assert back.euler_number == result.mesh.euler_number == 2
        assert result.stats["sheets_apart"] <= 0.05 * result.stats["h"]
        results.append(result)
    assert results[1].error_bound <= 1.05 * results[0].error_bound


def test_repair_says_what_it_changed(capsys, tmp_path):
    soup = _open_box()
    result = planner.offset(soup, 0.1, eps=0.05, repair=True)
    assert result.stats["kind"] == "solid" and result.stats["changes"].get("filled_holes") == 1
    path = _write(soup, tmp_path / "open.stl")
    assert main(["offset", str(path), "-r", "0.1", "--eps", "0.05", "--repair", "-o",
                 str(tmp_path / "grown.stl")]) == 0
    said = capsys.readouterr().out  # (an STL's corners are welded too)
    assert "made a solid by: " in said and "filled_holes 1" in said
    assert main(["offset", str(path), "-r", "0.1", "--kind", "surface", "--repair", "-o",
                 str(tmp_path / "x.stl")]) == 2
    assert "repair" in capsys.readouterr().err


def _finned() -> trimesh.Trimesh:
    """A unit box with a fin 0.1 thin sticking out along x (a non-convex solid)."""
    body = trimesh.creation.box([1.0, 1.0, 1.0])
    fin = trimesh.creation.box([0.7, 0.1, 0.6])
    fin.apply_translation([0.7, 0.0, 0.0])
    return trimesh.boolean.union([body, fin], engine="manifold")


@pytest.mark.parametrize("how", [planner.opening, planner.closing])
def test_a_morphologys_default_eps_keeps_each_stage_bound_below_the_radius(how, caplog):
    # r = 0.005 is below the default eps (0.5% of the ~1.8 diagonal, 0.009): each stage's
    # bound would not be below r (the stage need not lie on the right side of its input)
    finned = _finned()
    with caplog.at_level("WARNING", logger="planner.offsets"):
        result = how(finned, 0.005)
    assert all(bound < 0.005 for bound in result.stats["stage_bounds"])
    assert result.eps <= planner.offsets.OFFSET_EPS_SHARE * 0.005
    assert "is not below the radius" not in caplog.text


@pytest.mark.parametrize("how", [planner.opening, planner.closing])
def test_a_morphologys_eps_too_coarse_for_its_radius_is_refused_naming_the_eps(how):
    with pytest.raises(InvalidParameterError, match=r"eps = 0\.02: .* first stage .* not below "
                       r"the radius 0\.005.*use eps below 0\.00\d"):
        how(_finned(), 0.005, eps=0.02)


def test_a_closings_second_stage_refusing_the_first_stages_surface_is_minkplans_fault(
        monkeypatch):
    """The first stage's surface is minkplan's own: a refusal of it as a solid (the
    IndustReal gear base grown by 1 mm by the ball at eps 5e-4 had one triangle facing into
    it) is a GeometryError asking for a report, not advice to fix an input mesh."""
    from planner.errors import InvalidMeshError

    offset = planner.offsets._offset_unwarned

    def refusing(mesh, r, **options):
        if options["name"].endswith("(grown)"):
            raise InvalidMeshError(f"mesh {options['name']!r}: surface overlaps itself (1 "
                                   f"pairs); typically polygons triangulated wrongly")
        return offset(mesh, r, **options)

    monkeypatch.setattr(planner.offsets, "_offset_unwarned", refusing)
    with pytest.raises(GeometryError, match=r"first stage \(ball at eps .*\) made a surface "
                       r"its second stage cannot take as a solid \(surface overlaps itself "
                       r"\(1 pairs\)\); a fault of minkplan's") as info:
        planner.closing(_finned(), 0.05, name="fin", method="ball")
    assert "triangulated" not in str(info.value)


@pytest.mark.parametrize("method", ["ball", "cells"])
def test_a_stage_refusing_minkplans_own_surface_exits_3_with_advice_that_fits(
        monkeypatch, tmp_path, capsys, method):
    """A try-out: such a refusal was exit 2 (bad input), raised a private class, and after
    --method cells advised --method cells. It is a GeometryError (exit 3, a fault of
    minkplan's), and another method is advised only after one that was not the cells."""
    from planner.errors import InvalidMeshError

    offset = planner.offsets._offset_unwarned

    def refusing(mesh, r, **options):
        if options["name"].endswith("(grown)"):
            raise InvalidMeshError(f"mesh {options['name']!r}: 1 of its faces face into it")
        return offset(mesh, r, **options)

    monkeypatch.setattr(planner.offsets, "_offset_unwarned", refusing)
    with pytest.raises(GeometryError) as info:
        planner.closing(_finned(), 0.05, name="fin", method=method, eps=0.02)
    assert type(info.value) is GeometryError
    assert ("--method cells" in str(info.value)) == (method == "ball")
    part = tmp_path / "fin.obj"
    _finned().export(part)
    code = main(["offset", str(part), "-r", "0.05", "--closing", "--method", method,
                 "--eps", "0.02", "-o", str(tmp_path / "closed.obj"), "--no-progress"])
    said = capsys.readouterr().err
    assert code == 3 and said.count("\n") == 1 and "a fault of minkplan's" in said
    assert not (tmp_path / "closed.obj").exists()


def test_auto_closes_by_the_cells_when_the_balls_surface_is_refused(monkeypatch, caplog):
    """With method auto, a first stage whose surface its second stage refuses (the ball's
    on IndustReal's gear base at eps 5e-4: one triangle facing into the solid) is done
    again by the cells, with a warning saying why."""
    from planner.errors import InvalidMeshError

    offset = planner.offsets._offset_unwarned

    def refusing_the_balls(mesh, r, **options):
        if options["name"].endswith("(grown)") and options["method"] == "ball":
            raise InvalidMeshError(f"mesh {options['name']!r}: 1 of its faces face into the "
                                   f"solid")
        return offset(mesh, r, **options)

    monkeypatch.setattr(planner.offsets, "_offset_unwarned", refusing_the_balls)
    with caplog.at_level("WARNING", logger="planner.offsets"):
        closed = planner.closing(_finned(), 0.05, name="fin")
    assert closed.stats["method"] == "cells then cells"
    assert "a fault of minkplan's" in caplog.text and "again by the cells" in caplog.text
    assert closed.mesh.is_watertight and closed.mesh.volume >= _finned().volume


def test_the_offset_command_takes_an_eps_below_the_radius(tmp_path, capsys, caplog):
    """A plain erosion too: by default at an eps whose bound is below the radius; a given
    --eps too coarse for it is taken, with a warning saying which eps would do."""
    import re

    part = tmp_path / "finned.stl"
    _finned().export(part)
    out = tmp_path / "eroded.stl"
    assert main(["offset", str(part), "-r", "-0.005", "-o", str(out), "--no-progress"]) == 0
    bound = float(re.search(r"error bound ([\d.e-]+)", capsys.readouterr().out).group(1))
    assert bound < 0.005
    out.unlink()
    with caplog.at_level("WARNING", logger="planner.offsets"):
        assert main(["offset", str(part), "-r", "-0.005", "--eps", "0.02", "-o", str(out),
                     "--no-progress"]) == 0
    assert "is not below the radius" in caplog.text and "use eps below" in caplog.text


def test_a_stage_retried_at_a_finer_eps_is_not_warned_of(monkeypatch, caplog):
    """A stage whose bound at the default eps reaches the radius is done again finer, and
    only the log's info line says so: no warning that its result means nothing (that is
    for an eps the user gave)."""
    box = trimesh.creation.box([1.0, 1.0, 1.0])
    monkeypatch.setattr(planner.offsets, "_stage_eps", lambda solid, radius: 3.0 * abs(radius))
    with caplog.at_level("INFO", logger="planner.offsets"):
        closed = planner.closing(box, 0.05, method="cells")
    assert all(bound < 0.05 for bound in closed.stats["stage_bounds"])
    assert "again at eps" in caplog.text
    assert not [r for r in caplog.records if r.levelname == "WARNING"], caplog.text


@pytest.mark.assets
def test_the_gear_bases_ball_surface_is_a_clean_solid(caplog):
    """IndustReal's gear base grown by 1 mm at eps 5e-4: the ball's sum had one triangle
    "with the solid in front of it": a needle whose corners lie on a line up to the
    rounding of their coordinates, its normal noise. Such a face bounds nothing and has no
    front now; ``auto`` keeps the ball's surface (it took the cells: 4 s and 59k
    triangles where the ball takes 1 s and 21k). (The fall-back itself is tested with a
    fault made up.)"""
    from conftest import asset

    base = planner.load_mesh(asset("assemblies/industreal_gears/meshes/"
                                   "industreal_gear_base.obj"))
    with caplog.at_level("WARNING", logger="planner.offsets"):
        grown = planner.offset(base, 0.001, eps=0.0005)
    assert grown.stats["method"] == "ball" and "no clean solid" not in caplog.text
    checked = planner.meshes.validate_solid(grown.mesh, name="grown")
    assert not checked.metadata.get(planner.meshes.solids.FACES_INSIDE)
    _assert_within_bound_both_ways(base, 0.001, grown)


def test_a_cad_gears_offset_by_the_cells_keeps_its_crease_refinement_and_is_a_clean_solid():
    """IndustReal's small gear (20k triangles) grown by 1 mm at eps 1 mm: the offsets of
    neighbouring teeth meet in sharp concave creases (their normals turn by 70 to 117
    degrees), where marching tetrahedra's chords cut the valleys off by half the bound.
    Triangles that sag there are split where the creases run; but some splits passed the
    surface through itself (a try-out found the result no clean solid: 21 faces with the
    inside in front, winding number -1). Each round of the refinement now looks for new
    triangles that cross another and gives those splits up (or splits at the edge's
    midpoint instead of its crease point): the refinement is kept (not undone as no
    solid), the surface is a clean solid, and its error (1.7e-4 measured one way) is below
    what the unrefined chords leave (2.8e-4), a sixth of the bound."""
    from conftest import asset
    from oracle import surface_distance

    from planner.meshes.kinds import classify

    gear = classify(planner.load_mesh(asset(
        "assemblies/industreal_gears/meshes/industreal_gear_small.obj")),
        name="gear", kind="solid").mesh
    r = 0.001
    result = planner.offset(gear, r, eps=0.001, method="cells")
    out = result.mesh
    assert result.stats["creases_unrefined"] is None
    assert result.stats["sag_splits"] > 1000
    validate_solid(out, name="grown gear")
    probes = np.vstack([out.vertices, trimesh.sample.sample_surface(out, 20000, seed=0)[0]])
    error = np.abs(surface_distance(gear, probes) - r)
    assert error.max() <= 2.5e-4 < result.error_bound


def test_a_cells_surface_the_crease_refinement_left_no_solid_is_made_again_without_it(
        monkeypatch, caplog):
    """The last guard behind the refinement's own fold and crossing checks: when the
    winding check refuses the refined surface of a solid (here made to refuse the first
    surface it sees), the offset is made again without the refinement, says why in
    ``stats["creases_unrefined"]``, and is a clean solid."""
    from planner import _minkowski_core

    real_core, real_check = _minkowski_core.offset_surface, planner.offsets._checked_solid
    asked, checked = [], []

    def offset_surface(checked_mesh, radius, step, **kwargs):
        # (said to have split, so that the check runs; the unrefined stats say so too)
        asked.append(kwargs["refine_creases"])
        return {**real_core(checked_mesh, radius, step, **kwargs), "sag_splits": 1}

    def refusing_the_first(mesh, name):
        checked.append(len(mesh.faces))
        return (None, "closed but not a solid (made up)") if len(checked) == 1 else \
            real_check(mesh, name)

    monkeypatch.setattr(_minkowski_core, "offset_surface", offset_surface)
    monkeypatch.setattr(planner.offsets, "_checked_solid", refusing_the_first)
    with caplog.at_level(logging.INFO, logger="planner"):
        result = planner.offset(box(), 0.1, eps=0.02, method="cells")
    assert asked == [True, False]
    assert result.stats["creases_unrefined"] == "closed but not a solid (made up)"
    assert "made again without it" in caplog.text
    validate_solid(result.mesh, name="grown box")
    # Steiner's formula for a unit cube grown by 0.1: 1 + 0.6 + 0.03 pi + 0.004/3 pi
    assert result.mesh.volume == pytest.approx(1.6 + 0.1 * math.pi * (0.3 + 0.04 / 3),
                                               rel=0.01)


def test_a_cad_gears_opening_takes_its_eroded_surface_whose_sharp_tips_fold_nothing():
    """IndustReal's small gear opened by 1 mm at eps 0.4 mm: its eroded teeth end in
    ridges sharper than a few degrees, where the cells' crease refinement used to put a
    split point past a neighbouring edge and fold a triangle over (34 pairs of faces facing
    opposite ways, overlapping in one plane); the second stage then refused the erosion as
    no clean solid, and the opening failed. A split that folds is given up (the chord stays
    as the extraction made it, inside the bound): the erosion is a clean solid whose points
    lie within its bound of the gear's surface distance r, and the opening is made."""
    from conftest import asset
    from oracle import surface_distance

    gear = planner.load_mesh(asset("assemblies/industreal_gears/meshes/"
                                   "industreal_gear_small.obj"))
    r, eps = 0.001, 4e-4
    eroded = planner.offset(gear, -r, eps=eps, method="cells")
    assert eroded.stats["sag_folds_refused"] > 0 and eroded.stats["sag_splits"] > 0
    planner.meshes.validate_solid(eroded.mesh, name="eroded")
    out = eroded.mesh
    probes = np.vstack([out.vertices, trimesh.sample.sample_surface(out, 20000, seed=0)[0]])
    # inside the gear, the distance to its surface
    assert np.abs(surface_distance(gear, probes) - r).max() <= eroded.error_bound
    opened = planner.opening(gear, r, eps=eps)
    assert opened.stats["method"] == "cells then cells"
    assert 0 < opened.mesh.volume < gear.volume


def test_a_convex_solids_closing_is_itself_where_two_stages_agree(tmp_path, capsys):
    """A convex solid is its own closing (it lies in every half-space holding it): the
    closing returns it, bound by its rounding, where the two stages by the cells give a
    surface within their bounds of it."""
    box = trimesh.creation.box([1.0, 0.6, 0.4])
    closed = planner.closing(box, 0.1)
    assert closed.stats["convex"] == CLOSED and "stage_bounds" not in closed.stats
    assert closed.error_bound < 1e-8
    np.testing.assert_array_equal(np.sort(closed.mesh.vertices, axis=0),
                                  np.sort(box.vertices, axis=0))
    staged = planner.closing(box, 0.1, method="cells", eps=0.01)
    reach = sum(staged.stats["stage_bounds"])
    assert np.max(np.abs(mesh_distance(box.vertices, box.faces, staged.mesh.vertices))) <= reach
    part, out = tmp_path / "box.stl", tmp_path / "closed.stl"
    box.export(part)
    assert main(["offset", str(part), "-r", "0.1", "--closing", "-o", str(out),
                 "--no-progress"]) == 0
    assert f"(hull: {CLOSED})" in capsys.readouterr().out
    assert trimesh.load(out).volume == pytest.approx(box.volume, rel=1e-6)


def test_a_solid_short_of_convex_is_closed_in_two_stages():
    """The finned box is not convex: its closing fills the corners along the fin."""
    closed = planner.closing(_finned(), 0.12, eps=0.05)
    assert "convex" not in closed.stats and len(closed.stats["stage_bounds"]) == 2
    assert closed.mesh.volume > _finned().volume


@pytest.mark.assets
def test_a_part_convex_up_to_its_files_rounding_closes_within_its_hulls_gap():
    """The Factory round peg (float32 CAD, convex up to rounding) is its own closing
    within the gap between it and its hull (measured here on the hull's facets): the two
    stages took minutes at eps 2e-5."""
    from conftest import asset

    peg = planner.load_mesh(asset(
        "assemblies/factory_round_peg_8mm/meshes/factory_round_peg_8mm_loose.obj"))
    closed = planner.closing(peg, 0.0005, eps=2e-5)
    assert closed.stats["convex"] == CLOSED and closed.error_bound <= 2e-5
    assert len(closed.mesh.faces) == len(peg.faces)
    hull = peg.convex_hull  # its points farthest from the peg: on facets over dents
    on_hull = np.vstack([hull.triangles_center, trimesh.sample.sample_surface(hull, 20000,
                                                                              seed=0)[0]])
    gap = np.max(mesh_distance(peg.vertices, peg.faces, on_hull))
    assert 0.0 < gap <= closed.error_bound


def test_a_finely_faceted_cylinder_is_grown_from_fewer_corners_within_the_bound(monkeypatch):
    """A 300-sided prism grown by 0.05 at eps 0.01: its sides are finer than the
    tolerance, so the hull of fewer corners is grown, its gap in the bound (a third of the
    triangles). Both ways against exact distances: output points to the prism, and the
    exact offset's support points (the farthest corner along a direction, moved r along
    it) to the output."""
    from planner import offsets_convex

    prism, r, eps = trimesh.creation.cylinder(radius=1.0, height=2.0, sections=300), 0.05, 0.01
    grown = planner.offset(prism, r, eps=eps)
    assert grown.stats["convex"] == ROUNDED and grown.error_bound <= eps
    assert grown.stats["round_corners"] < len(prism.vertices) / 2
    assert 0 < grown.stats["round_thinned"] < eps
    _assert_within_bound_both_ways(prism, r, grown)
    directions = trimesh.sample.sample_surface_sphere(4000, seed=6)
    support = prism.vertices[np.argmax(prism.vertices @ directions.T, axis=0)] + r * directions
    assert np.all(mesh_distance(grown.mesh.vertices, grown.mesh.faces, support)
                  <= grown.error_bound + 1e-12)
    monkeypatch.setattr(offsets_convex, "THIN_SHARE", 0.0)
    every_corner = planner.offset(prism, r, eps=eps)
    assert every_corner.stats["round_thinned"] == 0.0
    assert len(grown.mesh.faces) < 0.5 * len(every_corner.mesh.faces)


def test_a_convex_solids_opening_is_bound_by_its_stages_sum(tmp_path, capsys):
    """A box opened by r is the box shrunk by r grown by r (its edges rounded): both
    stages by the hull, so the bound is their sum, checked against the exact distance to
    the shrunk box, both ways (the exact opening's support points to the output)."""
    size, r = np.array([1.0, 0.6, 0.4]), 0.1
    opened = planner.opening(trimesh.creation.box(size), r)
    assert opened.stats["method"] == "hull then hull"
    assert opened.error_bound == pytest.approx(sum(opened.stats["stage_bounds"]), rel=1e-12)
    assert 0 < opened.error_bound < r
    half = size / 2 - r  # the shrunk box, centred at the origin

    def to_shrunk(points):
        return np.linalg.norm(np.maximum(np.abs(points) - half, 0.0), axis=1)

    points = np.vstack([opened.mesh.vertices,
                        trimesh.sample.sample_surface(opened.mesh, 4000, seed=7)[0]])
    assert np.all(np.abs(to_shrunk(points) - r) <= opened.error_bound)
    directions = trimesh.sample.sample_surface_sphere(4000, seed=8)
    support = np.sign(directions) * half + r * directions
    assert np.all(mesh_distance(opened.mesh.vertices, opened.mesh.faces, support)
                  <= opened.error_bound + 1e-12)
    part, out = tmp_path / "box.stl", tmp_path / "opened.stl"
    trimesh.creation.box(size).export(part)
    assert main(["offset", str(part), "-r", str(r), "--opening", "-o", str(out),
                 "--no-progress"]) == 0
    assert f"error bound {opened.error_bound:.4g} (hull then hull)" in capsys.readouterr().out


@pytest.mark.parametrize("r", [0.01, -0.01])
def test_a_convex_part_far_from_the_origin_takes_the_hull_path_within_its_bound(r):
    """A 0.1 sphere at x = 1000: points are merged within 1e-6 of the size and distance
    from the origin only up to a share of eps (1e-6 of 1000 alone is ten times eps); the
    result is where the same sphere at the origin's is, within the bound."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.1)
    far = sphere.copy()
    far.apply_translation([1000.0, 0.0, 0.0])
    done = planner.offset(far, r, eps=1e-4, method="hull")
    assert done.stats["convex"] and done.error_bound <= 1e-4
    points = np.vstack([done.mesh.vertices,
                        trimesh.sample.sample_surface(done.mesh, 3000, seed=9)[0]])
    distance = mesh_distance(far.vertices, far.faces, points)
    assert np.all(np.abs(distance - abs(r)) <= done.error_bound + 1e-9)


def test_a_convex_part_with_thousands_of_facets_takes_the_hull_path():
    """2,000 points on a unit sphere, their hull (about 4,000 facets, each its own plane):
    the depth test measures triangles against planes in blocks, where a cap on their
    product (4 M) sent it to the ball, whose surface had folded slivers."""
    rng = np.random.default_rng(11)
    points = rng.normal(size=(2000, 3))
    hull = trimesh.convex.convex_hull(points / np.linalg.norm(points, axis=1)[:, None])
    assert len(hull.faces) * len(hull.faces) > 4_000_000
    grown = planner.offset(hull, 0.05, eps=0.01, method="hull")
    assert grown.stats["convex"] == ROUNDED and grown.error_bound <= 0.01
    _assert_within_bound_both_ways(hull, 0.05, grown)


def test_a_huge_radius_is_refused_without_numpy_warnings():
    """r = 1e300: the result's diagonal is measured without overflow, so the one-line
    refusal comes alone (numpy's overflow warnings came first)."""
    import warnings

    box = trimesh.creation.box((1.0, 1.0, 1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for how in (planner.offset, planner.closing):
            with pytest.raises(InvalidParameterError, match=r"more than 1e\+06 times"):
                how(box, 1e300)


def test_an_eps_finer_than_the_coordinates_is_refused_naming_the_floor():
    """Below 1e-9 of the size no method certifies an offset (the hull path's rounding
    allowance; the grids stop near 1e-6): the refusal says so and names the least eps,
    which then gives the exact eroded box (it named the octree's cells)."""
    box = trimesh.creation.box((1.0, 0.6, 0.4))
    for how, r in ((planner.offset, 0.1), (planner.offset, -0.1), (planner.closing, 0.1)):
        refused = r"eps = 1e-09: below 1\.\d+e-09, 1e-9 of .* use eps >= 1\.\d+e-09"
        with pytest.raises(InvalidParameterError, match=refused):
            how(box, r, eps=1e-9)
    eroded = planner.offset(box, -0.1, eps=1e-8)
    assert eroded.error_bound <= 1e-8 and len(eroded.mesh.faces) == 12
    np.testing.assert_allclose(eroded.mesh.bounds, [[-0.4, -0.2, -0.1], [0.4, 0.2, 0.1]],
                               atol=1e-12)


def test_an_openings_second_ball_stage_that_is_no_clean_solid_goes_to_the_cells_under_auto(
        monkeypatch, caplog):
    """Under auto an opening grows by the ball when it eroded by the ball; a ball surface
    that is no clean solid there has both stages done again by the cells (it was
    returned, with a warning that 'cells' gives one; the cells after the ball leave each
    stage's error in full, on opposite sides). Asked for, the ball is kept."""
    from shapes import l_bracket

    solid_fault = planner.offsets._solid_fault

    def faulting_grown_stage(mesh, name):
        return "a fault made up" if name.endswith("(eroded)") else solid_fault(mesh, name)

    monkeypatch.setattr(planner.offsets, "_solid_fault", faulting_grown_stage)
    with caplog.at_level("WARNING", logger="planner.offsets"):
        opened = planner.opening(l_bracket(), 0.2, eps=0.05, name="bracket")
    assert opened.stats["method"] == "cells then cells"
    assert "(a fault made up), a fault of minkplan's; an opening again by the cells" \
        in caplog.text
    assert "gives one" not in caplog.text
    assert opened.mesh.is_watertight
    caplog.clear()
    with caplog.at_level("WARNING", logger="planner.offsets"):
        by_ball = planner.opening(l_bracket(), 0.2, eps=0.05, name="bracket", method="ball")
    assert by_ball.stats["method"] == "ball then ball" and "gives one" in caplog.text


def test_a_float32_toruss_opening_by_the_ball_is_a_clean_solid(tmp_path, caplog):
    """A try-out: trimesh's torus (major 1, minor 0.3) saved as an STL (float32) and opened
    by 0.1. Where a plane-resolved cell's sharp edge ran into a sampled cell, the gap left in
    the cell face was a ring crossing itself, and its fill held a triangle turned over onto
    its neighbour (34 such pairs): the ball's surface was refused, and auto took 52 s and
    631k triangles by the cells. Such rings are now left open and sampled around."""
    part = tmp_path / "torus.stl"
    trimesh.creation.torus(major_radius=1.0, minor_radius=0.3).export(part)
    torus = planner.load_mesh(part)
    with caplog.at_level("WARNING", logger="planner.offsets"):
        opened = planner.opening(torus, 0.1, method="ball")
    assert "no clean solid" not in caplog.text
    assert opened.stats["method"] == "ball then ball"
    again = validate_solid(opened.mesh, name="opened torus")
    assert again.metadata[FACES_INSIDE] == 0
    assert abs(again.volume - torus.volume) < 0.02 * torus.volume  # it is the torus


@pytest.mark.parametrize(("sections", "radii", "opening", "growth"), [
    ((64, 32), (1.0, 0.3), 0.1, 0.01),
    ((16, 8), (2.0, 0.5), 0.25, 0.05),
])
def test_folds_in_a_plane_are_unfolded_so_an_opened_torus_grows_again_by_the_ball(
        caplog, sections, radii, opening, growth):
    """Try-outs: tori opened, then grown a little. On the flat bands of their facets, the
    joined surface folded back onto itself in the plane: a sliver facing up overlapping
    slivers facing down, a few welds across. The ball's surface was refused ("coplanar
    faces facing opposite ways overlap", then "1 of its triangles face into it") and auto
    fell to the cells: for the fine torus 35 s and 640k triangles for the opening, 113 s
    and 1.8M for the growth. Each fold is now replaced by what it covers once (its outline
    split where it crosses itself first). The coarse torus's growth left a sliver's loop
    whose five corners lie on one line, fanned (3 triangles facing into the solid; the
    cells took 33 s and 370k triangles): the face across its long edge takes the corners
    instead."""
    torus = trimesh.creation.torus(*radii, major_sections=sections[0],
                                   minor_sections=sections[1])
    with caplog.at_level("WARNING", logger="planner.offsets"):
        opened = planner.opening(torus, opening)
        grown = planner.offset(opened.mesh, growth)
    assert "no clean solid" not in caplog.text
    assert opened.stats["method"] == "ball then ball"
    assert grown.stats["method"] == "ball" and grown.stats["planar_unfolded"] >= 1
    assert validate_solid(grown.mesh, name="grown").metadata[FACES_INSIDE] == 0
    _assert_within_bound_both_ways(opened.mesh, growth, grown)
    # and the exact offset's points lie within the bound of the output
    truth = _on_the_offset(opened.mesh, growth, 3000, seed=3)
    assert len(truth) > 100
    gap = mesh_distance(grown.mesh.vertices, grown.mesh.faces, truth)
    assert gap.max() <= grown.error_bound


@pytest.mark.parametrize("method", ["cells", "ball", "auto"])
def test_an_erosion_of_bars_crossing_each_other_is_refused(method):
    """An L made of two bars in one file, overlapping at a corner: no triangle has the
    solid in front of its samples, but the bars' faces cross, and parts of them lie
    inside the other bar. The cells eroded them as if every triangle were boundary: three
    boxes, 0.145 off, with a bound of 0.014 (and the ball said the complement was no
    solid). Refused, naming the crossings."""
    bars = trimesh.util.concatenate([
        trimesh.creation.box([2.0, 0.5, 0.5], trimesh.transformations.translation_matrix(
            [1.0, 0.25, 0.25])),
        trimesh.creation.box([0.5, 2.0, 0.5], trimesh.transformations.translation_matrix(
            [0.25, 1.0, 0.25]))])
    with pytest.raises(InvalidParameterError, match="cross each other inside it along .* segments"):
        planner.offset(bars, -0.1, eps=0.02, method=method)
    # grown, the union is what is offset: allowed
    assert planner.offset(bars, 0.1, eps=0.02, method="cells").mesh.is_watertight


def test_a_float32_file_is_said_to_widen_the_bound_by_its_rounding(tmp_path, capsys):
    """The bound is the float64 mesh's; an STL stores float32, which moves a box eroded
    exactly (bound 2e-9) by 1e-7: the command says what the bound is in the file."""
    import re

    part = tmp_path / "box.obj"
    trimesh.creation.box([1.0, 0.6, 0.4]).export(part)
    out = tmp_path / "eroded.stl"
    assert main(["offset", str(part), "-r", "-0.1", "-o", str(out), "--no-progress"]) == 0
    said = capsys.readouterr().out
    in_file = float(re.search(r"stores float32: the bound is ([\d.e+-]+) in the file",
                              said).group(1))
    written = trimesh.load(out)
    exact = np.array([[-0.4, -0.2, -0.1], [0.4, 0.2, 0.1]])
    moved = np.abs(written.bounds - exact).max()
    assert 1e-9 < moved <= in_file
    assert main(["offset", str(part), "-r", "-0.1", "-o", str(tmp_path / "e.obj"),
                 "--no-progress"]) == 0
    assert "stores float32" not in capsys.readouterr().out


def test_an_offset_whose_planar_cells_would_pass_the_memory_limit_is_refused():
    """An L of two 2 x 0.5 bars grown by 1 mm at the default eps needs some 5M cells, each
    holding its faces' plane polygons (8M, and 13.9 GB under a 10 GiB limit when the budget
    took 640 B a cell; cells over its faces' seams and wider than the slab are cut by
    planes now, and it takes 6.8 GB there). Under 2 GiB: refused, in one line naming the
    setting, before the cells' memory is spent."""
    from planner.errors import ResourceLimitError

    bars = trimesh.creation.box([2.0, 0.5, 0.5], trimesh.transformations.translation_matrix(
        [1.0, 0.25, 0.25])).union(trimesh.creation.box(
            [0.5, 2.0, 0.5], trimesh.transformations.translation_matrix([0.25, 1.0, 0.25])),
        engine="manifold")
    with planner.memory_limit(2), pytest.raises(ResourceLimitError, match="memory-limit") as e:
        planner.offset(bars, 0.001, method="cells")
    # how far eps may go: the default is half the radius, and the bound must stay below it
    assert "use a larger eps (now 0.0005; below the radius 0.001" in str(e.value)


def test_a_millimetre_torus_grown_by_the_cells_reads_back_closed(tmp_path):
    """A torus of 1 mm grown by 0.1 mm (the cells, 450k triangles): two vertices 3.4e-9
    apart, joined by an edge, stayed within trimesh's 1e-8 weld (the edge's collapse was
    tried keeping one end only, which would turn a triangle over, and the move apart was
    held short by thin triangles), so the file read back open. Either end may be kept now."""
    torus = trimesh.creation.torus(1.0, 0.3)
    torus.apply_scale(1e-3)
    grown = planner.offset(torus, 1e-4, method="cells", name="torus")
    out = tmp_path / "grown.obj"
    grown.mesh.export(out, digits=17)
    read = trimesh.load(out)  # welded by position, as trimesh reads every file
    assert read.is_watertight and read.is_winding_consistent
    assert len(read.vertices) == len(grown.mesh.vertices)


def _l_with_a_bulging_flank(segments: int = 24) -> trimesh.Trimesh:
    """An L-shaped prism (height 1) whose inner corner joins a flat face to a curved one,
    finely faceted (a gear's tooth root, straight along z): grown, the two meet in a crease
    sharper than a right angle along the whole height."""
    import mapbox_earcut

    t = np.linspace(0.0, 1.0, segments + 1)
    flank = np.c_[1.0 + 0.25 * np.sin(np.pi * t), 1.0 + t]
    ring = np.vstack([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], flank, [0.0, 2.0]])
    m = len(ring)
    cap = mapbox_earcut.triangulate_float64(ring, np.array([m], dtype=np.uint32)).reshape(-1, 3)
    vertices = np.vstack([np.c_[ring, np.zeros(m)], np.c_[ring, np.ones(m)]])
    sides = [[[i, (i + 1) % m, (i + 1) % m + m], [i, (i + 1) % m + m, i + m]] for i in range(m)]
    faces = np.vstack([cap[:, ::-1], cap + m, np.reshape(sides, (-1, 3))])
    return trimesh.Trimesh(vertices, faces, process=False)


def test_a_straight_crease_is_refined_before_coplanar_triangles_are_merged():
    # the chords across the crease lie in one plane along its whole length: merged first,
    # they were a few triangles too long to split, and sagged by 1.9e-3 at eps 0.02
    solid = _l_with_a_bulging_flank()
    assert solid.is_watertight and solid.is_winding_consistent and solid.volume > 0
    res = planner.offset(solid, 0.1, eps=0.02, method="cells")
    grown = trimesh.Trimesh(res.mesh.vertices, res.mesh.faces, process=False)
    points, _ = trimesh.sample.sample_surface(grown, 20000, seed=0)
    _, distance, _ = trimesh.proximity.closest_point(solid, points)
    sag = float(np.max(np.abs(distance - 0.1)))
    assert res.stats["sag_splits"] > 0
    # the refinement's target: a sixteenth of the grid's bound
    assert sag <= res.error_bound / 16, (sag, res.error_bound)


def test_a_solid_whose_float32_copy_is_no_solid_is_warned_of(tmp_path):
    """A try-out: an opening written as an STL did not load back (its float32 rounding made
    two sheets cross). Two boxes 4e-8 apart: a clean solid in float64, glued along a face
    in float32; said for .stl, not for .obj."""
    from pathlib import Path

    from planner.output import float32_fault

    lower = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    upper = trimesh.creation.box(bounds=[[0, 0, 1 + 4e-8], [1, 1, 2]])
    pair = trimesh.util.concatenate([lower, upper])
    validate_solid(pair, name="pair")  # clean as it is
    fault = float32_fault(pair, Path("pair.stl"))
    assert fault is not None and "not watertight" in fault, fault
    assert float32_fault(pair, Path("pair.obj")) is None
    assert float32_fault(lower, Path("lower.stl")) is None


def test_the_commands_warn_when_a_solid_written_in_float32_is_no_solid(tmp_path, capsys,
                                                                       caplog):
    """What ``offset`` and ``minkowski`` call after writing: the check (on the status
    line, shown here) and its one warning (logged, as every other warning), for the pair
    of boxes 4e-8 apart."""
    from planner.cli_shapes import _warn_if_float32_breaks

    lower = trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])
    upper = trimesh.creation.box(bounds=[[0, 0, 1 + 4e-8], [1, 1, 2]])
    pair = trimesh.util.concatenate([lower, upper])
    for suffix, warned in ((".stl", True), (".obj", False)):
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="planner.cli_shapes"):
            _warn_if_float32_breaks(pair, tmp_path / f"pair{suffix}", progress=True)
        err = capsys.readouterr().err
        # (an OBJ keeps every digit: nothing to check)
        assert (f"checking that pair{suffix}'s float32 coordinates keep 24 triangles"
                in err) is warned
        said = "its float32 coordinates make the solid no clean solid"
        assert (said in caplog.text) is warned, caplog.text
