"""The tidy path of validate_solid (one native check, ``_tidy_windings``) against the full
cleaning it skips: on every mesh, clean or not, both give the same solid or the same
error, and the clean ones do take it."""

from __future__ import annotations

import numpy as np
import pytest
import shapes
import trimesh
from conftest import asset

import planner.meshes.solids as solids
from planner.errors import InvalidMeshError
from planner.meshes import load_mesh, validate_solid
from planner.meshes.kinds import classify

KEYS = (solids.SOLID_CHANGES, solids.FACES_INSIDE, solids.FACE_CROSSINGS)


def outcome(mesh: trimesh.Trimesh):
    """The solid's arrays and counts, or the error's message."""
    try:
        solid = validate_solid(mesh, name="part")
    except InvalidMeshError as error:
        return str(error)
    return (np.asarray(solid.vertices), np.asarray(solid.faces),
            [solid.metadata[key] for key in KEYS])


def both_paths(mesh: trimesh.Trimesh, monkeypatch) -> tuple[object, object, bool]:
    """``validate_solid`` with the tidy path and with the full cleaning only, and whether
    the first took the tidy path."""
    taken = []
    tidy = solids._tidy_windings

    def spy(*args):
        found = tidy(*args)
        taken.append(found is not None)
        return found
    with monkeypatch.context() as patch:
        patch.setattr(solids, "_tidy_windings", spy)
        fast = outcome(mesh)
    with monkeypatch.context() as patch:
        patch.setattr(solids, "_tidy_windings", lambda *args: None)
        full = outcome(mesh)
    return fast, full, any(taken)


def assert_same(fast, full) -> None:
    if isinstance(full, str) or isinstance(fast, str):
        assert fast == full
        return
    np.testing.assert_array_equal(fast[0], full[0])
    np.testing.assert_array_equal(fast[1], full[1])
    assert fast[2] == full[2]


def concatenated(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.util.concatenate(list(meshes))


def turned(mesh: trimesh.Trimesh, which=slice(None)) -> trimesh.Trimesh:
    faces = np.array(mesh.faces)
    faces[which] = faces[which][:, ::-1]
    return trimesh.Trimesh(np.array(mesh.vertices), faces, process=False)


def fanned_top_box() -> trimesh.Trimesh:
    """A box whose top is fanned from the middle of one edge, with the zero-area sliver
    that closes that edge (kept by the cleaning: dropping it would open the box)."""
    box = shapes.box((1.0, 0.6, 0.4))
    vertices, faces = np.array(box.vertices), np.array(box.faces)
    top = vertices[faces][:, :, 2].min(axis=1) > 0.1
    corners = {tuple(np.round(v[:2], 3)): i for i, v in enumerate(vertices) if v[2] > 0.1}
    a, b = corners[(-0.5, -0.3)], corners[(0.5, -0.3)]
    c, d = corners[(0.5, 0.3)], corners[(-0.5, 0.3)]
    vertices = np.vstack([vertices, (vertices[a] + vertices[b]) / 2])
    m = len(vertices) - 1
    fan = [[a, m, d], [m, b, c], [m, c, d], [a, b, m]]
    return trimesh.Trimesh(vertices, np.vstack([faces[~top], fan]), process=False)


def nudged_copy_of_a_vertex(mesh: trimesh.Trimesh, distance: float) -> trimesh.Trimesh:
    """The mesh with one corner of one face replaced by a copy ``distance`` away."""
    vertices, faces = np.array(mesh.vertices), np.array(mesh.faces)
    vertices = np.vstack([vertices, vertices[faces[0, 0]] + [distance, 0.0, 0.0]])
    faces[0, 0] = len(vertices) - 1
    return trimesh.Trimesh(vertices, faces, process=False)


CLEAN = {
    "box": lambda: shapes.box((1.0, 0.6, 0.4)),
    "icosphere": lambda: shapes.icosphere(3),
    "torus": lambda: shapes.torus(),
    "l bracket": lambda: shapes.l_bracket(),
    "plate with a hole": lambda: shapes.plate_with_hole(),
    "bunny-like part": lambda: shapes.nonconvex_part_2k(),
    "two boxes apart": lambda: concatenated(shapes.box(), shapes.box(center=(3, 0, 0))),
    "two boxes overlapping": lambda: concatenated(shapes.box(), shapes.box(center=(0.5, 0.2, 0))),
    "a box inside a box": lambda: concatenated(shapes.box((4, 4, 4)), shapes.box()),
    "a box fanned with a sliver": fanned_top_box,
    "an unused vertex (dropped before the check)": lambda: trimesh.Trimesh(
        np.vstack([shapes.box().vertices, [[9.0, 9.0, 9.0]]]), shapes.box().faces,
        process=False),
}
"""Meshes the cleaning leaves as they are: the tidy path must take them."""

UNTIDY = {
    "inside out": lambda: turned(shapes.box()),
    "one face turned": lambda: turned(shapes.icosphere(2), slice(0, 1)),
    "a cavity": lambda: concatenated(shapes.box((4, 4, 4)), turned(shapes.box())),
    "all inside out with a cavity": lambda: turned(
        concatenated(shapes.box((4, 4, 4)), turned(shapes.box()))),
    "a corner copied within the merge distance": lambda: nudged_copy_of_a_vertex(
        shapes.box(), 1e-12),
    "a corner copied just beyond it": lambda: nudged_copy_of_a_vertex(shapes.box(), 1e-6),
    "a repeated face": lambda: trimesh.Trimesh(
        shapes.box().vertices, np.vstack([shapes.box().faces, shapes.box().faces[:1]]),
        process=False),
    "an open box": lambda: trimesh.Trimesh(shapes.box().vertices, shapes.box().faces[1:],
                                           process=False),
    "a flat box": lambda: trimesh.creation.box(extents=(1.0, 1.0, 1e-14)),
    "a misfanned polygon": shapes.misfanned_l_prism,
    "boxes touching along an edge": lambda: concatenated(shapes.box(),
                                                         shapes.box(center=(1, 1, 0))),
}
"""Meshes the cleaning changes or refuses."""


@pytest.mark.parametrize("name", sorted(CLEAN))
def test_a_clean_mesh_takes_the_tidy_path_to_the_same_solid(name, monkeypatch):
    fast, full, took = both_paths(CLEAN[name](), monkeypatch)
    assert not isinstance(full, str), full
    assert_same(fast, full)
    assert took


@pytest.mark.parametrize("name", sorted(UNTIDY))
def test_a_mesh_the_cleaning_changes_gets_the_same_solid_or_error(name, monkeypatch):
    fast, full, took = both_paths(UNTIDY[name](), monkeypatch)
    assert_same(fast, full)
    assert not took


ASSET_FILES = [
    "assemblies/factory_round_peg_8mm/meshes/factory_round_peg_8mm_loose.obj",
    "assemblies/factory_round_peg_8mm/meshes/factory_round_hole_8mm_subdiv_3x.obj",
    "assemblies/industreal_gears/meshes/industreal_gear_small.obj",
    "assemblies/factory_nut_bolt_m12/meshes/factory_bolt_m12_loose.obj",
    "geometric_peg_in_hole_2mm/Arrow_cube_bottle.obj",
    "geometric_peg_in_hole_2mm/Cross_cube_cap.obj",
]


@pytest.mark.parametrize("relative", ASSET_FILES)
def test_real_parts_get_the_same_solid_both_ways(relative, monkeypatch):
    mesh = load_mesh(asset(relative))
    fast, full, _ = both_paths(mesh, monkeypatch)
    assert_same(fast, full)
    # and their solids (the round hole's file is open: repaired), clean by now, take the
    # tidy path
    solid = classify(mesh, name="part", kind="solid").mesh
    solid = trimesh.Trimesh(np.array(solid.vertices), np.array(solid.faces), process=False)
    fast, again, took = both_paths(solid, monkeypatch)
    assert_same(fast, again)
    assert took
