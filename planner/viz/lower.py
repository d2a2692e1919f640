"""Geometry to messages: a :class:`~planner.viz.scene.Scene` as meshcat commands.

:func:`commands` turns a scene into meshcat-python command objects (``SetObject``,
``SetTransform``, ``SetProperty``, ``SetAnimation``), each with ``.lower()`` giving the
dict that meshcat's viewer decodes; :func:`packed` msgpack-encodes them;
:func:`staged_commands` splits them into what builds the scene at once and what creates
each hidden layer (a page loads those on demand). Transport
(HTML file, notebook, live server) lives in :mod:`planner.viz.html` and
:mod:`planner.viz.live` and only ever sees these commands.

Every layer is one meshcat object at ``/meshcat/<layer path>``. Besides the layers the
commands set: a neutral background, a key light, the grid scaled and placed under the
scene, and the camera framing the visible layers (meshcat's camera lives at
``/Cameras/default`` with a y-up child ``rotated/<object>``).
"""

from __future__ import annotations

import math
import uuid

import numpy as np
import umsgpack

from ._meshcat import Animation, SetAnimation, SetObject, SetProperty, SetTransform
from ._meshcat import Path as MeshcatPath
from ._meshcat import geometry as mg
from .scene import Camera, Layer, Scene

__all__ = ["ROOT", "commands", "lowered", "on_demand", "packed", "staged_commands"]

ROOT = "meshcat"
"""Root of the layers in meshcat's scene tree (as meshcat-python's ``Visualizer``)."""

BACKGROUND_TOP = [1.0, 1.0, 1.0]
BACKGROUND_BOTTOM = [0.80, 0.82, 0.85]
KEY_LIGHT_DIRECTION = (0.6, -1.0, 1.6)
KEY_LIGHT_INTENSITY = 0.7
FPS = 30
ANIMATION_REPETITIONS = 1_000_000  # "loop": meshcat's LoopRepeat with a huge count

_NAMESPACE = uuid.UUID("6c1f7c2e-5d0b-4c31-9a57-2f4f9b1d0e11")


def _path(*parts: str) -> MeshcatPath:
    entries: tuple[str, ...] = ()
    for part in parts:
        entries += tuple(p for p in part.split("/") if p)
    return MeshcatPath(entries)


def _stable_uuid(*key: str) -> str:
    """Deterministic uuids: the same scene gives the same HTML (meshcat's default uuid1
    embeds the host and the time)."""
    return str(uuid.uuid5(_NAMESPACE, "/".join(key)))


class _Geometry(mg.Geometry):
    """A BufferGeometry from float32 positions ``(n, 3)`` and optional uint32 index."""

    def __init__(self, key: str, positions: np.ndarray, index: np.ndarray | None = None):
        super().__init__()
        self.uuid = _stable_uuid(key, "geometry")
        self.positions = np.ascontiguousarray(positions, dtype=np.float32)
        self.index = None if index is None else np.ascontiguousarray(index, dtype=np.uint32)

    def lower(self, object_data):
        data = {"attributes": {"position": mg.pack_numpy_array(self.positions.T)}}
        if self.index is not None:
            data["index"] = mg.pack_numpy_array(self.index.reshape(-1))
        return {"uuid": self.uuid, "type": "BufferGeometry", "data": data}


class _Material(mg.Material):
    """A three.js material given by its type and properties."""

    def __init__(self, key: str, kind: str, **properties):
        super().__init__()
        self.uuid = _stable_uuid(key, "material")
        self.kind = kind
        self.properties = properties

    def lower(self, object_data):
        return {"uuid": self.uuid, "type": self.kind, **self.properties}


class _Object(mg.Object):
    """A three.js object of any type (Mesh, LineSegments, Line, Points)."""

    def __init__(self, key: str, kind: str, geometry: mg.Geometry, material: mg.Material):
        super().__init__(geometry, material)
        self.uuid = _stable_uuid(key, "object")
        self._type = kind


class _Light(mg.Object):
    """A directional light (not expressible with meshcat-python's classes)."""

    def __init__(self, key: str, direction, intensity: float):
        mg.SceneElement.__init__(self)
        self.uuid = _stable_uuid(key, "light")
        d = np.asarray(direction, dtype=np.float64)
        self.position = d / np.linalg.norm(d)
        self.intensity = intensity

    def lower(self):
        matrix = np.eye(4)
        matrix[:3, 3] = self.position
        return {
            "metadata": {"version": 4.5, "type": "Object"},
            "object": {"uuid": self.uuid, "type": "DirectionalLight", "color": 0xFFFFFF,
                       "intensity": self.intensity,
                       "matrix": list(matrix.T.flatten())},
        }


def _material(layer: Layer, key: str) -> mg.Material:
    transparent = layer.opacity < 1.0
    common = {"color": layer.color, "opacity": layer.opacity, "transparent": transparent,
              "depthWrite": not transparent, "vertexColors": False}
    if layer.kind == "points":
        return _Material(key, "PointsMaterial", size=layer.size, sizeAttenuation=True, **common)
    if layer.kind in ("segments", "polyline"):
        return _Material(key, "LineBasicMaterial", linewidth=1.0, **common)
    if transparent:
        # drawn after the opaque layers without writing depth: pushed back a little so
        # that faces coinciding with an opaque layer's (a C-obstacle's top face on its
        # obstacle's) consistently lose instead of z-fighting
        common.update(polygonOffset=True, polygonOffsetFactor=1.0, polygonOffsetUnits=4.0)
    if layer.lit:
        # front faces only (meshes are closed and outward): meshcat makes every object
        # cast and receive shadows, and double-sided lit faces then show shadow-map acne
        return _Material(key, "MeshPhongMaterial", side=0, flatShading=True, shininess=20,
                         **common)
    return _Material(key, "MeshBasicMaterial", side=2, **common)


_OBJECT_TYPES = {"mesh": "Mesh", "segments": "LineSegments", "polyline": "Line",
                 "points": "Points"}


def layer_object(path: str, layer: Layer) -> mg.Object:
    """The meshcat object of one layer (geometry + material, merged into one buffer)."""
    geometry = _Geometry(path, layer.vertices, layer.faces)
    return _Object(path, _OBJECT_TYPES[layer.kind], geometry, _material(layer, path))


def _camera_commands(camera: Camera) -> list:
    # meshcat's orbit controls look at the world origin whatever the transform of
    # /Cameras/default, so the scene is shifted to put camera.target at the origin (see
    # commands()) and the camera sits at the `position` property of rotated/<object>,
    # in rotated's y-up frame: a world offset (x, y, z) is (x, z, -y) there.
    offset = np.asarray(camera.position, dtype=np.float64) - camera.target
    y_up = [float(offset[0]), float(offset[2]), float(-offset[1])]
    cam = _path("Cameras/default/rotated/<object>")
    return [
        SetTransform(np.eye(4), _path("Cameras/default")),
        SetProperty("position", y_up, cam),
        SetProperty("fov", float(camera.fov), cam),
        SetProperty("near", float(camera.near), cam),
        SetProperty("far", float(camera.far), cam),
    ]


def _grid_commands(bounds: np.ndarray | None, visible: bool, shift: np.ndarray) -> list:
    if not visible or bounds is None:
        return [SetProperty("visible", False, _path("Grid")),
                SetProperty("visible", False, _path("Axes"))]
    # meshcat's grid is 20 x 20 units in 40 divisions: scale it so that a division is
    # a round number near a sixth of the scene, centre it under the scene on a grid line
    extent = max(float(np.max(bounds[1] - bounds[0])), 1e-12)
    spacing = _round_125(extent / 6.0)
    scale = 2.0 * spacing
    centre = np.round(bounds.mean(axis=0) / spacing) * spacing
    grid = np.diag([scale, scale, scale, 1.0])
    grid[:3, 3] = np.array([centre[0], centre[1], bounds[0][2]]) + shift
    axes = np.diag([spacing, spacing, spacing, 1.0])  # axes half a division long
    axes[:3, 3] = shift  # at the world origin
    return [SetTransform(grid, _path("Grid")), SetTransform(axes, _path("Axes"))]


def _round_125(x: float) -> float:
    """The number of the form {1, 2, 5} x 10^k nearest to ``x`` (in ratio)."""
    k = math.floor(math.log10(x))
    candidates = [m * 10.0 ** e for e in (k - 1, k, k + 1) for m in (1.0, 2.0, 5.0)]
    return min(candidates, key=lambda c: abs(math.log(c / x)))


def on_demand(scene: Scene) -> list[str]:
    """Paths of the layers created hidden (their own flag off, e.g. the octree cells and
    the roadmap): a page loads them only when they are switched on."""
    return [path for path in scene.layers if scene.visibility.get(path) is False]


def staged_commands(scene: Scene) -> tuple[list, dict[str, list]]:
    """The commands that build ``scene``: those to run at once, in order, and per
    :func:`on_demand` layer the ones that create it (run them, then make it visible)."""
    later = set(on_demand(scene))
    out: list = [
        SetProperty("top_color", BACKGROUND_TOP, _path("Background")),
        SetProperty("bottom_color", BACKGROUND_BOTTOM, _path("Background")),
        SetObject(_Light("key", KEY_LIGHT_DIRECTION, KEY_LIGHT_INTENSITY),
                  path=_path("Lights/Key")),
        # meshcat's two point lights sit near the origin with a 10-unit range: inside the
        # (re-centred) scene they light faces from within; directional lights scale
        SetProperty("visible", False, _path("Lights/PointLightNegativeX")),
        SetProperty("visible", False, _path("Lights/PointLightPositiveX")),
    ]
    bounds = scene.bounds()
    camera = scene.camera
    if camera is None:
        camera = Camera.framing(bounds if bounds is not None else [[-1, -1, -1], [1, 1, 1]])
    # the whole scene is shifted by -target: meshcat orbits about the origin
    shift = -np.asarray(camera.target, dtype=np.float64)
    out += _grid_commands(bounds, scene.grid, shift)
    out += _camera_commands(camera)
    root = np.eye(4)
    root[:3, 3] = shift
    out.append(SetTransform(root, _path(ROOT)))
    for path, layer in scene.layers.items():
        if path not in later:
            out += _layer_commands(path, layer)
    for path, visible in scene.visibility.items():
        if path not in later:
            out.append(SetProperty("visible", bool(visible), _path(ROOT, path)))
    if scene.tracks:
        out.append(_animation(scene))
    return out, {path: _layer_commands(path, scene.layers[path]) for path in scene.layers
                 if path in later}


def commands(scene: Scene) -> list:
    """The meshcat commands that build ``scene`` in an empty viewer, in order (every
    layer, the hidden ones created hidden)."""
    now, later = staged_commands(scene)
    for path, created in later.items():
        now += [*created, SetProperty("visible", False, _path(ROOT, path))]
    return now


def _layer_commands(path: str, layer: Layer) -> list:
    node = _path(ROOT, path)
    out: list = [SetObject(layer_object(path, layer), path=node)]
    if not np.allclose(layer.transform, np.eye(4)):
        out.append(SetTransform(layer.transform, node))
    return out


def _animation(scene: Scene) -> SetAnimation:
    animation = Animation(default_framerate=FPS)
    for track in scene.tracks:
        node = _path(ROOT, track.path)
        for t, p in zip(track.times, track.positions):
            with animation.at_frame(_FakeVisualizer(node), float(t) * FPS) as frame:
                frame.set_property("position", "vector3", [float(x) for x in p])
    repetitions = ANIMATION_REPETITIONS if scene.loop else 1
    return SetAnimation(animation, play=True, repetitions=repetitions)


class _FakeVisualizer:
    """What ``Animation.at_frame`` needs of a visualizer: its path."""

    def __init__(self, path: MeshcatPath):
        self.path = path


def lowered(scene: Scene) -> list[dict]:
    """The commands as the dicts meshcat's viewer decodes."""
    return [c.lower() for c in commands(scene)]


def packed(scene: Scene) -> list[bytes]:
    """The commands msgpack-encoded, as meshcat's websocket and static HTML carry them."""
    return [umsgpack.packb(d) for d in lowered(scene)]
