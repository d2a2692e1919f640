"""The core's checked mesh is made once per validated mesh (planner.meshes.checked): the
one validate_solid's winding check made is given back for that mesh while it is
unchanged, and a changed, other or differently taken mesh is checked again."""

from __future__ import annotations

import numpy as np
import trimesh

import planner
from planner.meshes import validate_solid
from planner.meshes.checked import core_mesh


def test_a_validated_solid_is_not_checked_again():
    solid = validate_solid(trimesh.creation.box((1.0, 2.0, 3.0)), name="box")
    first = core_mesh(solid, solid=True, name="box")
    assert core_mesh(solid, solid=True, name="box") is first


def test_a_mesh_changed_in_place_is_checked_again():
    solid = validate_solid(trimesh.creation.box((1.0, 2.0, 3.0)), name="box")
    first = core_mesh(solid, solid=True, name="box")
    solid.vertices[:, 0] *= 2.0                       # still a solid, another one
    again = core_mesh(solid, solid=True, name="box")
    assert again is not first
    assert core_mesh(solid, solid=True, name="box") is again


def test_a_mesh_changed_through_a_plain_array_view_is_checked_again():
    # trimesh's own hash tracks writes to its arrays, not to a plain ndarray view of them
    solid = validate_solid(trimesh.creation.box((1.0, 2.0, 3.0)), name="box")
    first = core_mesh(solid, solid=True, name="box")
    np.asarray(solid.vertices)[:, 0] *= 2.0
    again = core_mesh(solid, solid=True, name="box")
    assert again is not first
    grown = planner.offset(solid, 0.1, eps=0.01, method="cells")
    assert grown.mesh.bounds[1, 0] - grown.mesh.bounds[0, 0] > 2.1  # the 2-wide box's


def test_a_copy_or_a_surface_is_checked_on_its_own():
    solid = validate_solid(trimesh.creation.box((1.0, 2.0, 3.0)), name="box")
    first = core_mesh(solid, solid=True, name="box")
    assert core_mesh(solid.copy(), solid=True, name="box") is not first
    assert core_mesh(solid, solid=False, name="box") is not first


def test_the_remembered_solid_gives_the_same_offset():
    mesh = trimesh.creation.annulus(r_min=0.3, r_max=1.0, height=0.5, sections=24)
    remembered = planner.offset(mesh, 0.1, eps=0.02, method="cells")
    fresh = planner.offset((np.asarray(mesh.vertices), np.asarray(mesh.faces)), 0.1,
                           eps=0.02, method="cells")
    assert np.isclose(remembered.mesh.volume, fresh.mesh.volume, rtol=0, atol=1e-12)
    assert len(remembered.mesh.faces) == len(fresh.mesh.faces)
