"""Import OMPL.app rigid-body (SE(3)) problems as translational scenarios.

An OMPL.app problem is an INI file (``NAME.cfg``) whose ``[problem]`` section names a
robot and a world mesh (COLLADA ``.dae``, paths relative to the ``.cfg``), a start and a
goal pose (``start.x/y/z``, ``start.axis.x/y/z``, ``start.theta`` in radians; same for
``goal``) and the bounds of the robot's position (``volume.min.x`` ... ``volume.max.z``).

Entry points:

- :func:`load_omplapp` -- a ``.cfg`` file to a :class:`~planner.problem.Scenario`.
- :func:`read_app_mesh` -- a COLLADA file's triangles in OMPL.app's frame, as loaded.
- :func:`robot_reference_point` -- OMPL.app's reference point of a robot mesh.
- :func:`read_omplapp_path` / :func:`path_state_transform` -- OMPL.app solution files
  (rows ``x y z qx qy qz qw``) and the ``(4, 4)`` pose of one row.

Frames (checked against OMPL.app's reference solutions in ``tests/test_omplapp.py``):

- OMPL.app reads meshes through assimp, which turns a ``Z_UP`` COLLADA file into its
  Y-up frame: a file point ``(x, y, z)`` is at ``(x, z, -y)`` in the app frame
  (:data:`APP_FROM_ZUP`). Every number in the ``.cfg`` is in the app frame.
- The robot's reference point is the mean of all its vertices (assimp's vertex
  arrays: node transforms applied, nothing merged), in the app frame. A state
  ``(p, R)`` places a robot vertex ``v`` at ``R @ (v - c) + p``.

Because minkplan only translates the robot, the goal orientation must equal the start
orientation (true of the OMPL.app problems it was written for); the start orientation
is applied to the robot mesh once.

Meshes: the SketchUp exports OMPL.app ships have every triangle twice, once per side,
so none is a closed manifold as loaded. The importer keeps one triangle of each such
pair, splits the world into connected pieces and checks each with
:func:`planner.meshes.validate_solid`. A shell whose only defects are pairs of facing
openings with the walls between them missing (a hole through a slab, modelled as a hole
in its top and one in its bottom face) gets those walls added and is a solid; any other
piece that is not a solid (open, flat, or closed with inverted faces, as Easy's frame)
is a *surface*: its triangles as imported, colliding where triangles meet, as OMPL.app
and FCL see every mesh. ``Scenario.notes`` records each such decision.
"""

from __future__ import annotations

import configparser
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from trimesh import transformations as tf

from planner.errors import InvalidMeshError, ScenarioError
from planner.meshes import load_mesh, validate_solid
from planner.problem import Body, PlannerSettings, Robot, Scenario, default_bounds
from planner.tolerances import scale_of, tol

__all__ = [
    "APP_FROM_ZUP",
    "load_omplapp",
    "path_state_transform",
    "read_app_mesh",
    "read_omplapp_path",
    "robot_reference_point",
]

APP_FROM_ZUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""Rotation from a Z-up COLLADA file's frame to OMPL.app's (assimp's Y-up) frame:
``app = APP_FROM_ZUP @ file``, i.e. ``(x, y, z) -> (x, z, -y)``."""



# ------------------------------------------------------------------------------ meshes


def _up_axis(path: Path) -> str:
    """The ``<up_axis>`` of a COLLADA file (``Y_UP`` when absent, as the spec says)."""
    head = path.read_bytes()[:65536].decode("utf-8", errors="replace")
    asset = head.split("</asset>", 1)[0]
    match = re.search(r"<up_axis>\s*([XYZ]_UP)\s*</up_axis>", asset)
    unit = re.search(r"<unit\b[^>]*\bmeter\s*=\s*\"([^\"]+)\"", asset)
    if unit is not None and not math.isclose(float(unit.group(1)), 1.0):
        raise InvalidMeshError(
            f"mesh file '{path}': COLLADA <unit meter=\"{unit.group(1)}\"> is not supported "
            "by the OMPL.app importer (only unscaled files have been checked against "
            "OMPL.app)")
    return match.group(1) if match else "Y_UP"


def read_app_mesh(path: str | os.PathLike[str]) -> trimesh.Trimesh:
    """All triangles of a COLLADA file, in OMPL.app's frame, exactly as loaded.

    Node transforms are applied; vertices are not merged and duplicate faces are kept
    (so the vertex mean is OMPL.app's reference point, see
    :func:`robot_reference_point`). ``Z_UP`` files are turned by :data:`APP_FROM_ZUP`;
    ``Y_UP`` files are used as they are.

    Raises:
        InvalidMeshError: unreadable file, no triangles, ``X_UP`` or a scaled ``<unit>``.
    """
    path = Path(path)
    mesh = load_mesh(path)
    axis = _up_axis(path)
    if axis == "Z_UP":
        mesh.vertices = mesh.vertices @ APP_FROM_ZUP.T
    elif axis != "Y_UP":
        raise InvalidMeshError(f"mesh file '{path}': up axis {axis} is not supported by the "
                               "OMPL.app importer")
    return mesh


def robot_reference_point(mesh: trimesh.Trimesh) -> np.ndarray:
    """OMPL.app's reference point of a robot mesh from :func:`read_app_mesh`: the mean
    of its vertices, ``(3,)``. (assimp's vertex arrays may hold each corner a different
    number of times than trimesh's; on the shipped problems the two means agree to
    ``2e-4``, far below their clearances.)"""
    return np.asarray(mesh.vertices, dtype=np.float64).mean(axis=0)


def _single_sided(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int]:
    """Merge coincident vertices and keep one triangle of every group of triangles on
    the same three vertices (double-sided exports). Returns the mesh and how many
    triangles were dropped."""
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    faces = np.asarray(merged.faces, dtype=np.int64)
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    keep = np.sort(first)
    return trimesh.Trimesh(merged.vertices, faces[keep], process=False), len(faces) - len(keep)


def _pieces(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    """Edge-connected pieces, in order of their first face."""
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency,
                                                      node_count=len(mesh.faces))
    _, first = np.unique(labels, return_index=True)
    pieces = []
    for label in labels[np.sort(first)]:
        piece = trimesh.Trimesh(mesh.vertices, mesh.faces[labels == label], process=False)
        piece.remove_unreferenced_vertices()
        pieces.append(piece)
    return pieces


def _thickness(points: np.ndarray) -> float:
    """Smallest extent of a point set over all directions (0 for coplanar points)."""
    centred = points - points.mean(axis=0)
    return float(np.linalg.svd(centred, compute_uv=False)[-1]) if len(points) > 3 else 0.0


def _boundary_loops(faces: np.ndarray) -> list[list[int]] | None:
    """Cycles of boundary edges (edges of one face), or None if they are not simple
    cycles (a vertex on more than two boundary edges)."""
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = unique[counts == 1]
    neighbours: dict[int, list[int]] = {}
    for a, b in boundary.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    if any(len(n) != 2 for n in neighbours.values()):
        return None
    loops, seen = [], set()
    for start in sorted(neighbours):
        if start in seen:
            continue
        loop, previous, current = [start], None, start
        seen.add(start)
        while True:
            a, b = neighbours[current]
            following = b if a == previous else a
            if following == start:
                break
            if following in seen:
                return None
            loop.append(following)
            seen.add(following)
            previous, current = current, following
        loops.append(loop)
    return loops


def _loop_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid, unit normal and out-of-plane spread of a loop's points."""
    centre = points.mean(axis=0)
    _, singular, vt = np.linalg.svd(points - centre)
    return centre, vt[-1], float(singular[-1])


def _bridge(vertices: np.ndarray, a: list[int], b: list[int], normal: np.ndarray) -> np.ndarray:
    """Triangles joining two facing loops (a band, like the wall of a drilled hole).

    Both loops are put in the same rotational sense about ``normal`` and started at the
    closest pair of vertices; the band then advances along whichever loop gives the
    shorter diagonal. Winding is left to :func:`planner.meshes.validate_solid`.
    """
    def sense(loop: list[int]) -> float:
        p = vertices[loop]
        return float(np.dot(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0), normal))

    if (sense(a) > 0) != (sense(b) > 0):
        b = b[::-1]
    distances = np.linalg.norm(vertices[a][:, None] - vertices[b][None], axis=2)
    i0, j0 = np.unravel_index(np.argmin(distances), distances.shape)
    a = a[i0:] + a[:i0] + [a[i0]]
    b = b[j0:] + b[:j0] + [b[j0]]
    i = j = 0
    triangles = []
    while i < len(a) - 1 or j < len(b) - 1:
        advance_a = j == len(b) - 1 or (
            i < len(a) - 1
            and np.linalg.norm(vertices[a[i + 1]] - vertices[b[j]])
            <= np.linalg.norm(vertices[a[i]] - vertices[b[j + 1]]))
        if advance_a:
            triangles.append((a[i], a[i + 1], b[j]))
            i += 1
        else:
            triangles.append((a[i], b[j + 1], b[j]))
            j += 1
    return np.array(triangles, dtype=np.int64)


def _bridge_openings(piece: trimesh.Trimesh) -> tuple[trimesh.Trimesh, int] | None:
    """Close a piece whose boundary loops come in facing pairs (planar, parallel, their
    outlines overlapping, closer together than their size) by joining each pair with a
    band. Returns ``(mesh, pairs)`` or None when the boundary is not of that kind."""
    vertices = np.asarray(piece.vertices, dtype=np.float64)
    faces = np.asarray(piece.faces, dtype=np.int64)
    loops = _boundary_loops(faces)
    if not loops or len(loops) % 2:
        return None
    planes = [_loop_plane(vertices[loop]) for loop in loops]
    sizes = [float(np.ptp(vertices[loop], axis=0).max()) for loop in loops]
    if any(spread > tol.planar_rel * size for (_, _, spread), size in zip(planes, sizes)):
        return None  # a loop that is not planar

    def overlap(i: int, j: int) -> float:
        # overlap of the two outlines' boxes in the plane, relative to the smaller one
        normal = planes[i][1]
        basis = np.linalg.svd(np.eye(3) - np.outer(normal, normal))[0][:, :2]
        pi, pj = vertices[loops[i]] @ basis, vertices[loops[j]] @ basis
        lo = np.maximum(pi.min(0), pj.min(0))
        hi = np.minimum(pi.max(0), pj.max(0))
        inter = float(np.prod(np.clip(hi - lo, 0, None)))
        smaller = min(float(np.prod(np.ptp(pi, 0))), float(np.prod(np.ptp(pj, 0))))
        return inter / smaller if smaller > 0 else 0.0

    unpaired = set(range(len(loops)))
    bands = []
    while unpaired:
        i = min(unpaired)
        unpaired.discard(i)
        best, best_score = None, 0.5
        for j in unpaired:
            (ci, ni, _), (cj, nj, _) = planes[i], planes[j]
            gap = abs(float(np.dot(cj - ci, ni)))
            if abs(float(np.dot(ni, nj))) < 1 - 1e-9 or not 0 < gap < min(sizes[i], sizes[j]):
                continue
            score = overlap(i, j)
            if score > best_score:
                best, best_score = j, score
        if best is None:
            return None
        unpaired.discard(best)
        bands.append(_bridge(vertices, loops[i], loops[best], planes[i][1]))
    closed = trimesh.Trimesh(vertices, np.concatenate([faces, *bands]), process=False)
    return closed, len(bands)


def _reason(error: InvalidMeshError) -> str:
    """Why a mesh is no solid, without its label and the advice on fixing it."""
    return str(error).split(": ", 1)[-1].split("; ", 1)[0]


def _world_parts(raw: trimesh.Trimesh, label: str,
                 notes: list[str]) -> list[tuple[trimesh.Trimesh, bool, str]]:
    """The world mesh as ``(mesh, solid, why)``, one per connected piece (see module doc)."""
    single, dropped = _single_sided(raw)
    if dropped:
        notes.append(f"{label}: dropped {dropped} back-side duplicate triangles "
                     "(double-sided export)")
    size = scale_of(single)
    parts = []
    for index, piece in enumerate(_pieces(single)):
        where = f"{label} piece {index} ({len(piece.faces)} triangles, box "\
                f"{np.round(piece.bounds, 2).tolist()})"
        try:
            parts.append((validate_solid(piece, name=f"{label}[{index}]"), True,
                          "closed and its winding number never negative"))
            continue
        except InvalidMeshError as error:
            problem = _reason(error)
        if _thickness(np.asarray(piece.vertices)) > tol.flat_rel * size:
            bridged = _bridge_openings(piece)
            if bridged is not None:
                closed, pairs = bridged
                try:
                    parts.append((validate_solid(closed, name=f"{label}[{index}]"), True,
                                  f"closed once {pairs} pair(s) of facing openings got the "
                                  "walls between them"))
                except InvalidMeshError:
                    pass
                else:
                    notes.append(f"{where}: {pairs} pair(s) of facing openings had no walls "
                                 "between them; added the walls")
                    continue
        notes.append(f"{where}: a surface (triangles, as OMPL.app and FCL see them): "
                     f"{problem}")
        parts.append((piece, False, problem))
    return parts


# ------------------------------------------------------------------------------ config


def _cfg_line(text: str, key: str) -> int | None:
    pattern = re.compile(rf"^\s*{re.escape(key)}\s*[=:]", re.IGNORECASE)
    for number, line in enumerate(text.splitlines(), start=1):
        if pattern.match(line):
            return number
    return None


class _Cfg:
    """The ``[problem]`` section with errors that name the key and its line."""

    def __init__(self, path: Path) -> None:
        self.label = str(path)
        try:
            self.text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise ScenarioError(f"{self.label}: OMPL.app problem file not found "
                                f"(looked in {path.parent.resolve()})") from None
        except (OSError, UnicodeDecodeError) as error:
            raise ScenarioError(f"{self.label}: cannot read the file: {error}") from None
        parser = configparser.ConfigParser(interpolation=None)
        try:
            parser.read_string(self.text, source=self.label)
        except configparser.Error as error:
            line = getattr(error, "lineno", None)
            where = self.label if line is None else f"{self.label}:{line}"
            message = str(error).splitlines()[0]
            raise ScenarioError(f"{where}: INI syntax error: {message}", line=line) from None
        if not parser.has_section("problem"):
            raise ScenarioError(f"{self.label}: problem: missing [problem] section",
                                field="problem")
        self.problem = parser["problem"]
        self.parser = parser

    def error(self, key: str, problem: str) -> ScenarioError:
        field = f"problem.{key}"
        line = _cfg_line(self.text, key)
        where = self.label if line is None else f"{self.label}:{line}"
        return ScenarioError(f"{where}: {field}: {problem}", field=field, line=line)

    def has(self, key: str) -> bool:
        return key in self.problem

    def string(self, key: str) -> str:
        if key not in self.problem or not self.problem[key].strip():
            raise self.error(key, "missing required field")
        return self.problem[key].strip()

    def number(self, key: str, default: float | None = None) -> float:
        if key not in self.problem:
            if default is not None:
                return default
            raise self.error(key, "missing required field")
        raw = self.problem[key].strip()
        try:
            value = float(raw)
        except ValueError:
            raise self.error(key, f"expected a number, got {raw!r}") from None
        if not math.isfinite(value):
            raise self.error(key, f"expected a finite number, got {raw!r}")
        return value

    def vector(self, prefix: str) -> np.ndarray:
        return np.array([self.number(f"{prefix}.{axis}") for axis in "xyz"])

    def rotation(self, prefix: str) -> np.ndarray:
        """Axis-angle ``prefix.axis.x/y/z`` + ``prefix.theta`` (radians) as ``(3, 3)``."""
        theta = self.number(f"{prefix}.theta", 0.0)
        if theta == 0.0:
            return np.eye(3)
        axis = np.array([self.number(f"{prefix}.axis.{a}") for a in "xyz"])
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            raise self.error(f"{prefix}.axis.x", "rotation axis must not be the zero vector")
        return tf.rotation_matrix(theta, axis / norm)[:3, :3]

    def mesh_path(self, key: str, base: Path) -> Path:
        value = self.string(key)
        path = Path(value) if Path(value).is_absolute() else base / value
        if not path.is_file():
            raise self.error(key, f"file '{value}' not found (looked in "
                                  f"{path.parent.resolve()})")
        return path


def load_omplapp(cfg_path: str | os.PathLike[str]) -> Scenario:
    """Read an OMPL.app SE(3) problem as a translational :class:`Scenario`.

    The robot mesh is expressed relative to its reference point (see
    :func:`robot_reference_point`) with the start orientation applied, so the scenario's
    ``start``/``goal`` are the ``.cfg``'s positions. The world becomes one obstacle per
    connected piece (named ``"<world file stem>_<k>"``), each a validated solid; what the
    import had to change is listed in ``Scenario.notes`` (see the module doc).
    ``volume`` becomes the bounds; ``[benchmark] time_limit``, when present, the
    planner's time limit. Units are ``"unitless"`` (the files state none).

    Raises:
        ScenarioError: missing or malformed keys (field ``problem.<key>``, with its line),
            missing or unusable meshes, a 2D (SE(2)) problem, a goal orientation that
            differs from the start's, start or goal outside the volume.
    """
    path = Path(cfg_path)
    cfg = _Cfg(path)
    base = path.parent
    if not cfg.has("start.z") and cfg.has("start.x"):
        raise cfg.error("start.z", "missing: 2D (SE(2)) problems are not supported, only "
                                   "3D rigid bodies")
    start = cfg.vector("start")
    goal = cfg.vector("goal")
    orientation = cfg.rotation("start")
    goal_rotation = cfg.rotation("goal")
    difference = math.acos(min(1.0, max(-1.0, (np.trace(orientation.T @ goal_rotation) - 1)
                                        / 2)))
    if math.degrees(difference) > tol.orientation_deg:
        raise cfg.error("goal.theta", f"goal orientation differs from the start's by "
                                      f"{math.degrees(difference):.4g} degrees; minkplan only "
                                      "translates the robot")

    notes: list[str] = []
    robot_file = cfg.mesh_path("robot", base)
    world_file = cfg.mesh_path("world", base)
    try:
        raw_robot = read_app_mesh(robot_file)
        centre = robot_reference_point(raw_robot)
        single, dropped = _single_sided(raw_robot)
        if dropped:
            notes.append(f"robot: dropped {dropped} back-side duplicate triangles "
                         "(double-sided export)")
    except InvalidMeshError as error:
        raise cfg.error("robot", str(error)) from None
    robot_solid, robot_why = True, "closed and its winding number never negative"
    try:
        robot_mesh = validate_solid(single, name=robot_file.stem)
    except InvalidMeshError as error:
        robot_mesh, robot_solid = single, False
        robot_why = _reason(error)
        notes.append(f"robot: a surface (triangles, as OMPL.app and FCL see them): {robot_why}")
    robot_mesh.apply_translation(-centre)
    robot_mesh.apply_transform(_homogeneous(orientation))
    robot = Robot(robot_file.stem, robot_mesh,
                  f"{robot_file.resolve()} (OMPL.app frame, reference point "
                  f"{np.round(centre, 6).tolist()})", robot_solid, robot_why, checked=robot_solid)

    try:
        parts = _world_parts(read_app_mesh(world_file), world_file.stem, notes)
    except InvalidMeshError as error:
        raise cfg.error("world", str(error)) from None
    obstacles = [Body(f"{world_file.stem}_{k}", mesh,
                      f"{world_file.resolve()} (OMPL.app frame, piece {k})", solid, why,
                      checked=solid)
                 for k, (mesh, solid, why) in enumerate(parts)]

    if all(cfg.has(f"volume.{end}.{axis}") for end in ("min", "max") for axis in "xyz"):
        bounds = (cfg.vector("volume.min"), cfg.vector("volume.max"))
        bad = [axis for axis, lo, hi in zip("xyz", *bounds) if lo >= hi]
        if bad:
            raise cfg.error(f"volume.max.{bad[0]}", "volume.max must exceed volume.min")
        for name, point in (("start", start), ("goal", goal)):
            outside = [axis for axis, v, lo, hi in zip("xyz", point, *bounds)
                       if not lo <= v <= hi]
            if outside:
                raise cfg.error(f"{name}.{outside[0]}",
                                f"{name} {point.tolist()} is outside the volume")
    else:
        bounds = default_bounds(robot.mesh, [b.mesh for b in obstacles], start, goal)
        notes.append("no complete volume.min/max in the file: default bounds used")

    settings = PlannerSettings()
    limit = _benchmark_time_limit(cfg)
    if limit is not None:
        settings = PlannerSettings(time_limit=limit)
    name = cfg.problem.get("name", path.stem).strip() or path.stem
    return Scenario(name=name, units="unitless", robot=robot, obstacles=obstacles,
                    start=start, goal=goal, orientation=orientation, bounds=bounds,
                    settings=settings, path=path.resolve(), notes=tuple(notes))


def _benchmark_time_limit(cfg: _Cfg) -> float | None:
    if not cfg.parser.has_option("benchmark", "time_limit"):
        return None
    raw = cfg.parser["benchmark"]["time_limit"].strip()
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        line = _cfg_line(cfg.text, "time_limit")
        where = cfg.label if line is None else f"{cfg.label}:{line}"
        raise ScenarioError(f"{where}: benchmark.time_limit: expected a number > 0, got "
                            f"{raw!r}", field="benchmark.time_limit", line=line)
    return value


def _homogeneous(rotation: np.ndarray) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    return matrix


# ------------------------------------------------------------------------------- paths


def read_omplapp_path(path: str | os.PathLike[str]) -> np.ndarray:
    """An OMPL.app SE(3) solution file as an ``(n, 7)`` array of rows
    ``x y z qx qy qz qw`` (quaternion scalar last, as OMPL prints it).

    Raises:
        ScenarioError: unreadable file, or rows that are not 7 finite numbers.
    """
    path = Path(path)
    rows = []
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ScenarioError(f"{path}: cannot read the path file: {error}") from None
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            row = [float(v) for v in line.split()]
        except ValueError:
            row = []
        if len(row) != 7 or not all(math.isfinite(v) for v in row):
            raise ScenarioError(f"{path}:{number}: expected 7 numbers x y z qx qy qz qw",
                                line=number)
        rows.append(row)
    return np.array(rows, dtype=np.float64).reshape(-1, 7)


def path_state_transform(row: Any) -> np.ndarray:
    """The ``(4, 4)`` pose of one OMPL.app SE(3) state ``[x, y, z, qx, qy, qz, qw]``: it
    maps a robot vertex relative to the reference point into the app frame."""
    x, y, z, qx, qy, qz, qw = (float(v) for v in row)
    matrix = tf.quaternion_matrix([qw, qx, qy, qz])
    matrix[:3, 3] = (x, y, z)
    return matrix
