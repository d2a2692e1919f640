"""The scene: one layout of named layers, as plain data (no meshcat, no transport).

A :class:`Scene` is a set of :class:`Layer` objects, each at its own path of meshcat's
scene tree (so every layer can be toggled in meshcat's controls), plus visibility flags,
translation animations (:class:`Track`) and an optional camera. Geometry is merged per
layer: all octree cells of one label are one line-segment, point or triangle buffer.

The layout every entry point uses (constants of this module)::

    workspace/obstacles/<name>    obstacle meshes                       OBSTACLES
    workspace/obstacles/<name>.edges  its creases, when it encloses the path (see_through)
    workspace/robot/start         robot at the start, ghosted           ROBOT_START
    workspace/robot/goal          robot at the goal, ghosted            ROBOT_GOAL
    workspace/robot/moving        robot animated along the path         ROBOT_MOVING
    cspace/c_obstacle[/<name>]    C-obstacle surface(s)                 C_OBSTACLE
    cspace/cells/empty|mixed|full octree leaves, merged per label       CELLS_EMPTY, ...
    cspace/roadmap                roadmap edges, one LineSegments       ROADMAP
    path                          the path: path/line and path/tube     PATH
    certificate/walls             FULL wall cells of a no-path proof    CERTIFICATE_WALLS
    certificate/component         the walled-off free cells             CERTIFICATE_COMPONENT
    minkowski/a, minkowski/b      operands of a plain Minkowski sum     MINKOWSKI_A, ...
    minkowski/sum                 the sum's surface                     MINKOWSKI_SUM

All layers live under meshcat's root ``/meshcat``. Hidden by default (toggle them in the
controls, or :meth:`Scene.set_visible`): the octree cells, the roadmap and the
certificate's component (:data:`HIDDEN_BY_DEFAULT`). An obstacle that holds the path, the
robot's start or goal or a certificate's walls inside its bounding box is drawn
translucent, its creases as lines (:meth:`Scene.see_through`). A layer's ``note`` says
what of it is drawn; :mod:`planner.viz.legend` collects them.

Inputs are plain arrays: meshes as ``trimesh.Trimesh``, cells as ``(n, 2, 3)`` boxes
``[lo, hi]`` with ``(n,)`` labels (0 EMPTY, 1 FULL, 2 MIXED, as the core numbers them,
or the strings), roadmap edges as ``(m, 2, 3)`` segments, a path as ``(k, 3)``
waypoints.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import trimesh

from planner.errors import InvalidParameterError

from . import shapes

__all__ = [
    "C_OBSTACLE",
    "CELLS",
    "CELLS_EMPTY",
    "CELLS_FULL",
    "CELLS_MIXED",
    "CERTIFICATE_COMPONENT",
    "CERTIFICATE_WALLS",
    "COLORS",
    "EMPTY",
    "FULL",
    "HIDDEN_BY_DEFAULT",
    "MINKOWSKI_A",
    "MINKOWSKI_B",
    "MINKOWSKI_SUM",
    "MIXED",
    "OBSTACLES",
    "PATH",
    "ROADMAP",
    "ROBOT_GOAL",
    "ROBOT_MOVING",
    "ROBOT_START",
    "Camera",
    "Layer",
    "Scene",
    "Track",
    "node_name",
]

# ---- the layout ------------------------------------------------------------------------

OBSTACLES = "workspace/obstacles"
ROBOT_START = "workspace/robot/start"
ROBOT_GOAL = "workspace/robot/goal"
ROBOT_MOVING = "workspace/robot/moving"
C_OBSTACLE = "cspace/c_obstacle"
CELLS = "cspace/cells"
CELLS_EMPTY = "cspace/cells/empty"
CELLS_MIXED = "cspace/cells/mixed"
CELLS_FULL = "cspace/cells/full"
ROADMAP = "cspace/roadmap"
PATH = "path"
CERTIFICATE_WALLS = "certificate/walls"
CERTIFICATE_COMPONENT = "certificate/component"
MINKOWSKI_A = "minkowski/a"
MINKOWSKI_B = "minkowski/b"
MINKOWSKI_SUM = "minkowski/sum"

HIDDEN_BY_DEFAULT = frozenset({CELLS_EMPTY, CELLS_MIXED, CELLS_FULL, ROADMAP,
                               CERTIFICATE_COMPONENT})
"""Layers created hidden (they are dense); every other layer starts visible."""

# octree labels, as the native core numbers them
EMPTY, FULL, MIXED = 0, 1, 2
_LABEL_NAMES = {"empty": EMPTY, "full": FULL, "mixed": MIXED}
_CELL_PATHS = {EMPTY: CELLS_EMPTY, MIXED: CELLS_MIXED, FULL: CELLS_FULL}

COLORS: dict[str, int] = {
    "obstacle": 0xE8701A,  # orange: the screenshot test looks for this hue
    "robot_start": 0x2DA44E,
    "robot_goal": 0x2F6FDE,
    "robot_moving": 0x1B7F3B,
    "robot_collision": 0xD0021B,
    "c_obstacle": 0x5B8DEF,
    "cells_empty": 0x43A047,
    "cells_mixed": 0xF2B705,
    "cells_full": 0x8D6E63,
    "roadmap": 0x00A3BF,
    "path": 0xE6007E,  # magenta: the screenshot test looks for this hue
    "walls": 0xC62828,
    "component": 0x7E57C2,
    "operand_a": 0xE8701A,
    "operand_b": 0x2DA44E,
    "sum": 0x5B8DEF,
}
"""Colour of each kind of layer, ``0xRRGGBB``."""

GHOST_OPACITY = 0.35
C_OBSTACLE_OPACITY = 0.3
WALL_OPACITY = 0.55
CELL_FACE_OPACITY = 0.25
ENCLOSING_OPACITY = 0.4
"""Opacity of an obstacle that encloses the path, the robot or a certificate (see
:meth:`Scene.see_through`)."""
CREASE_DEGREES = 30.0
"""Edges where faces meet at more than this are drawn on a translucent obstacle."""
TUBE_RADIUS_FRACTION = 0.004
"""Default path-tube radius as a fraction of the scene's bounding-box diagonal."""
MAX_CELL_EDGES = 20_000
"""``style="auto"`` draws up to this many cells as box edges, more as centre points."""

DEFAULT_VIEW = (1.0, -1.6, 1.1)
"""Direction from the scene's centre towards the default camera (world, z up)."""

_SEGMENT = re.compile(r"^[A-Za-z0-9_.\-]+$")


# ---- plain data ------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Layer:
    """One object of the scene tree.

    Attributes:
        path: scene path below the root, e.g. ``"cspace/roadmap"``.
        kind: ``"mesh"`` (``vertices`` ``(n, 3)`` with ``faces`` ``(m, 3)``),
            ``"segments"`` (``vertices`` ``(2 m, 3)``: consecutive pairs), ``"polyline"``
            (``vertices`` ``(k, 3)`` joined in order) or ``"points"`` (``(n, 3)``).
        vertices: float64 coordinates in the layer's frame.
        faces: ``(m, 3)`` vertex indices for meshes, else ``None``.
        color: ``0xRRGGBB``.
        opacity: 1 opaque .. 0 invisible.
        lit: shaded by the scene's lights (meshes); unlit meshes show ``color`` exactly.
        size: point size in scene units (points only).
        transform: ``(4, 4)`` pose of the layer's node.
        count: what the layer stands for (cells, edges, waypoints), for captions.
        note: what is drawn, in words, when it is not simply the whole thing (e.g.
            "the 40,000 segments nearest the path, of 612,442"); the page's legend shows
            it.
    """

    path: str
    kind: str
    vertices: np.ndarray
    faces: np.ndarray | None = None
    color: int = 0xFFFFFF
    opacity: float = 1.0
    lit: bool = True
    size: float = 1.0
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    count: int = 0
    note: str = ""

    def world_bounds(self) -> np.ndarray | None:
        """``(2, 3)`` axis-aligned bounds in the world, or ``None`` if empty."""
        if len(self.vertices) == 0:
            return None
        lo, hi = self.vertices.min(axis=0), self.vertices.max(axis=0)
        corners = shapes.box_corners(np.array([[lo, hi]]))[0]
        world = corners @ self.transform[:3, :3].T + self.transform[:3, 3]
        bounds = np.array([world.min(axis=0), world.max(axis=0)])
        if self.kind == "points":
            bounds += np.array([[-1.0], [1.0]]) * 0.5 * self.size
        return bounds


@dataclass(frozen=True, eq=False)
class Track:
    """A node translated along ``positions`` ``(k, 3)`` at ``times`` ``(k,)`` seconds
    (non-decreasing, starting at 0), linearly between keys."""

    path: str
    times: np.ndarray
    positions: np.ndarray


@dataclass(frozen=True, eq=False)
class Camera:
    """Where the camera looks from: ``position`` ``(3,)`` and ``target`` ``(3,)`` in the
    world (z up); the user orbits about ``target``. ``fov``: vertical field of view in
    degrees; ``near``/``far``: clip planes."""

    position: np.ndarray
    target: np.ndarray
    near: float
    far: float
    fov: float = 45.0

    @classmethod
    def framing(cls, bounds, direction=DEFAULT_VIEW, fov_deg: float = 45.0,
                margin: float = 1.05) -> Camera:
        """A camera looking at the centre of ``bounds`` ``(2, 3)`` from ``direction``,
        far enough that the bounding sphere fits the (vertical) field of view."""
        b = np.asarray(bounds, dtype=np.float64).reshape(2, 3)
        centre = b.mean(axis=0)
        radius = max(0.5 * float(np.linalg.norm(b[1] - b[0])), 1e-9)
        d = np.asarray(direction, dtype=np.float64)
        d = d / np.linalg.norm(d)
        distance = margin * radius / math.sin(math.radians(fov_deg) / 2.0)
        return cls(position=centre + distance * d, target=centre,
                   near=distance / 1000.0, far=10.0 * (distance + radius), fov=float(fov_deg))


def _check_path(path: str) -> str:
    parts = [p for p in str(path).split("/") if p]
    if not parts or not all(_SEGMENT.match(p) for p in parts):
        raise InvalidParameterError(
            f"scene path {path!r}: use '/'-separated names of letters, digits, '_', '.', '-'")
    return "/".join(parts)


def node_name(name: str) -> str:
    """``name`` made usable as one segment of a scene path (other characters -> ``_``)."""
    cleaned = re.sub(r"[^A-Za-z0-9_.\-]", "_", str(name)).strip("_") or "unnamed"
    return cleaned


def _points(value, what: str) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if array.size == 0:
        return np.zeros((0, 3))
    if array.ndim != 2 or array.shape[1] != 3:
        raise InvalidParameterError(f"{what}: expected shape (n, 3), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidParameterError(f"{what}: values must be finite")
    return array


def _segments(value, what: str) -> np.ndarray:
    array = np.asarray(value, dtype=np.float64)
    if array.size == 0:
        return np.zeros((0, 2, 3))
    if array.ndim != 3 or array.shape[1:] != (2, 3):
        raise InvalidParameterError(f"{what}: expected shape (m, 2, 3), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidParameterError(f"{what}: values must be finite")
    return array


def _boxes(value, what: str) -> np.ndarray:
    array = _segments(value, what)
    if np.any(array[:, 1] < array[:, 0]):
        raise InvalidParameterError(f"{what}: every box must be [lo, hi] with lo <= hi")
    return array


def _labels(value, n: int) -> np.ndarray:
    raw = np.asarray(value)
    if raw.shape != (n,):
        raise InvalidParameterError(f"cell labels: expected shape ({n},), got {raw.shape}")
    if raw.dtype.kind in "US":
        try:
            return np.array([_LABEL_NAMES[str(s).lower()] for s in raw], dtype=np.int64)
        except KeyError as err:
            raise InvalidParameterError(
                f"cell labels: unknown label {err.args[0]!r} (empty, mixed, full)") from None
    labels = raw.astype(np.int64)
    if np.any((labels < 0) | (labels > 2)):
        raise InvalidParameterError("cell labels: expected 0 (EMPTY), 1 (FULL) or 2 (MIXED)")
    return labels


def _mesh_arrays(mesh) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(mesh, trimesh.Trimesh):
        inner = getattr(mesh, "mesh", None)  # a MinkowskiResult, a Body, a Robot
        if isinstance(inner, trimesh.Trimesh):
            mesh = inner
        else:
            raise InvalidParameterError(
                f"expected a trimesh.Trimesh (or an object with .mesh), got {type(mesh).__name__}")
    return (np.asarray(mesh.vertices, dtype=np.float64),
            np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3))


def _any_inside(points: np.ndarray, bounds: np.ndarray) -> bool:
    """Whether any of ``points`` ``(n, 3)`` lies strictly inside ``bounds`` ``(2, 3)``
    (by more than a millionth of the box's size: a point on a face is not enclosed)."""
    margin = 1e-6 * float(np.max(bounds[1] - bounds[0]))
    inside = np.all((points > bounds[0] + margin) & (points < bounds[1] - margin), axis=1)
    return bool(np.any(inside))


def _creases(layer: Layer) -> np.ndarray:
    """``(m, 2, 3)`` edges of a mesh layer where its faces meet at more than
    :data:`CREASE_DEGREES`, and its open edges."""
    mesh = trimesh.Trimesh(layer.vertices, layer.faces, process=True)
    sharp = mesh.face_adjacency_edges[mesh.face_adjacency_angles > math.radians(CREASE_DEGREES)]
    open_edges = mesh.edges_sorted[trimesh.grouping.group_rows(mesh.edges_sorted, require_count=1)]
    return mesh.vertices[np.vstack([sharp.reshape(-1, 2), open_edges.reshape(-1, 2)])]


def _translation(t) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = np.asarray(t, dtype=np.float64).reshape(3)
    return matrix


def _named(items) -> list[tuple[str, object]]:
    """``items`` as ``(name, mesh)`` pairs: a mapping, ``Body``-like objects with
    ``.name``/``.mesh``, ``(name, mesh)`` pairs or bare meshes (named ``0``, ``1``...)."""
    if items is None:
        return []
    if isinstance(items, Mapping):
        return [(str(k), v) for k, v in items.items()]
    if isinstance(items, trimesh.Trimesh) or hasattr(items, "mesh"):
        items = [items]
    out: list[tuple[str, object]] = []
    for i, item in enumerate(items):
        if isinstance(item, tuple) and len(item) == 2:
            out.append((str(item[0]), item[1]))
        elif hasattr(item, "name") and hasattr(item, "mesh"):
            out.append((str(item.name), item.mesh))
        else:
            out.append((str(i), item))
    return out


# ---- the scene -------------------------------------------------------------------------

class Scene:
    """A meshcat scene as plain data: layers at scene paths, visibility, animation.

    Build it with the generic ``add_*`` methods (any path) or the layout methods
    (:meth:`add_obstacles`, :meth:`add_robot`, :meth:`add_c_obstacle`,
    :meth:`add_cells`, :meth:`add_roadmap`, :meth:`add_path`, :meth:`add_motion`,
    :meth:`add_certificate`); render it with :func:`planner.viz.to_html`,
    :func:`planner.viz.show` or :func:`planner.viz.serve`. Adding at an existing path
    replaces that layer. Not thread-safe (build it in one thread).

    Attributes:
        title: page title.
        layers: ``{path: Layer}`` in insertion order.
        visibility: ``{path: visible}`` for layers and group nodes (``"cspace"``).
        tracks: translation animations (:class:`Track`), played together.
        camera: explicit :class:`Camera`, or ``None``: frame the visible layers.
        grid: show meshcat's grid (scaled to the scene, under it).
        loop: repeat the animation (else it plays once).
    """

    def __init__(self, title: str = "minkplan") -> None:
        self.title = str(title)
        self.layers: dict[str, Layer] = {}
        self.visibility: dict[str, bool] = {}
        self.tracks: list[Track] = []
        self.camera: Camera | None = None
        self.grid = True
        self.loop = True

    # ---- generic layers ----------------------------------------------------------------

    def _add(self, layer: Layer) -> Layer:
        path = _check_path(layer.path)
        for other in list(self.layers):  # a layer cannot also be a group of layers
            if other.startswith(path + "/") or path.startswith(other + "/"):
                del self.layers[other]
        self.layers.pop(path, None)
        self.layers[path] = layer
        if path in HIDDEN_BY_DEFAULT:
            self.visibility.setdefault(path, False)
        return layer

    def add_mesh(self, path: str, mesh, *, color: int, opacity: float = 1.0, lit: bool = True,
                 transform=None, note: str = "") -> Layer:
        """A triangle mesh (``trimesh.Trimesh`` or anything with ``.mesh``)."""
        vertices, faces = _mesh_arrays(mesh)
        return self.add_triangles(path, vertices, faces, color=color, opacity=opacity, lit=lit,
                                  transform=transform, count=len(faces), note=note)

    def add_triangles(self, path: str, vertices, faces, *, color: int, opacity: float = 1.0,
                      lit: bool = True, transform=None, count: int | None = None,
                      note: str = "") -> Layer:
        """A triangle mesh from vertices ``(n, 3)`` and faces ``(m, 3)``."""
        v = _points(vertices, f"{path}: vertices")
        f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        if len(f) and (f.min() < 0 or f.max() >= len(v)):
            raise InvalidParameterError(f"{path}: face index out of range")
        return self._add(Layer(path, "mesh", v, f, int(color), float(opacity), bool(lit),
                               transform=self._transform(transform),
                               count=len(f) if count is None else int(count), note=note))

    def add_segments(self, path: str, segments, *, color: int, opacity: float = 1.0,
                     count: int | None = None, note: str = "") -> Layer:
        """Line segments ``(m, 2, 3)`` as ONE LineSegments object."""
        s = _segments(segments, f"{path}: segments")
        return self._add(Layer(path, "segments", s.reshape(-1, 3), None, int(color),
                               float(opacity), False,
                               count=len(s) if count is None else int(count), note=note))

    def add_polyline(self, path: str, points, *, color: int, opacity: float = 1.0,
                     note: str = "") -> Layer:
        """An open polyline through ``(k, 3)`` points."""
        p = _points(points, f"{path}: points")
        return self._add(Layer(path, "polyline", p, None, int(color), float(opacity), False,
                               count=len(p), note=note))

    def add_points(self, path: str, points, *, color: int, size: float,
                   opacity: float = 1.0, count: int | None = None, note: str = "") -> Layer:
        """Points ``(n, 3)`` drawn as squares of ``size`` scene units."""
        p = _points(points, f"{path}: points")
        if not (math.isfinite(size) and size > 0):
            raise InvalidParameterError(f"{path}: point size must be positive, got {size!r}")
        return self._add(Layer(path, "points", p, None, int(color), float(opacity), False,
                               size=float(size), count=len(p) if count is None else int(count),
                               note=note))

    def add_boxes(self, path: str, boxes, *, color: int, style: str = "auto",
                  opacity: float | None = None, max_edges: int = MAX_CELL_EDGES) -> Layer | None:
        """Boxes ``(n, 2, 3)`` merged into one object: ``style`` ``"edges"`` (one
        LineSegments), ``"faces"`` (one triangle mesh), ``"points"`` (centres) or
        ``"auto"`` (edges up to ``max_edges`` boxes, else points). ``None`` if no box."""
        b = _boxes(boxes, f"{path}: boxes")
        if len(b) == 0:
            return None
        if style == "auto":
            style = "edges" if len(b) <= max_edges else "points"
        if style == "edges":
            return self.add_segments(path, shapes.box_edges(b), color=color,
                                     opacity=1.0 if opacity is None else opacity, count=len(b),
                                     note=f"{len(b):,}, drawn as box edges")
        if style == "faces":
            vertices, faces = shapes.box_faces(b)
            return self.add_triangles(path, vertices, faces, color=color,
                                      opacity=CELL_FACE_OPACITY if opacity is None else opacity,
                                      count=len(b), note=f"{len(b):,}, drawn as boxes")
        if style == "points":
            size = float(np.median(np.max(b[:, 1] - b[:, 0], axis=1))) * 0.35
            note = f"{len(b):,}, drawn as centre points"
            if len(b) > max_edges:
                note += f" (over {max_edges:,}, too many for edges)"
            return self.add_points(path, b.mean(axis=1), color=color, size=max(size, 1e-12),
                                   opacity=1.0 if opacity is None else opacity, count=len(b),
                                   note=note)
        raise InvalidParameterError(
            f"box style {style!r}: use 'auto', 'edges', 'faces' or 'points'")

    def set_visible(self, path: str, visible: bool = True) -> None:
        """Show or hide the node at ``path`` (a layer or a group such as ``"cspace"``)."""
        self.visibility[_check_path(path)] = bool(visible)

    def is_visible(self, path: str) -> bool:
        """Whether ``path`` and all its ancestors are visible."""
        parts = _check_path(path).split("/")
        return all(self.visibility.get("/".join(parts[:i]), True)
                   for i in range(1, len(parts) + 1))

    def animate(self, path: str, times, positions) -> Track:
        """Translate the node at ``path`` through ``positions`` ``(k, 3)`` at ``times``
        ``(k,)`` seconds."""
        p = _points(positions, f"{path}: positions")
        t = np.asarray(times, dtype=np.float64).reshape(-1)
        if len(t) != len(p) or len(p) == 0:
            raise InvalidParameterError(f"{path}: need as many times as positions (>= 1)")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0) or t[0] < 0:
            raise InvalidParameterError(f"{path}: times must be finite, >= 0, non-decreasing")
        track = Track(_check_path(path), t, p)
        self.tracks = [tr for tr in self.tracks if tr.path != track.path] + [track]
        return track

    @staticmethod
    def _transform(transform) -> np.ndarray:
        if transform is None:
            return np.eye(4)
        m = np.asarray(transform, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise InvalidParameterError(
                f"transform: expected a finite (4, 4) matrix, got {m.shape}")
        return m

    # ---- the layout --------------------------------------------------------------------

    def add_obstacles(self, obstacles) -> list[Layer]:
        """Obstacles at ``workspace/obstacles/<name>``: a mapping ``{name: mesh}``,
        ``Body``-like objects (``.name``, ``.mesh``), ``(name, mesh)`` pairs or meshes."""
        return [self.add_mesh(f"{OBSTACLES}/{node_name(name)}", mesh, color=COLORS["obstacle"])
                for name, mesh in _named(obstacles)]

    def add_robot(self, robot, start=None, goal=None, *, start_color: int | None = None,
                  goal_color: int | None = None) -> list[Layer]:
        """The robot (its own frame; at ``t`` it occupies ``robot + t``) ghosted at
        ``start`` and ``goal`` ``(3,)`` (each optional)."""
        layers = []
        for path, where, color in ((ROBOT_START, start, start_color or COLORS["robot_start"]),
                                   (ROBOT_GOAL, goal, goal_color or COLORS["robot_goal"])):
            if where is not None:
                layers.append(self.add_mesh(path, robot, color=color, opacity=GHOST_OPACITY,
                                            transform=_translation(where)))
        return layers

    def add_c_obstacle(self, c_obstacle, *, note: str = "") -> list[Layer]:
        """C-obstacle surface(s): one mesh (or ``MinkowskiResult``) at
        ``cspace/c_obstacle``, or a mapping ``{name: mesh}`` at
        ``cspace/c_obstacle/<name>``."""
        if c_obstacle is None:
            return []
        if isinstance(c_obstacle, Mapping):
            return [self.add_mesh(f"{C_OBSTACLE}/{node_name(n)}", m, color=COLORS["c_obstacle"],
                                  opacity=C_OBSTACLE_OPACITY, note=note)
                    for n, m in c_obstacle.items()]
        return [self.add_mesh(C_OBSTACLE, c_obstacle, color=COLORS["c_obstacle"],
                              opacity=C_OBSTACLE_OPACITY, note=note)]

    def add_cells(self, boxes, labels, *, style: str = "auto",
                  max_edges: int = MAX_CELL_EDGES) -> list[Layer]:
        """Octree leaves ``(n, 2, 3)`` with ``(n,)`` labels, one merged object per label
        at ``cspace/cells/empty|mixed|full`` (see :meth:`add_boxes` for ``style``)."""
        b = _boxes(boxes, "cells")
        lab = _labels(labels, len(b))
        layers = []
        for label, path in _CELL_PATHS.items():
            name = path.rsplit("/", 1)[1]
            layer = self.add_boxes(path, b[lab == label], color=COLORS[f"cells_{name}"],
                                   style=style, max_edges=max_edges)
            if layer is not None:
                layers.append(layer)
        return layers

    def add_roadmap(self, segments) -> Layer | None:
        """Roadmap edges ``(m, 2, 3)`` as one LineSegments at ``cspace/roadmap``."""
        s = _segments(segments, "roadmap")
        return self.add_segments(ROADMAP, s, color=COLORS["roadmap"]) if len(s) else None

    def add_path(self, waypoints, *, radius: float | None = None) -> list[Layer]:
        """The path ``(k, 3)``: a polyline at ``path/line`` and a tube at ``path/tube``
        (``radius`` default: :data:`TUBE_RADIUS_FRACTION` of the diagonal of the visible
        layers and the path)."""
        p = _points(waypoints, "path waypoints")
        if len(p) == 0:
            return []
        if radius is None:
            bounds = self.bounds()
            both = p if bounds is None else np.vstack([bounds, p])
            diagonal = float(np.linalg.norm(both.max(axis=0) - both.min(axis=0)))
            radius = TUBE_RADIUS_FRACTION * diagonal if diagonal > 0 else 1e-3
        vertices, faces = shapes.tube(p, radius)
        return [
            self.add_polyline(f"{PATH}/line", p, color=COLORS["path"],
                              note=f"{len(p):,} waypoints"),
            self.add_triangles(f"{PATH}/tube", vertices, faces, color=COLORS["path"], lit=False,
                               count=len(p)),
        ]

    def add_motion(self, robot, waypoints, *, seconds: float | None = None) -> Layer | None:
        """The robot moving along ``waypoints`` ``(k, 3)`` at constant speed, at
        ``workspace/robot/moving`` (``seconds``: duration, default 2 + 4 per scene
        diagonal travelled, capped at 20)."""
        p = _points(waypoints, "motion waypoints")
        if len(p) == 0:
            return None
        layer = self.add_mesh(ROBOT_MOVING, robot, color=COLORS["robot_moving"],
                              transform=_translation(p[0]),
                              note="along the path (play it under Open Controls > Animations)")
        step = np.linalg.norm(np.diff(p, axis=0), axis=1)
        arc = np.concatenate([[0.0], np.cumsum(step)])
        if seconds is None:
            bounds = self.bounds()
            diagonal = 1.0 if bounds is None else float(np.linalg.norm(bounds[1] - bounds[0]))
            seconds = min(2.0 + 4.0 * arc[-1] / max(diagonal, 1e-12), 20.0)
        times = arc / arc[-1] * float(seconds) if arc[-1] > 0 else np.zeros(len(p))
        self.animate(ROBOT_MOVING, times, p)
        return layer

    def add_certificate(self, walls, component=None) -> list[Layer]:
        """A no-path certificate: wall cells ``(n, 2, 3)`` as one translucent mesh at
        ``certificate/walls``; optionally the walled-off component's cells at
        ``certificate/component`` (hidden by default)."""
        added = [self.add_boxes(CERTIFICATE_WALLS, _boxes(walls, "certificate walls"),
                                color=COLORS["walls"], style="faces", opacity=WALL_OPACITY)]
        if component is not None:
            added.append(self.add_boxes(CERTIFICATE_COMPONENT,
                                        _boxes(component, "certificate component"),
                                        color=COLORS["component"]))
        return [layer for layer in added if layer is not None]

    def see_through(self, points) -> list[Layer]:
        """Draw translucent, outlined by its creases, every obstacle whose bounding box
        holds one of ``points`` ``(n, 3)`` (the path, the robot's start and goal, a
        certificate's walls) strictly inside: an enclosing obstacle would hide them. The
        creases (edges where faces meet at more than :data:`CREASE_DEGREES`) are a layer
        ``<obstacle>.edges`` beside it. Returns the layers changed or added."""
        p = _points(points, "see-through points")
        changed = []
        for path, layer in list(self.layers.items()):
            bounds = layer.world_bounds()
            if (not path.startswith(OBSTACLES + "/") or layer.kind != "mesh"
                    or bounds is None or len(p) == 0 or not _any_inside(p, bounds)):
                continue
            note = (f"{path.rsplit('/', 1)[-1]} translucent with its edges drawn: it "
                    f"encloses the path or the robot")
            self.layers[path] = dataclasses.replace(layer, opacity=ENCLOSING_OPACITY, note=note)
            edges = self.add_segments(f"{path}.edges", _creases(layer), color=layer.color,
                                      note=note)
            self.layers[f"{path}.edges"] = dataclasses.replace(edges, transform=layer.transform)
            changed += [self.layers[path], self.layers[f"{path}.edges"]]
        return changed

    # ---- framing -----------------------------------------------------------------------

    def bounds(self, *, visible_only: bool = True) -> np.ndarray | None:
        """``(2, 3)`` bounds of the (visible) layers, ``None`` when there is nothing."""
        boxes = [b for path, layer in self.layers.items()
                 if (not visible_only or self.is_visible(path))
                 and (b := layer.world_bounds()) is not None]
        if not boxes:
            return None
        stacked = np.array(boxes)
        return np.array([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])

    def frame(self, direction=DEFAULT_VIEW, *, margin: float = 1.05) -> Camera:
        """Set :attr:`camera` to look at the visible layers from ``direction``."""
        bounds = self.bounds()
        if bounds is None:
            bounds = np.array([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]])
        self.camera = Camera.framing(bounds, direction, margin=margin)
        return self.camera

    def paths(self) -> list[str]:
        """Every layer path."""
        return list(self.layers)

    def summary(self) -> dict[str, dict]:
        """``{path: {"kind", "count", "visible"}}``, e.g. for captions and tests."""
        return {p: {"kind": layer.kind, "count": layer.count, "visible": self.is_visible(p)}
                for p, layer in self.layers.items()}

    def __repr__(self) -> str:
        return f"<Scene {self.title!r}: {len(self.layers)} layers: {', '.join(self.layers)}>"

    def _repr_html_(self) -> str:  # Jupyter: a Scene as a cell's value renders inline
        from .html import notebook_html

        return notebook_html(self)

