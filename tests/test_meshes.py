"""Tests for planner.meshes, planner.errors and planner.tolerances."""

from __future__ import annotations

import dataclasses
import logging
import pickle

import numpy as np
import pytest
import shapes
import trimesh
from conftest import asset

from planner.errors import (
    GeometryError,
    InvalidMeshError,
    InvalidParameterError,
    MinkplanError,
    ResourceLimitError,
    ScenarioError,
)
from planner.meshes import (
    load_mesh,
    load_obj,
    mirror,
    repair_mesh,
    split_solid,
    validate_solid,
)
from planner.meshes.topology import boundary_loops, group_rows
from planner.meshes.triangulation import ear_clip
from planner.tolerances import Tolerances, scale_of, tol

PEG = "geometric_peg_in_hole_2mm"
CUBE = 0.08**3  # the 80 mm cube every peg-in-hole part is built on (metres)


def box(extents=(1.0, 2.0, 3.0), offset=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents)
    mesh.apply_translation(offset)
    return mesh


def l_prism_obj(start: int) -> str:
    """OBJ text of an L-shaped prism (area 3, height 1, volume 3) whose two caps are
    hexagons listed from corner ``start``: from corner 2 a fan is wrong."""
    outline = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # counter-clockwise
    outline = outline[start:] + outline[:start]
    lines = [f"v {x} {y} 0" for x, y in outline] + [f"v {x} {y} 1" for x, y in outline]
    n = len(outline)
    lines.append("f " + " ".join(str(i + 1) for i in reversed(range(n))))  # bottom, -z
    lines.append("f " + " ".join(str(n + i + 1) for i in range(n)))  # top, +z
    for i in range(n):
        j = (i + 1) % n
        lines.append(f"f {i + 1} {j + 1} {n + j + 1} {n + i + 1}")
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------- errors


def test_error_hierarchy_and_builtin_bases():
    assert issubclass(InvalidMeshError, MinkplanError) and issubclass(InvalidMeshError, ValueError)
    assert issubclass(InvalidParameterError, ValueError)
    assert issubclass(ResourceLimitError, MemoryError)
    assert issubclass(GeometryError, RuntimeError)
    assert issubclass(ScenarioError, ValueError)


def test_messages_are_one_line():
    error = InvalidMeshError("mesh 'a':\nnot watertight\n  fix it")
    assert str(error) == "mesh 'a': not watertight fix it"


def test_scenario_error_fields_survive_pickling():
    error = ScenarioError("robot.mesh: file not found", field="robot.mesh", line=7)
    copy = pickle.loads(pickle.dumps(error))
    assert (copy.field, copy.line, str(copy)) == ("robot.mesh", 7, "robot.mesh: file not found")
    assert ScenarioError("x").field is None and ScenarioError("x").line is None


# ------------------------------------------------------------------- tolerances


def test_scale_of_mesh_bounds_and_points():
    mesh = box((3.0, 4.0, 12.0))
    assert scale_of(mesh) == pytest.approx(13.0)
    assert scale_of(mesh.bounds) == pytest.approx(13.0)
    assert scale_of(mesh.vertices) == pytest.approx(13.0)
    with pytest.raises(InvalidParameterError):
        scale_of(np.array([[0.0, 0.0, np.nan], [1.0, 1.0, 1.0]]))


def test_tolerances_frozen_and_checked():
    with pytest.raises(dataclasses.FrozenInstanceError):
        tol.eps_rel = 0.1  # type: ignore[misc]
    assert dataclasses.replace(tol, eps_rel=0.01).eps_rel == 0.01
    with pytest.raises(InvalidParameterError, match="eps_rel"):
        Tolerances(eps_rel=0.0)
    with pytest.raises(InvalidParameterError, match="max_cells"):
        Tolerances(max_cells=0)


# ------------------------------------------------------------------- validation


def test_valid_box_passes_and_input_is_untouched():
    mesh = box()
    before = mesh.vertices.copy()
    solid = validate_solid(mesh, name="box")
    assert solid is not mesh
    assert solid.is_watertight and solid.is_winding_consistent
    assert solid.volume == pytest.approx(6.0)
    assert solid.vertices.dtype == np.float64
    assert solid.metadata["name"] == "box"
    np.testing.assert_array_equal(mesh.vertices, before)


def test_triangle_soup_is_merged():
    mesh = box()
    soup = trimesh.Trimesh(mesh.triangles.reshape(-1, 3), np.arange(36).reshape(-1, 3),
                           process=False)
    solid = validate_solid(soup, name="soup")
    assert len(solid.vertices) == 8
    assert solid.volume == pytest.approx(6.0)


def test_harmless_degenerate_face_is_dropped_harmful_one_reported():
    mesh = box()
    a, b = mesh.edges_unique[0]
    vertices = np.vstack([mesh.vertices, (mesh.vertices[a] + mesh.vertices[b]) / 2])
    sliver = [a, b, len(mesh.vertices)]  # zero area, makes edge a-b non-manifold
    with_sliver = trimesh.Trimesh(vertices, np.vstack([mesh.faces, sliver]), process=False)
    solid = validate_solid(with_sliver, name="sliver")
    assert len(solid.faces) == 12 and solid.volume == pytest.approx(6.0)
    # with a box face missing as well, the mesh is open whatever is dropped
    open_faces = np.vstack([mesh.faces[1:], sliver])
    with pytest.raises(InvalidMeshError, match=r"mesh 'sliver'.*not watertight"):
        validate_solid(trimesh.Trimesh(vertices, open_faces, process=False), name="sliver")


def test_empty_mesh_rejected():
    with pytest.raises(InvalidMeshError, match=r"mesh 'nothing'.*empty"):
        validate_solid(trimesh.Trimesh(), name="nothing")


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_nonfinite_vertex_rejected(value):
    mesh = box()
    vertices = mesh.vertices.copy()
    vertices[3, 1] = value
    bad = trimesh.Trimesh(vertices, mesh.faces, process=False)
    with pytest.raises(InvalidMeshError, match=r"mesh 'robot'.*NaN or infinite.*vertex 3"):
        validate_solid(bad, name="robot")


def test_coordinates_too_large_to_compute_with_are_refused_unless_unused():
    mesh = box()
    vertices = mesh.vertices.copy()
    vertices[3, 1] = 1e300
    with pytest.raises(InvalidMeshError, match=r"mesh 'robot': coordinates up to 1e\+300 "
                                               r"exceed 1e\+30.*rescale"):
        validate_solid(trimesh.Trimesh(vertices, mesh.faces, process=False), name="robot")
    with pytest.raises(InvalidMeshError, match="exceed 1e"):
        repair_mesh(trimesh.Trimesh(vertices, mesh.faces, process=False))
    unused = np.vstack([mesh.vertices, [[1e300, 0.0, 0.0]]])
    solid = validate_solid(trimesh.Trimesh(unused, mesh.faces, process=False))
    assert len(solid.vertices) == len(mesh.vertices)


def test_open_box_rejected_with_edge_count():
    mesh = box()
    # drop the two triangles of one side: a square hole with 4 boundary edges
    side = np.flatnonzero(np.isclose(mesh.face_normals[:, 0], 1.0))
    assert len(side) == 2
    open_box = trimesh.Trimesh(mesh.vertices, np.delete(mesh.faces, side, axis=0),
                               process=False)
    with pytest.raises(InvalidMeshError, match=r"mesh 'lid'.*not watertight.*4 boundary edges"):
        validate_solid(open_box, name="lid")


def test_zero_volume_flat_mesh_rejected():
    # a closed but flat surface: a square with both sides
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]])
    with pytest.raises(InvalidMeshError, match=r"mesh 'sheet'.*zero volume"):
        validate_solid(trimesh.Trimesh(vertices, faces, process=False), name="sheet")


def test_flat_closed_tetrahedron_rejected():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0]], dtype=float)
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    with pytest.raises(InvalidMeshError, match=r"mesh 'flat'.*zero volume"):
        validate_solid(trimesh.Trimesh(vertices, faces, process=False), name="flat")


def test_inside_out_cube_is_flipped_and_logged(caplog):
    mesh = box()
    mesh.invert()
    assert mesh.volume < 0
    with caplog.at_level(logging.INFO, logger="planner.meshes"):
        solid = validate_solid(mesh, name="inverted")
    assert solid.volume == pytest.approx(6.0)
    assert any("inside out" in r.getMessage() for r in caplog.records)


def test_inconsistent_winding_is_fixed():
    mesh = box()
    faces = mesh.faces.copy()
    faces[[0, 5, 7]] = faces[[0, 5, 7]][:, ::-1]
    solid = validate_solid(trimesh.Trimesh(mesh.vertices, faces, process=False), name="w")
    assert solid.is_winding_consistent
    assert solid.volume == pytest.approx(6.0)


def test_hollow_box_keeps_its_cavity_even_when_all_inside_out():
    inner = box((1, 1, 1))
    inner.invert()
    hollow = trimesh.util.concatenate([box((2, 2, 2)), inner])
    solid = validate_solid(hollow, name="hollow")
    assert solid.volume == pytest.approx(7.0)
    assert len(split_solid(solid)) == 1  # one body: the shell with its cavity
    everything_inverted = hollow.copy()
    everything_inverted.invert()
    assert validate_solid(everything_inverted).volume == pytest.approx(7.0)


def test_two_bodies_split():
    pair = trimesh.util.concatenate([box(), box(offset=(5, 0, 0))])
    bodies = split_solid(validate_solid(pair))
    assert [round(b.volume, 9) for b in bodies] == [6.0, 6.0]


def test_boxes_touching_along_an_edge_are_a_valid_union():
    # after vertex merging the shared edge has four faces; each box is closed on its own
    pair = trimesh.util.concatenate([box((1, 1, 1)), box((1, 1, 1), offset=(1, 1, 0))])
    solid = validate_solid(pair, name="touching")
    assert solid.is_watertight
    assert solid.volume == pytest.approx(2.0)
    assert len(split_solid(solid)) == 2


def test_misfanned_polygon_is_rejected():
    # L prism whose hexagon caps were fanned from a corner that cannot see them all:
    # topologically closed, right volume, but the caps overlap themselves
    bad = shapes.misfanned_l_prism()
    assert bad.is_watertight and bad.volume == pytest.approx(3.0)  # nothing else notices
    with pytest.raises(InvalidMeshError, match=r"mesh 'L'.*overlaps itself"):
        validate_solid(bad, name="L")
    with pytest.raises(InvalidMeshError, match="overlaps itself"):
        repair_mesh(bad, name="L")


def test_validate_rejects_non_mesh():
    with pytest.raises(InvalidMeshError, match="expected a trimesh.Trimesh"):
        validate_solid(np.zeros((3, 3)), name="array")


# ---------------------------------------------------------------------- loading


def test_missing_file(tmp_path):
    path = tmp_path / "nope.stl"
    with pytest.raises(InvalidMeshError, match=r"nope\.stl.*not found"):
        load_mesh(path)
    with pytest.raises(InvalidMeshError, match=r"mesh 'robot' \(file .*nope\.stl'\)"):
        load_mesh(path, name="robot")


@pytest.mark.parametrize(
    ("filename", "content"),
    [
        ("garbage.stl", bytes(range(256)) * 3),
        ("garbage.obj", bytes(range(128, 256)) * 4),
        ("garbage.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n"),
        ("garbage.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n"),
        ("garbage.glb", b"glTF" + bytes(40)),
        ("empty.stl", b""),
        ("text.obj", b"v 1 2\nf 1 2 3\n"),
        ("noface.obj", b"v 0 0 0\nv 1 0 0\n"),
        ("badindex.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
    ],
)
def test_corrupt_files(tmp_path, filename, content):
    path = tmp_path / filename
    path.write_bytes(content)
    with pytest.raises(InvalidMeshError, match=filename.replace(".", r"\.")) as info:
        load_mesh(path)
    assert "\n" not in str(info.value)


def test_truncated_binary_stl(tmp_path):
    path = tmp_path / "box.stl"
    box().export(path)
    assert validate_solid(load_mesh(path)).volume == pytest.approx(6.0)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InvalidMeshError, match=r"box\.stl.*truncated"):
        load_mesh(path)


@pytest.mark.parametrize("suffix", [".stl", ".ply", ".off", ".glb", ".obj"])
def test_round_trip_formats(tmp_path, suffix):
    path = tmp_path / f"part{suffix}"
    box(offset=(1, 2, 3)).export(path)
    mesh = load_mesh(path, name="part")
    assert mesh.metadata["name"] == "part"
    solid = validate_solid(mesh)
    assert solid.volume == pytest.approx(6.0)
    np.testing.assert_allclose(solid.bounds, [[0.5, 1.0, 1.5], [1.5, 3.0, 4.5]])


def test_scene_transforms_are_applied(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(box((1, 1, 1)), transform=trimesh.transformations.translation_matrix(
        [10, 0, 0]))
    scene.add_geometry(box((1, 1, 1)))
    path = tmp_path / "scene.glb"
    scene.export(path)
    solid = validate_solid(load_mesh(path))
    assert solid.volume == pytest.approx(2.0)
    assert solid.bounds[1, 0] == pytest.approx(10.5)


@pytest.mark.parametrize("start", range(6))
def test_obj_ngons_are_ear_clipped(tmp_path, start):
    path = tmp_path / "L.obj"
    path.write_text(l_prism_obj(start))
    solid = validate_solid(load_mesh(path), name="L")
    assert solid.volume == pytest.approx(3.0)
    assert solid.area == pytest.approx(2 * 3.0 + 8.0)  # caps + perimeter 8 x height 1
    assert load_obj(path).metadata["polygon_problems"] == 0


# ---------------------------------------------------- triangulation and bookkeeping


def _twice_areas(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    a, b, c = (xy[triangles[:, k]] for k in range(3))
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])


@pytest.mark.parametrize(
    ("outline", "area"),
    [
        # corners on straight sides must be kept, or the neighbour gets a T-junction
        ([(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2), (0, 1)], 3.0),
        # a keyhole: a square with a square hole, joined by a bridge walked both ways
        ([(0, 0), (4, 0), (4, 4), (0, 4), (0, 0), (1, 1), (1, 3), (3, 3), (3, 1), (1, 1)],
         12.0),
        ([(0, 0), (5, 0), (5, 3), (4, 3), (4, 1), (3, 1), (3, 3), (2, 3), (2, 1), (1, 1),
          (1, 3), (0, 3)], 11.0),  # a comb
    ],
)
def test_ear_clip_tiles_non_convex_polygons_with_every_corner(outline, area):
    xy = np.asarray(outline, dtype=np.float64)
    tilted = np.column_stack([xy, 0.5 * xy[:, 0]])  # in the plane z = x / 2
    triangles, ok = ear_clip(tilted)
    assert ok and triangles.shape == (len(xy) - 2, 3)
    areas = _twice_areas(xy, triangles) / 2
    assert (areas > 0).all()  # every triangle wound like the polygon
    assert areas.sum() == pytest.approx(area)


def test_ear_clip_of_a_reversed_polygon_keeps_its_winding():
    xy = np.array([(0, 0), (0, 2), (1, 2), (1, 1), (2, 1), (2, 0)], dtype=np.float64)
    triangles, ok = ear_clip(np.column_stack([xy, np.zeros(len(xy))]))
    assert ok and (_twice_areas(xy, triangles) < 0).all()  # clockwise, like the input


@pytest.mark.parametrize(
    "outline",
    [[(0, 0), (1, 0), (2, 0), (1, 0)],  # no area
     [(0, 0), (2, 2), (2, 0), (0, 2), (-1, 1)]],  # crosses itself
)
def test_ear_clip_says_when_a_polygon_cannot_be_tiled(outline):
    points = np.column_stack([np.asarray(outline, float), np.zeros(len(outline))])
    triangles, ok = ear_clip(points)
    assert not ok and triangles.shape == (len(outline) - 2, 3)


def test_group_rows_groups_equal_rows_and_finds_the_first():
    rng = np.random.default_rng(4)
    small = rng.integers(0, 5, size=(400, 2))
    large = np.column_stack([rng.integers(0, 3, 400), rng.integers(0, 2, 400) * 2**40,
                             rng.integers(0, 2, 400)])  # too large to pack in one integer
    for rows in (small, large):
        inverse, counts, first = group_rows(rows)
        unique, want_first, want_inverse, want_counts = np.unique(
            rows, axis=0, return_index=True, return_inverse=True, return_counts=True)
        assert np.array_equal(np.sort(first), np.sort(want_first))
        assert np.array_equal(rows[first][inverse], rows)  # each row is its group's row
        assert np.array_equal(np.sort(counts), np.sort(want_counts))
    assert [len(a) for a in group_rows(np.zeros((0, 3), dtype=np.int64))] == [0, 0, 0]


def open_box(faces_removed) -> np.ndarray:
    mesh = trimesh.creation.box([2.0, 2.0, 2.0]).subdivide()
    keep = np.ones(len(mesh.faces), dtype=bool)
    keep[list(faces_removed)] = False
    return np.asarray(mesh.faces, dtype=np.int64)[keep]


def test_boundary_loops_follow_the_faces():
    mesh = trimesh.creation.box([2.0, 2.0, 2.0]).subdivide()
    top = np.flatnonzero(mesh.triangles_center[:, 2] > 0.99)[:1]
    bottom = np.flatnonzero(mesh.triangles_center[:, 2] < -0.99)
    faces = np.asarray(mesh.faces)
    pair = [f for f in bottom if len(set(faces[f]) & set(faces[bottom[0]])) == 2][:1]
    faces = open_box([*top, bottom[0], *pair])  # a triangle hole and a quad hole
    loops, tangled = boundary_loops(faces)
    assert tangled == 0 and sorted(len(loop) for loop in loops) == [3, 4]
    directed = {tuple(edge) for edge in faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2).tolist()}
    for loop in loops:
        assert all((a, b) in directed for a, b in zip(loop, loop[1:] + loop[:1]))


def test_boundary_loops_set_a_pinch_apart():
    """Two holes that share one vertex: that vertex has four boundary edges, so no loop
    through it is simple."""
    mesh = trimesh.creation.box([2.0, 2.0, 2.0]).subdivide()
    faces = np.asarray(mesh.faces, dtype=np.int64)
    corner = faces[0, 0]
    around = np.flatnonzero((faces == corner).any(axis=1))
    apart = [int(around[0])]
    for f in around[1:]:  # faces at the vertex sharing no edge with the chosen ones
        shared = [len(set(faces[f]) & set(faces[g])) for g in apart]
        if max(shared) == 1:
            apart.append(int(f))
            break
    assert len(apart) == 2
    loops, tangled = boundary_loops(open_box(apart))
    assert loops == [] and tangled == 6


def test_repair_fills_a_non_convex_hole():
    """An L-shaped hole (8 corners, two on straight sides) cut in a box's top face: the
    fill restores the box (trimesh's fill_holes fills only triangles and quads)."""
    box4 = trimesh.creation.box([4.0, 4.0, 1.0]).subdivide().subdivide()
    c = box4.triangles_center
    hole = (c[:, 2] > 0.49) & (((c[:, 0] < 0) & (c[:, 1] < -1)) | ((c[:, 0] < -1) & (c[:, 1] < 0)))
    holed = trimesh.Trimesh(box4.vertices, box4.faces[~hole], process=False)
    (loop,), _ = boundary_loops(np.asarray(holed.faces))
    assert len(loop) == 8
    repaired, report = repair_mesh(holed, name="holed")
    assert report["filled_holes"] == 1 and report["added_faces"] == 6
    assert repaired.volume == pytest.approx(16.0)


# ---------------------------------------------------------------------- mirror


def test_mirror_keeps_volume_and_negates_bounds():
    mesh = validate_solid(box(offset=(1, 2, 3)), name="R")
    flipped = mirror(mesh)
    assert flipped.is_watertight and flipped.is_winding_consistent
    assert flipped.volume == pytest.approx(mesh.volume)
    np.testing.assert_allclose(flipped.bounds, -mesh.bounds[::-1])
    assert flipped.metadata["name"] == "-R"
    np.testing.assert_allclose(mirror(flipped).vertices, mesh.vertices)


# ------------------------------------------------------------- real messy meshes


def hexagon_prism_area(half_width: float, half_height: float) -> float:
    """Area 3 w R of a hexagon with corners (0, ±R) and (±w, ±R/2)."""
    return 2 * half_width * half_height * 1.5


# Closed forms from the files' own (6-decimal) coordinates, in m^3:
# Hexagon cap: 80 mm cube + hexagonal prism, corners (±27.713, ±16) and (0, ±32) mm,
# 20 mm tall. Hexagon bottle: cube minus a hexagonal hole, corners (±28.713, ±16.5) and
# (0, ±33) mm, 25 mm deep. Arrow cap: cube + (16 x 40 mm bar + triangle of base
# 2 x 17.321 mm and height 20 mm) x 20 mm.
HEXAGON_CAP = CUBE + hexagon_prism_area(0.027713, 0.032) * 0.020
HEXAGON_BOTTLE = CUBE - hexagon_prism_area(0.028713, 0.033) * 0.025
ARROW_CAP = CUBE + (0.016 * 0.040 + 0.5 * 2 * 0.017321 * 0.020) * 0.020


@pytest.mark.parametrize(
    ("filename", "expected"),
    [("Hexagon_cube_cap.obj", HEXAGON_CAP), ("Arrow_cube_cap.obj", ARROW_CAP)],
)
def test_repair_real_asset_loaded_by_trimesh(filename, expected):
    # trimesh splits vertices along texture seams: nothing is watertight as loaded
    # (merging them, which validate_solid also does, closes the caps)
    raw = trimesh.load(asset(f"{PEG}/{filename}"), force="mesh")
    assert not raw.is_watertight
    repaired, report = repair_mesh(raw, name=filename)
    assert repaired.is_watertight and repaired.is_winding_consistent
    assert report["merged_vertices"] > 0
    # exact up to the rounding of the file's coordinates (1e-6 m on ~0.1 m parts)
    assert repaired.volume == pytest.approx(expected, rel=1e-9)
    assert len(split_solid(repaired)) == 2  # the cube and the peg resting on it


def test_trimesh_fans_real_bottle_wrongly_and_we_say_so():
    raw = trimesh.load(asset(f"{PEG}/U_cube_bottle.obj"), force="mesh")
    with pytest.raises(InvalidMeshError, match=r"U_cube_bottle.*overlaps itself.*load_obj"):
        repair_mesh(raw, name="U_cube_bottle.obj")


PEG_FILES = [f"{shape}_cube_{part}.obj" for shape in ("Arrow", "Circle", "Cross", "Hexagon",
                                                       "Key", "U") for part in ("bottle", "cap")]
"""The peg-in-hole set's meshes (its README lists the six shapes)."""


@pytest.mark.parametrize("name", PEG_FILES)
def test_load_mesh_reads_every_peg_in_hole_asset_as_a_solid(name):
    path = asset(f"{PEG}/{name}")
    solid = validate_solid(load_mesh(path), name=path.name)
    assert solid.is_watertight and solid.is_winding_consistent
    if "cap" in path.name:  # cube + a 20 mm prism of cross-section < 60 x 60 mm
        assert CUBE < solid.volume < CUBE + 0.06 * 0.06 * 0.02
        assert len(split_solid(solid)) == 2
    else:  # cube minus a 25 mm deep hole
        assert CUBE - 0.06 * 0.06 * 0.025 < solid.volume < CUBE
        assert len(split_solid(solid)) == 1
    if path.name == "Hexagon_cube_bottle.obj":
        assert solid.volume == pytest.approx(HEXAGON_BOTTLE, rel=1e-9)
