"""Tests for planner.meshes, planner.errors and planner.tolerances."""

from __future__ import annotations

import dataclasses
import logging
import pickle

import numpy as np
import pytest
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


def fan(polygon):
    return [(polygon[0], polygon[k], polygon[k + 1]) for k in range(1, len(polygon) - 1)]


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
    outline = [(2, 1), (1, 1), (1, 2), (0, 2), (0, 0), (2, 0)]
    vertices = [(x, y, 0) for x, y in outline] + [(x, y, 1) for x, y in outline]
    n = len(outline)
    faces = [tuple(reversed(t)) for t in fan(list(range(n)))]
    faces += fan([n + i for i in range(n)])
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    bad = trimesh.Trimesh(np.array(vertices, float), np.array(faces), process=False)
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
