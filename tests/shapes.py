"""Test solids for the Minkowski-sum tests and benchmarks.

Every function returns a watertight, consistently outward-oriented ``trimesh.Trimesh``
with float64 vertices and positive volume (checked by :func:`checked`).  Booleans go
through manifold3d (deterministic) in float64 (``Mesh64``); everything else is built
directly.  Shapes are centred on the origin unless a centre is given, because
manifold3d's ``minkowski_sum`` is only right when the second operand contains the origin.
"""

from __future__ import annotations

from functools import reduce

import manifold3d
import numpy as np
import trimesh

__all__ = [
    "bored_block",
    "box",
    "checked",
    "cross_of_bars",
    "from_manifold",
    "icosphere",
    "l_bracket",
    "nonconvex_part_2k",
    "plate_with_hole",
    "random_convex",
    "roofed_channel",
    "slotted_bar",
    "to_manifold",
    "torus",
]


def checked(mesh: trimesh.Trimesh, name: str = "mesh", *,
            allow_degenerate: bool = False) -> trimesh.Trimesh:
    """Return ``mesh`` after asserting it is a valid closed solid.

    Raises ``ValueError`` (not ``assert``: it must hold under ``python -O`` too) when the
    mesh is not watertight, not winding-consistent, has a degenerate triangle (area below
    1e-12 of the squared bounding-box diagonal; unless ``allow_degenerate``, e.g. for
    manifold3d's Minkowski sums, which have some) or non-positive volume.
    """
    mesh = trimesh.Trimesh(
        vertices=np.asarray(mesh.vertices, dtype=np.float64),
        faces=np.asarray(mesh.faces, dtype=np.int64),
        process=False,
    )
    if not mesh.is_watertight:
        raise ValueError(f"{name}: not watertight")
    if not mesh.is_winding_consistent:
        raise ValueError(f"{name}: winding not consistent")
    diag = float(np.linalg.norm(mesh.extents))
    if not allow_degenerate and not np.all(mesh.area_faces > 1e-12 * diag**2):
        raise ValueError(f"{name}: degenerate triangle")
    if mesh.volume < 0:
        mesh.invert()
    if not mesh.volume > 0:
        raise ValueError(f"{name}: volume {mesh.volume} is not positive")
    return mesh


def to_manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    """trimesh -> manifold3d, in float64."""
    m = manifold3d.Manifold(
        manifold3d.Mesh64(
            # fresh writeable copies: nanobind refuses trimesh's read-only views
            vert_properties=np.array(mesh.vertices, dtype=np.float64, order="C", copy=True),
            tri_verts=np.array(mesh.faces, dtype=np.uint64, order="C", copy=True),
        )
    )
    if m.status() != manifold3d.Error.NoError:
        raise ValueError(f"manifold3d rejected the mesh: {m.status()}")
    return m


def from_manifold(m: manifold3d.Manifold, name: str = "manifold", *,
                  allow_degenerate: bool = False) -> trimesh.Trimesh:
    """manifold3d -> checked trimesh, in float64."""
    mg = m.to_mesh64()
    verts = np.asarray(mg.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(mg.tri_verts, dtype=np.int64)
    # process=False: manifold3d's indexing is already watertight, and trimesh's merge of
    # vertices closer than 1e-8 could pinch it
    return checked(trimesh.Trimesh(vertices=verts, faces=faces, process=False), name,
                   allow_degenerate=allow_degenerate)


def box(size=(1.0, 1.0, 1.0), center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Axis-aligned box of extents ``size`` centred at ``center`` (12 triangles)."""
    size = np.broadcast_to(np.asarray(size, dtype=np.float64), (3,))
    mesh = trimesh.creation.box(extents=size)
    mesh.apply_translation(np.asarray(center, dtype=np.float64))
    return checked(mesh, "box")


def icosphere(subdivisions: int = 2, r: float = 1.0, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Icosphere of circumradius ``r`` (vertices on the sphere; the solid is inside it)."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=r)
    mesh.apply_translation(np.asarray(center, dtype=np.float64))
    return checked(mesh, "icosphere")


def random_convex(n_points: int = 40, scale=(1.0, 1.0, 1.0), seed: int = 0,
                  center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Convex hull of ``n_points`` seeded random points in an ellipsoid-ish cloud."""
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n_points, 3)) * np.asarray(scale, dtype=np.float64)
    pts += np.asarray(center, dtype=np.float64)
    return checked(trimesh.convex.convex_hull(pts), "random_convex")


def _extrude_polygon(polygon, depth: float) -> manifold3d.Manifold:
    cs = manifold3d.CrossSection([np.asarray(polygon, dtype=np.float64)])
    return manifold3d.Manifold.extrude(cs, depth)


def l_bracket(length: float = 4.0, height: float = 3.0, thickness: float = 1.0,
              depth: float = 2.0, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """L-shaped bracket: an ``length`` x ``thickness`` foot and a ``thickness`` x ``height``
    leg in the xy plane, extruded ``depth`` along z; bounding box centred at ``center``.
    """
    t = thickness
    poly = [(0, 0), (length, 0), (length, t), (t, t), (t, height), (0, height)]
    m = _extrude_polygon(poly, depth)
    m = m.translate([-length / 2 + center[0], -height / 2 + center[1], -depth / 2 + center[2]])
    return from_manifold(m, "l_bracket")


def slotted_bar(slot_width: float = 0.2, length: float = 3.0, width: float = 1.0,
                height: float = 0.5, n_slots: int = 2, slot_length: float = 0.6
                ) -> trimesh.Trimesh:
    """Bar ``length`` (x) x ``width`` (y) x ``height`` (z), centred on the origin, with
    ``n_slots`` through-slots along z, each ``slot_width`` wide in x and ``slot_length``
    long in y, spaced evenly along x and centred in y.

    ``mesh.metadata["slot_centers"]`` holds the ``(n_slots, 3)`` slot centres,
    ``metadata["slot_width"]``, ``["slot_length"]`` and ``["slot_normal"]`` (x) describe
    them: the slot between ``c - w/2`` and ``c + w/2`` along x is empty for the full height.
    """
    if not (0 < slot_length < width and 0 < slot_width and n_slots * slot_width < length):
        raise ValueError("slots do not fit in the bar")
    bar = manifold3d.Manifold.cube([length, width, height], True)
    xs = (np.arange(n_slots) + 1) * length / (n_slots + 1) - length / 2
    cutters = [
        manifold3d.Manifold.cube([slot_width, slot_length, 2 * height], True).translate(
            [float(x), 0.0, 0.0])
        for x in xs
    ]
    m = bar - reduce(lambda a, b: a + b, cutters)
    mesh = from_manifold(m, "slotted_bar")
    mesh.metadata["slot_centers"] = np.column_stack([xs, np.zeros(n_slots), np.zeros(n_slots)])
    mesh.metadata["slot_width"] = float(slot_width)
    mesh.metadata["slot_length"] = float(slot_length)
    mesh.metadata["slot_normal"] = np.array([1.0, 0.0, 0.0])
    return mesh


def torus(R: float = 10.0, r: float = 3.0, major_sections: int = 32,
          minor_sections: int = 16, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    """Polygonal torus around the z axis; vertices lie on the smooth torus."""
    if not (R > r > 0 and major_sections >= 3 and minor_sections >= 3):
        raise ValueError("need R > r > 0 and at least 3 sections each way")
    u = 2 * np.pi * np.arange(major_sections) / major_sections
    v = 2 * np.pi * np.arange(minor_sections) / minor_sections
    uu, vv = np.meshgrid(u, v, indexing="ij")
    rho = R + r * np.cos(vv)
    verts = np.stack([rho * np.cos(uu), rho * np.sin(uu), r * np.sin(vv)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(major_sections), np.arange(minor_sections), indexing="ij")
    i1, j1 = (i + 1) % major_sections, (j + 1) % minor_sections

    def idx(a, b):
        return a * minor_sections + b

    q00, q10, q11, q01 = idx(i, j), idx(i1, j), idx(i1, j1), idx(i, j1)
    faces = np.concatenate([
        np.stack([q00, q10, q11], axis=-1).reshape(-1, 3),
        np.stack([q00, q11, q01], axis=-1).reshape(-1, 3),
    ])
    mesh = trimesh.Trimesh(vertices=verts + np.asarray(center, dtype=np.float64),
                           faces=faces, process=False)
    return checked(mesh, "torus")


def cross_of_bars(length: float = 30.0, width: float = 6.0) -> trimesh.Trimesh:
    """Union of three orthogonal ``length`` x ``width`` x ``width`` bars centred on the
    origin (manifold3d boolean union)."""
    bars = [
        manifold3d.Manifold.cube([length, width, width], True),
        manifold3d.Manifold.cube([width, length, width], True),
        manifold3d.Manifold.cube([width, width, length], True),
    ]
    return from_manifold(bars[0] + bars[1] + bars[2], "cross_of_bars")


def plate_with_hole(size=(10.0, 10.0, 1.0), hole_radius: float = 2.0,
                    sections: int = 32) -> trimesh.Trimesh:
    """Plate ``size`` centred on the origin with a round through-hole along z."""
    plate = manifold3d.Manifold.cube(list(map(float, size)), True)
    hole = manifold3d.Manifold.cylinder(2.0 * size[2] + 1.0, hole_radius, -1.0, sections, True)
    return from_manifold(plate - hole, "plate_with_hole")


def bored_block(size=(2.0, 2.0, 4.0), bore_radius: float = 0.56,
                sections: int = 32) -> trimesh.Trimesh:
    """Block ``size`` centred on the origin with a round through-bore along z (a polygon
    of ``sections`` sides with circumradius ``bore_radius``; its inradius is
    ``bore_radius * cos(pi / sections)``)."""
    block = manifold3d.Manifold.cube(list(map(float, size)), True)
    bore = manifold3d.Manifold.cylinder(2.0 * size[2], bore_radius, -1.0, sections, True)
    return from_manifold(block - bore, "bored_block")


def nonconvex_part_2k() -> trimesh.Trimesh:
    """A deterministic non-convex machined part of about 2,000 triangles, ~10 units across,
    centred near the origin: a block with a blind pocket and a cross hole, a boss on top,
    a bore through the boss, and a flange tab."""
    M = manifold3d.Manifold
    block = M.cube([8.0, 6.0, 4.0], True)
    pocket = M.cube([3.0, 2.0, 3.0], True).translate([-2.0, 0.0, 1.0])
    cross_hole = M.cylinder(10.0, 0.8, -1.0, 48, True).rotate([90.0, 0.0, 0.0]).translate(
        [2.0, 0.0, -0.5])
    boss = M.cylinder(3.1, 1.6, 1.2, 72, False).translate([2.0, 0.0, 1.9])
    bore = M.cylinder(12.0, 0.6, -1.0, 48, True).translate([2.0, 0.0, 0.0])
    tab = M.cube([2.2, 4.0, 1.0], True).translate([-4.9, 0.0, -1.5])
    tab_hole = M.cylinder(3.0, 0.5, -1.0, 32, True).translate([-5.3, 0.0, -1.5])
    ball = M.sphere(1.2, 64).translate([0.0, -3.0, 0.0])
    part = (block + boss + tab + ball) - pocket - cross_hole - bore - tab_hole
    box_ = part.bounding_box()
    centre = [(box_[i] + box_[i + 3]) / 2 for i in range(3)]
    return from_manifold(part.translate([-c for c in centre]), "nonconvex_part_2k")


def jack(length: float = 3.0, width: float = 0.5) -> trimesh.Trimesh:
    """A jack of three orthogonal ``length`` x ``width`` x ``width`` bars centred on the
    origin (:func:`cross_of_bars` at a small scale)."""
    m = cross_of_bars(length, width)
    m.metadata["name"] = "jack"
    return m


def tetrahedron(size: float = 1.0) -> trimesh.Trimesh:
    """The corner tetrahedron of edge ``size`` along the axes, its centroid at the origin."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) * size
    return trimesh.convex.convex_hull(v - v.mean(axis=0))


def comb(teeth: int = 8, length: float = 4.0, tooth: float = 1.0, thickness: float = 0.25
         ) -> trimesh.Trimesh:
    """A comb: a ``length`` x ``thickness`` back with ``teeth`` teeth ``tooth`` long and
    ``thickness`` wide along y, ``thickness`` deep in z; centred on the origin."""
    M = manifold3d.Manifold
    back = M.cube([length, thickness, thickness], True)
    pitch = length / teeth
    parts = [back] + [
        M.cube([thickness, tooth, thickness], True).translate(
            [-length / 2 + pitch * (i + 0.5), (tooth + thickness) / 2 - 0.01, 0.0])
        for i in range(teeth)]
    m = reduce(lambda a, b: a + b, parts)
    box_ = m.bounding_box()
    return from_manifold(m.translate([-(box_[i] + box_[i + 3]) / 2 for i in range(3)]), "comb")


def grate(holes: int, size: float, thickness: float, bar: float) -> trimesh.Trimesh:
    """A square plate ``size`` wide and ``thickness`` thick, centred on the origin, with
    ``holes`` x ``holes`` square through-holes separated by bars ``bar`` wide."""
    plate = manifold3d.Manifold.cube([size, size, thickness], True)
    pitch = size / holes
    cutters = [
        manifold3d.Manifold.cube([pitch - bar, pitch - bar, 2 * thickness], True).translate(
            [-size / 2 + pitch * (i + 0.5), -size / 2 + pitch * (j + 0.5), 0.0])
        for i in range(holes) for j in range(holes)]
    return from_manifold(plate - reduce(lambda a, b: a + b, cutters), f"grate{holes}")


ROOFED_CHANNEL_BOXES = (
    ((-1.0, -0.5, 0.0), (1.0, 0.5, 0.2)),      # floor
    ((-1.0, -0.5, 0.1), (1.0, -0.3, 0.8)),     # side walls
    ((-1.0, 0.3, 0.1), (1.0, 0.5, 0.8)),
    ((-0.95, -0.45, 0.7), (0.95, 0.45, 1.2)),  # thick roof
    ((0.8, -0.35, 0.1), (1.0, 0.35, 0.75)),    # end wall (+x)
    ((-1.0, -0.35, 0.1), (-0.8, 0.35, 0.4)),   # low stop (-x)
)
"""``(lo, hi)`` corners of the boxes of :func:`roofed_channel`."""


def roofed_channel() -> trimesh.Trimesh:
    """A roofed channel along x, open on its floor at ``z = 0.2``, for a slider of up to
    0.5 x 0.5 wide: +z is blocked by a thick roof, +x by an end wall, -x by a low stop (top
    at ``z = 0.4``) that a slider on the floor must climb over; so it has no straight exit.
    Overlapping boxes, not booleaned (every body convex, so decompositions are exact)."""
    boxes = []
    for lo, hi in ROOFED_CHANNEL_BOXES:
        lo_, hi_ = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        boxes.append(box(hi_ - lo_, (lo_ + hi_) / 2))
    return trimesh.util.concatenate(boxes)


def misfanned_l_prism() -> trimesh.Trimesh:
    """An L prism (volume 3) whose hexagon caps were fanned from a corner that cannot see
    them all: closed and of the right volume, but its caps overlap themselves (not
    checked: the solid tests refuse it)."""
    outline = [(2, 1), (1, 1), (1, 2), (0, 2), (0, 0), (2, 0)]
    n = len(outline)
    vertices = [(x, y, 0) for x, y in outline] + [(x, y, 1) for x, y in outline]
    faces = [(0, k + 1, k) for k in range(1, n - 1)]
    faces += [(n, n + k, n + k + 1) for k in range(1, n - 1)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    return trimesh.Trimesh(np.array(vertices, float), np.array(faces), process=False)
