"""A scene as binary glTF (GLB), for any 3D viewer (Blender, three.js editor, model-viewer).

:func:`to_trimesh` turns a :class:`~planner.viz.scene.Scene` into a ``trimesh.Scene`` with
one node per layer, named by its scene path (``workspace/obstacles/block``), under group
nodes for the path's parents (``workspace``, ``workspace/obstacles``) and one root
``minkplan`` that turns the scene's z-up world into glTF's y-up frame. Meshes carry a PBR
material of the layer's colour and opacity (``alphaMode`` ``BLEND`` when translucent);
segments and polylines become line primitives, points point primitives, coloured per
vertex. :func:`write_glb` writes it atomically.

What glTF cannot say is left out and listed in the file's scene ``extras``
(``minkplan.left_out``): the layers created hidden (octree cells, the roadmap, a
certificate's walled-in cells: a viewer without switches would show them over everything;
``include_hidden=True`` keeps them) and the animated robot (the path and the robot at start
and goal stand for it). ``minkplan.layers`` gives every exported layer's kind, count and
note, as the page's legend does.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import trimesh
from trimesh.path.entities import Line

from planner.output import atomic_write

from .scene import ROBOT_MOVING, Layer, Scene

__all__ = ["ROOT_NODE", "Z_UP_TO_Y_UP", "to_trimesh", "write_glb"]

ROOT_NODE = "minkplan"
"""Name of the root node; every layer's node lies below it."""

Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0, 0.0],
                         [0.0, 0.0, 1.0, 0.0],
                         [0.0, -1.0, 0.0, 0.0],
                         [0.0, 0.0, 0.0, 1.0]])
"""The root's transform: world (x, y, z), z up, to glTF's (x, z, −y), y up."""


def _rgba(layer: Layer) -> np.ndarray:
    """``(4,)`` uint8 colour and opacity of ``layer``."""
    c = layer.color
    alpha = round(255 * min(max(layer.opacity, 0.0), 1.0))
    return np.array([(c >> 16) & 255, (c >> 8) & 255, c & 255, alpha], dtype=np.uint8)


def _geometry(layer: Layer):
    """The trimesh geometry of one layer (``None`` when it has nothing to draw)."""
    rgba = _rgba(layer)
    if len(layer.vertices) == 0:
        return None
    if layer.kind == "mesh":
        material = trimesh.visual.material.PBRMaterial(
            baseColorFactor=rgba, metallicFactor=0.0, roughnessFactor=0.8,
            alphaMode="BLEND" if rgba[3] < 255 else "OPAQUE", doubleSided=not layer.lit)
        return trimesh.Trimesh(layer.vertices, layer.faces, process=False,
                               visual=trimesh.visual.TextureVisuals(material=material))
    if layer.kind == "points":
        return trimesh.PointCloud(layer.vertices, colors=np.tile(rgba, (len(layer.vertices), 1)))
    if layer.kind == "segments":
        entities = [Line([i, i + 1]) for i in range(0, len(layer.vertices) - 1, 2)]
    else:  # a polyline
        entities = [Line(np.arange(len(layer.vertices)))]
    path = trimesh.path.Path3D(entities=entities, vertices=layer.vertices, process=False)
    path.colors = np.tile(rgba, (len(entities), 1))
    return path


def _left_out(scene: Scene, include_hidden: bool) -> dict[str, str]:
    """``{layer path: why}`` of the layers the file does not hold."""
    out = {}
    for path in scene.layers:
        if path == ROBOT_MOVING:
            out[path] = "animated in the HTML page only (the path and the ghosts stand for it)"
        elif not include_hidden and not scene.is_visible(path):
            out[path] = "hidden when the scene opens (switch it on in the HTML page)"
    return out


def _add_group_nodes(result: trimesh.Scene, path: str, made: set[str]) -> str:
    """Create the group nodes above ``path`` (``a``, ``a/b`` for ``a/b/c``); returns the
    parent's name."""
    parent = ROOT_NODE
    parts = path.split("/")
    for i in range(1, len(parts)):
        group = "/".join(parts[:i])
        if group not in made:
            result.graph.update(frame_to=group, frame_from=parent, matrix=np.eye(4))
            made.add(group)
        parent = group
    return parent


def to_trimesh(scene: Scene, *, include_hidden: bool = False) -> trimesh.Scene:
    """``scene`` as a ``trimesh.Scene`` ready for ``export(file_type="glb")`` (see the
    module's docstring for its nodes, materials and what is left out)."""
    left_out = _left_out(scene, include_hidden)
    result = trimesh.Scene()
    result.graph.update(frame_from=result.graph.base_frame, frame_to=ROOT_NODE,
                        matrix=Z_UP_TO_Y_UP)
    made = {ROOT_NODE}
    layers = {}
    for path, layer in scene.layers.items():
        geometry = None if path in left_out else _geometry(layer)
        if geometry is None:
            continue
        parent = _add_group_nodes(result, path, made)
        result.add_geometry(geometry, node_name=path, geom_name=path, parent_node_name=parent,
                            transform=layer.transform)
        layers[path] = {"kind": layer.kind, "count": layer.count, "note": layer.note,
                        "color": f"#{layer.color:06x}", "opacity": layer.opacity}
    result.metadata["minkplan"] = {"title": scene.title, "up": "z (the root node turns it to y)",
                                   "layers": layers, "left_out": left_out}
    return result


def write_glb(scene: Scene, path: str | os.PathLike[str], *,
              include_hidden: bool = False) -> Path:
    """Write :func:`to_trimesh` of ``scene`` to ``path`` as GLB, atomically (a temporary
    file in the same folder renamed over it); returns the path."""
    target = Path(path)
    data = to_trimesh(scene, include_hidden=include_hidden).export(file_type="glb")
    atomic_write(target, lambda tmp: Path(tmp).write_bytes(data))
    return target
