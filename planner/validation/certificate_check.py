"""A no-path certificate checked with independent libraries: what ``minkplan verify`` runs.

A certificate (``certificate.json``) claims that the walled point (the start or the goal)
lies in a *component* of cells that no translation leaves without entering a *wall* cell,
and that every translation in a wall cell is blocked. :func:`check_certificate` confirms
both with independent libraries, from the scenario's meshes:

1. the walled point is the scenario's start (or goal) and lies in a component cell; the
   other end does not;
2. the cells (component and walls) are disjoint cells of one octree lattice (cubes of
   the smallest side times powers of two, each on the lattice at its size, none inside
   another, none listed twice), so that areas and volumes can be summed;
3. the component is closed: every face of every component cell is covered by faces of
   other component cells and of wall cells (areas summed across the face's plane);
4. every wall cell is blocked: its witnesses' parts tile its box, each names geometry of
   the scenario (a triangle or vertex of the named obstacle, of the robot as oriented;
   compared exactly: the core copies the coordinates), and each holds —
   ``"triangles"``: the parts' corners lie in the convex hull of ``o − r`` over the two
   triangles' corners (scipy's Qhull; the set of translations where they meet is that
   hull, so the corners decide); ``"robot_vertex"`` / ``"obstacle_vertex"``: the vertex's
   box lies in the solid (trimesh's containment of its centre, and FCL's box against the
   solid's triangles: no contact); ``"robot_shell"`` / ``"obstacle_shell"``: the shell
   (faces of the scenario's mesh) is closed mod 2 (every edge, vertices welded by
   coordinates, used an even number of times), the point lies on its triangle (the
   nearest point of the triangle is tested) and the far vertex is a vertex of the same
   connected part (triangles sharing welded vertices), the point's box lies in the
   shell's odd region (FCL: no shell triangle meets it; the parity of crossings of a ray
   from its centre, counted here with numpy, is odd) and the far vertex's box misses the
   shell's box — so the part's connected surface crosses the shell at every translation
   of the box; ``"bounds"``: the part lies beyond the bounds' face; ``"primitive"`` (a
   decomposition's convex piece) is not checked here and is counted.

Rounding: coordinates match within :data:`SLACK` of the scenario's size (never of the
certificate's). The check speaks of the meshes as the scenario loads them, as the
certificate does, at the robot's orientation it records. What it takes from the loader
(which uses the native core): which meshes are solids — their winding number never
negative, computed exactly by the core; here a solid a witness rests on is checked again
to be closed and outward (every edge used as often in each direction, positive volume),
not for the winding number's sign. The shell witnesses need no solid. Malformed certificates
raise (``ValueError``, ``KeyError``, ``TypeError``, ``IndexError``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import fcl
import numpy as np
import scipy.sparse
import scipy.sparse.csgraph
import trimesh
from scipy.spatial import ConvexHull, QhullError

from planner.meshes.closest import closest_points_on_triangles
from planner.output import schema_id
from planner.problem import Scenario

from .fcl_checker import bvh_model

__all__ = ["SLACK", "CertificateCheck", "box_in_solid", "check_certificate",
           "closed_and_oriented", "closed_mod_2", "odd_parity", "piece_holds", "welded_ids"]

SLACK = 1e-9
"""Relative rounding slack of the tests (a wall cell may touch its piece, cells meet on a
lattice computed in floating point)."""

_MAX_FAILURES = 20
"""Failures kept in the result (the count is complete)."""


@dataclass
class CertificateCheck:
    """The outcome of :func:`check_certificate`.

    Attributes:
        valid: every test passed (``unchecked`` aside).
        point_in_component: the walled point lies in a component cell.
        component_closed: every face of the component is covered.
        walls: wall cells checked; ``witnesses``: their witnesses' parts by kind.
        unchecked: witness parts of a kind this module does not check (``"primitive"``).
        failures: the first failures, one line each; ``n_failures`` all of them.
        seconds: time taken.
    """

    valid: bool = True
    point_in_component: bool = False
    component_closed: bool = False
    walls: int = 0
    witnesses: dict[str, int] = field(default_factory=dict)
    unchecked: int = 0
    failures: list[str] = field(default_factory=list)
    n_failures: int = 0
    seconds: float = 0.0

    def fail(self, message: str) -> None:
        self.valid = False
        self.n_failures += 1
        if len(self.failures) < _MAX_FAILURES:
            self.failures.append(message)


def corners(box: np.ndarray) -> np.ndarray:
    """The eight corners of the box ``[lo, hi]``."""
    lo, hi = box
    return np.array([[(lo, hi)[i >> a & 1][a] for a in range(3)] for i in range(8)])


def piece_holds(box: np.ndarray, obstacle: np.ndarray, robot: np.ndarray) -> bool:
    """Whether at every translation ``t`` of ``box`` the triangle ``robot + t`` meets the
    triangle ``obstacle``: the box's corners lie in the convex hull of ``o − r``."""
    points = (obstacle[:, None, :] - robot[None, :, :]).reshape(-1, 3)
    scale = float(np.abs(points).max() + np.abs(box).max())
    try:
        hull = ConvexHull(points)
    except QhullError:
        return False  # a flat piece holds no box
    return bool(np.all(corners(box) @ hull.equations[:, :3].T + hull.equations[:, 3]
                       <= SLACK * scale))


class _Parts:
    """The scenario's meshes as a check asks about them: their vertices and triangles
    (so that a witness names geometry of the parts, not anything), and FCL models of the
    solids, built once each."""

    def __init__(self, scenario: Scenario) -> None:
        self.robot = scenario.robot
        self.obstacles = {o.name: o for o in scenario.obstacles}
        self._vertices: dict[int, set[tuple[float, ...]]] = {}
        self._triangles: dict[int, set[frozenset[tuple[float, ...]]]] = {}
        self.models: dict[int, fcl.BVHModel] = {}
        self._parts: dict[int, dict[tuple[float, ...], int]] = {}
        self._solid: dict[int, bool] = {}
        self.unit = _fcl_unit(scenario)

    def has_vertex(self, mesh: trimesh.Trimesh, v: np.ndarray) -> bool:
        key = id(mesh)
        if key not in self._vertices:
            used = np.asarray(mesh.vertices)[np.unique(np.asarray(mesh.faces))]
            self._vertices[key] = {tuple(p) for p in used.tolist()}
        return tuple(np.asarray(v, dtype=np.float64).tolist()) in self._vertices[key]

    def has_triangle(self, mesh: trimesh.Trimesh, corners: np.ndarray) -> bool:
        key = id(mesh)
        if key not in self._triangles:
            tris = np.asarray(mesh.vertices)[np.asarray(mesh.faces)].tolist()
            self._triangles[key] = {frozenset(map(tuple, t)) for t in tris}
        return frozenset(map(tuple, np.asarray(corners, dtype=np.float64).tolist())) \
            in self._triangles[key]

    def part_of(self, mesh: trimesh.Trimesh, point: np.ndarray) -> int | None:
        """The connected part (triangles sharing vertices, welded by coordinates) of the
        mesh's vertex at ``point``, or ``None`` when no vertex lies there."""
        key = id(mesh)
        if key not in self._parts:
            ids = welded_ids(np.asarray(mesh.vertices))
            faces = ids[np.asarray(mesh.faces)]
            n = int(ids.max()) + 1 if len(ids) else 0
            graph = scipy.sparse.coo_matrix(
                (np.ones(2 * len(faces)), (np.concatenate([faces[:, 0], faces[:, 0]]),
                                           np.concatenate([faces[:, 1], faces[:, 2]]))),
                shape=(n, n))
            labels = scipy.sparse.csgraph.connected_components(graph, directed=False)[1]
            used = np.unique(np.asarray(mesh.faces))
            where = {tuple(p): int(labels[ids[i]])
                     for p, i in zip(np.asarray(mesh.vertices)[used].tolist(), used, strict=True)}
            self._parts[key] = where
        return self._parts[key].get(tuple(np.asarray(point, dtype=np.float64).tolist()))

    def is_solid(self, body: Any) -> bool:
        """Whether ``body`` was loaded as a solid and its mesh is closed and outward
        (:func:`closed_and_oriented`, checked here once per mesh)."""
        key = id(body.mesh)
        if key not in self._solid:
            self._solid[key] = bool(body.solid) and closed_and_oriented(
                np.asarray(body.mesh.vertices), np.asarray(body.mesh.faces))
        return self._solid[key]

    def model(self, mesh: trimesh.Trimesh) -> fcl.BVHModel:
        key = id(mesh)
        if key not in self.models:
            self.models[key] = _fcl_model(mesh, self.unit)
        return self.models[key]


_RAY_DIRECTIONS = np.array([[0.5773502691896258, 0.6180339887498948, 0.5320888862379561],
                            [-0.381966011250105, 0.7071067811865475, -0.595241580617241],
                            [0.2679491924311227, -0.8090169943749474, 0.5235987755982988],
                            [-0.723606797749979, -0.223606797749979, 0.6524758424985279]])
_RAY_DIRECTIONS /= np.linalg.norm(_RAY_DIRECTIONS, axis=1, keepdims=True)
"""Generic ray directions for :func:`odd_parity`, tried in turn."""


def welded_ids(vertices: np.ndarray) -> np.ndarray:
    """Each vertex's id, equal for vertices of equal coordinates (``-0.0`` as ``0.0``)."""
    _, ids = np.unique(np.asarray(vertices, dtype=np.float64) + 0.0, axis=0,
                       return_inverse=True)
    return ids.reshape(-1)


def closed_mod_2(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether every edge of the triangles (vertices welded) is used an even number of
    times (degenerate edges aside)."""
    ids = welded_ids(vertices)[np.asarray(faces)]
    edges = np.concatenate([ids[:, [0, 1]], ids[:, [1, 2]], ids[:, [2, 0]]])
    edges = np.sort(edges[edges[:, 0] != edges[:, 1]], axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts % 2 == 0))


def closed_and_oriented(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """Whether every edge (vertices welded) is used as often in one direction as in the
    other, and the enclosed signed volume is positive: what a solid's mesh must be
    (the sign of its winding number inside is the loader's test, with the core)."""
    ids = welded_ids(vertices)[np.asarray(faces)]
    directed = np.concatenate([ids[:, [0, 1]], ids[:, [1, 2]], ids[:, [2, 0]]])
    directed = directed[directed[:, 0] != directed[:, 1]]
    forward = directed[:, 0] < directed[:, 1]
    keys = np.sort(directed, axis=1)
    edges, inverse = np.unique(keys, axis=0, return_inverse=True)
    balance = np.bincount(inverse.reshape(-1), weights=np.where(forward, 1.0, -1.0),
                          minlength=len(edges))
    triangles = np.asarray(vertices, dtype=np.float64)[np.asarray(faces)]
    volume = np.einsum("ij,ij->i", triangles[:, 0],
                       np.cross(triangles[:, 1], triangles[:, 2])).sum() / 6.0
    return bool(np.all(balance == 0) and volume > 0)


def odd_parity(triangles: np.ndarray, q: np.ndarray, tol: float) -> bool | None:
    """Whether a ray from ``q`` crosses an odd number of the triangles (n, 3, 3): by
    Möller–Trumbore on each of a few generic directions until one passes no edge or
    vertex within rounding; ``None`` when ``q`` lies on a triangle or every ray did."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    scale = float(np.ptp(triangles.reshape(-1, 3), axis=0).max()) if len(triangles) else 0.0
    flat = area <= 1e-14 * scale * scale  # zero area: crossing it changes no parity
    a, b, c, normal, area = a[~flat], b[~flat], c[~flat], normal[~flat], area[~flat]
    e1, e2 = b - a, c - a
    s = q - a
    for d in _RAY_DIRECTIONS:
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12 * np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1)
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        u = np.einsum("ij,ij->i", s, p) * inv
        qv = np.cross(s, e1)
        v = (qv @ d) * inv
        t = np.einsum("ij,ij->i", e2, qv) * inv
        inside = ok & (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9)
        if np.any(inside & (np.abs(t) <= tol)):
            return None
        hits = inside & (t > 0)
        edge = (u <= 1e-9) | (v <= 1e-9) | (u + v >= 1 - 1e-9)
        if np.any(hits & edge) or np.any(~ok & (np.abs(np.einsum("ij,ij->i", s, normal))
                                                <= tol * area)):
            continue  # through an edge, or along a triangle's plane: another direction
        return bool(hits.sum() % 2 == 1)
    return None


def _fcl_unit(scenario: Scenario) -> float:
    """The power of two nearest the scene's extent: FCL's models and boxes are given in
    it, so that they are about unit size (FCL's box-against-triangles test has fixed
    tolerances, and reports a box a tenth of a millimetre across, in metres, as meeting
    triangles it is clear of). A power of two scales coordinates without rounding."""
    lo, hi = scenario.bounds
    extents = [np.ptp(np.asarray([lo, hi], dtype=np.float64), axis=0).max(),
               np.ptp(scenario.robot.mesh.bounds, axis=0).max(),
               *(np.ptp(o.mesh.bounds, axis=0).max() for o in scenario.obstacles)]
    size = float(max(extents))
    return 2.0 ** round(math.log2(size)) if size > 0 and math.isfinite(size) else 1.0


def _fcl_model(mesh: trimesh.Trimesh, unit: float = 1.0) -> fcl.BVHModel:
    return bvh_model(np.asarray(mesh.vertices) / unit, np.asarray(mesh.faces))


def _box_free_of(box: np.ndarray, model: fcl.BVHModel, grow: float = 0.0,
                 unit: float = 1.0) -> bool:
    """Whether no triangle of ``model`` (in coordinates divided by ``unit``) meets the box
    (grown by ``grow`` and the relative rounding slack)."""
    centre, half = box.mean(axis=0) / unit, ((box[1] - box[0]) / 2 + grow) / unit
    grown = fcl.Box(*(2 * half * (1 + SLACK)))
    return not fcl.collide(fcl.CollisionObject(grown, fcl.Transform(centre)),
                           fcl.CollisionObject(model, fcl.Transform()),
                           fcl.CollisionRequest(), fcl.CollisionResult())


class _Shell:
    """One closed shell a certificate names: its triangles, box, FCL model, and whether
    it is closed mod 2."""

    def __init__(self, entry: dict[str, Any], parts: _Parts) -> None:
        self.of = entry["of"]
        if self.of == "robot":
            self.owner: str | None = None
            mesh = parts.robot.mesh
        elif self.of == "obstacle":
            self.owner = str(entry["obstacle"])
            mesh = parts.obstacles[self.owner].mesh
        else:
            raise ValueError(f"shell of = {self.of!r}: expected 'robot' or 'obstacle'")
        listed = entry["faces"]
        if not isinstance(listed, list):
            raise TypeError("faces: expected a list of face indices")
        index = np.asarray([_index(f, "face") for f in listed], dtype=np.int64)
        if len(index) and index.max() >= len(mesh.faces):
            raise IndexError(f"face {int(index.max())}: the mesh has {len(mesh.faces)} faces")
        faces = np.asarray(mesh.faces)[index]
        self.closed = len(faces) >= 4 and closed_mod_2(np.asarray(mesh.vertices), faces)
        self.triangles = np.asarray(mesh.vertices, dtype=np.float64)[faces]
        flat = self.triangles.reshape(-1, 3)
        self.box = np.stack([flat.min(axis=0), flat.max(axis=0)])
        self.unit = parts.unit
        self.model = bvh_model(flat / self.unit, np.arange(len(flat)).reshape(-1, 3))

    def holds_inside(self, box: np.ndarray, tol: float) -> bool:
        """Whether ``box`` lies in the shell's odd region."""
        return (self.closed and _box_free_of(box, self.model, tol, self.unit)
                and odd_parity(self.triangles, box.mean(axis=0), tol) is True)

    def misses(self, box: np.ndarray, tol: float) -> bool:
        """Whether ``box`` misses the shell's box."""
        return bool(np.any(box[0] > self.box[1] + tol) or np.any(box[1] < self.box[0] - tol))


def box_in_solid(box: np.ndarray, solid: trimesh.Trimesh,
                 model: fcl.BVHModel | None = None, unit: float = 1.0) -> bool:
    """Whether the box lies inside the closed mesh ``solid``: its centre inside
    (trimesh), and no triangle meets it (FCL's box against the triangles; ``model``, if
    given, in coordinates divided by ``unit``: :func:`_fcl_unit`)."""
    if not solid.contains([box.mean(axis=0)])[0]:
        return False
    return _box_free_of(box, model if model is not None else _fcl_model(solid, unit), 0.0, unit)


def check_certificate(certificate: dict[str, Any], scenario: Scenario) -> CertificateCheck:
    """Check ``certificate`` (as ``certificate.json`` holds it) against ``scenario``'s
    meshes, ends and bounds (see the module documentation).

    Raises:
        ValueError, KeyError, TypeError, IndexError: the certificate is malformed.
    """
    t0 = time.perf_counter()
    out = CertificateCheck()
    if not isinstance(certificate, dict):
        raise TypeError("the certificate is not a JSON object")
    if certificate.get("schema", schema_id("certificate")) != schema_id("certificate"):
        raise ValueError(f"schema = {certificate['schema']!r}: expected "
                         f"{schema_id('certificate')!r}")
    component = _within("component.boxes", lambda: _boxes(certificate["component"]["boxes"]))
    walls = certificate["walls"]
    if not isinstance(walls, list):
        raise TypeError("walls: expected a list")
    wall_boxes = _within("walls", lambda: _boxes([w["box"] for w in walls]))
    lo, hi = (np.asarray(b, dtype=np.float64) for b in scenario.bounds)
    tol = SLACK * _scene_size(scenario)  # from the scenario, never from the certificate
    _check_orientation(certificate, scenario, out)
    _check_ends(certificate, scenario, component, tol, out)
    for message in _lattice_problems(np.concatenate([component, wall_boxes]), tol):
        out.fail(message)
    uncovered = _uncovered_faces(component, wall_boxes, tol)
    out.component_closed = not uncovered
    for message in uncovered:
        out.fail(message)
    parts = _Parts(scenario)
    entries = certificate.get("shells", [])
    if not isinstance(entries, list):
        raise TypeError("shells: expected a list")
    shells = [_within(f"shells[{i}]", lambda entry=entry: _Shell(entry, parts))
              for i, entry in enumerate(entries)]
    for i, shell in enumerate(shells):
        if not shell.closed:
            whose = "the robot's" if shell.owner is None else f"obstacle {shell.owner}'s"
            out.fail(f"shell {i} ({whose}) is not closed mod 2: some edge is used an odd "
                     f"number of times")
    for i, wall in enumerate(walls):
        out.walls += 1
        _within(f"walls[{i}]", lambda wall=wall: _check_wall(wall, lo, hi, tol, parts, shells, out))
    out.seconds = time.perf_counter() - t0
    return out


def _within(where: str, step: Any) -> Any:
    """``step()``, its malformed-input errors re-raised as a ``ValueError`` naming
    ``where`` (the certificate's field)."""
    try:
        return step()
    except KeyError as exc:
        raise ValueError(f"{where}: missing {exc.args[0]!r}") from exc
    except (ValueError, TypeError, IndexError, AttributeError, OverflowError) as exc:
        raise ValueError(f"{where}: {exc}") from exc


def _index(value: Any, what: str) -> int:
    """``value`` as an index: an integer (not a bool, not a float) at least 0."""
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{what} = {value!r}: expected an integer >= 0")
    return value


def _check_orientation(certificate: dict[str, Any], scenario: Scenario,
                       out: CertificateCheck) -> None:
    """The robot's orientation the certificate was made for is the scenario's (as loaded,
    with the same ``--hold-orientation``)."""
    if "robot_orientation" not in certificate:
        return  # certificates written before it was recorded
    given = np.asarray(certificate["robot_orientation"], dtype=np.float64)
    if given.shape != (3, 3):
        raise ValueError("robot_orientation: expected a 3 x 3 matrix")
    if not np.allclose(given, np.asarray(scenario.orientation), rtol=0.0, atol=1e-9):
        out.fail("the certificate is for the robot at another orientation than the "
                 "scenario's as loaded (plan and verify with the same --hold-orientation)")


def _boxes(rows: Any) -> np.ndarray:
    """Boxes ``(n, 2, 3)`` from a certificate's lists: finite, ``lo < hi``."""
    boxes = np.asarray(rows, dtype=np.float64).reshape(-1, 2, 3)
    if not np.all(np.isfinite(boxes)) or np.any(boxes[:, 1] <= boxes[:, 0]):
        raise ValueError("a box is not finite or has no volume")
    return boxes


def _scene_size(scenario: Scenario) -> float:
    """The largest coordinate of the scenario's bounds, ends and meshes (at least 1)."""
    lo, hi = scenario.bounds
    values = [np.abs(lo).max(), np.abs(hi).max(), np.abs(scenario.start).max(),
              np.abs(scenario.goal).max(), np.abs(scenario.robot.mesh.bounds).max(),
              *(np.abs(o.mesh.bounds).max() for o in scenario.obstacles)]
    return max(1.0, float(max(values)))


def _check_ends(certificate: dict[str, Any], scenario: Scenario, component: np.ndarray,
                tol: float, out: CertificateCheck) -> None:
    """The walled point is the scenario's start (or goal), in the component; the other
    end is not."""
    walled = certificate["walled"]
    if walled not in ("start", "goal"):
        raise ValueError(f"walled = {walled!r}: expected 'start' or 'goal'")
    ends = {"start": np.asarray(scenario.start, float), "goal": np.asarray(scenario.goal, float)}
    point = np.asarray(certificate["walled_point"], dtype=np.float64)
    if point.shape != (3,) or not np.allclose(point, ends[walled], rtol=0.0, atol=tol):
        out.fail(f"the walled point {point.tolist()} is not the scenario's {walled} "
                 f"{ends[walled].tolist()}")

    def inside(p: np.ndarray, grow: float) -> bool:
        return bool(np.any(np.all((component[:, 0] - grow <= p) & (p <= component[:, 1] + grow),
                                  axis=1)))

    out.point_in_component = inside(ends[walled], tol)
    if not out.point_in_component:
        out.fail(f"the {walled} lies in no component cell")
    other = "goal" if walled == "start" else "start"
    if inside(ends[other], -tol):
        out.fail(f"the {other} lies in the component too")


def _lattice_problems(boxes: np.ndarray, tol: float) -> list[str]:
    """Why the cells are not disjoint cells of one octree lattice: cubes of the smallest
    one's side times powers of two, each on that lattice at its own size, none holding
    another's centre (for such cells overlapping means nesting)."""
    sizes = boxes[:, 1] - boxes[:, 0]
    floor = float(sizes.min())
    levels = np.round(np.log2(sizes[:, 0] / floor)).astype(np.int64)
    cube = floor * 2.0 ** levels
    if np.any(np.abs(sizes - cube[:, None]) > tol) or floor <= 100 * tol:
        return ["the cells are not cubes of the smallest one's side times powers of two "
                "(or are thinner than the check can tell)"]
    origin = boxes[int(np.argmax(sizes[:, 0])), 0]  # a largest cell: every level's lattice
    steps = (boxes[:, 0] - origin) / cube[:, None]
    if np.any(np.abs(steps - np.round(steps)) * cube[:, None] > tol):
        return ["the cells do not lie on one lattice"]
    keys = {(int(level), *map(int, np.round(s))) for level, s in zip(levels, steps, strict=True)}
    if len(keys) < len(boxes):
        return ["a cell is listed twice"]
    centres = boxes.mean(axis=1)
    for level in np.unique(levels):
        index = np.floor((centres - origin) / (floor * 2.0 ** level)).astype(np.int64)
        for i, ijk in enumerate(index):
            if levels[i] < level and (int(level), *map(int, ijk)) in keys:
                return [f"cell {i} lies inside a larger cell"]
    return []


def _check_wall(wall: dict[str, Any], lo: np.ndarray, hi: np.ndarray, tol: float,
                parts: _Parts, shells: list[_Shell], out: CertificateCheck) -> None:
    """Check one wall cell's witnesses (see the module documentation)."""
    box = _boxes([wall["box"]])[0]
    witnesses = wall.get("witnesses")
    name = f"wall cell {_index(wall['leaf'], 'leaf')}"
    if not witnesses:
        out.fail(f"{name} has no witness")
        return
    boxes = _boxes([w["box"] if "box" in w else wall["box"] for w in witnesses])
    volume = float(np.prod(boxes[:, 1] - boxes[:, 0], axis=1).sum())
    inside = np.all(boxes[:, 0] >= box[0] - tol) and np.all(boxes[:, 1] <= box[1] + tol)
    disjoint = not _lattice_problems(boxes, tol)
    if not (inside and disjoint
            and np.isclose(volume, float(np.prod(box[1] - box[0])), rtol=1e-9)):
        out.fail(f"{name}: its witnesses' parts do not tile its box")
    for witness, sub in zip(witnesses, boxes, strict=True):
        kind = witness["kind"]
        if kind not in _KINDS:
            raise ValueError(f"kind = {kind!r}: expected one of {', '.join(_KINDS)}")
        out.witnesses[kind] = out.witnesses.get(kind, 0) + 1
        if kind == "primitive":
            out.unchecked += 1
            continue
        if not _part_holds(kind, witness, sub, lo, hi, tol, parts, shells):
            out.fail(f"{name}: its {kind} witness does not hold for the box {sub.tolist()}")


_KINDS = ("triangles", "robot_vertex", "obstacle_vertex", "robot_shell", "obstacle_shell",
          "bounds", "primitive")
"""The witness kinds a certificate may hold."""


def _part_holds(kind: str, witness: dict[str, Any], sub: np.ndarray, lo: np.ndarray,
                hi: np.ndarray, tol: float, parts: _Parts, shells: list[_Shell]) -> bool:
    """Whether one witness holds for its part ``sub`` of a wall cell, with its geometry
    the scenario's own (see the module documentation)."""
    if kind == "bounds":
        axis, upper = divmod(_index(witness["side"], "side"), 2)
        if not 0 <= axis < 3:
            raise ValueError(f"side = {witness['side']!r}: expected 0 to 5")
        return bool(sub[0][axis] >= hi[axis] - tol if upper else sub[1][axis] <= lo[axis] + tol)
    if kind in ("robot_shell", "obstacle_shell"):
        return _shell_holds(kind, witness, sub, tol, parts, shells)
    obstacle = parts.obstacles.get(witness["obstacle"])
    if obstacle is None:
        return False
    if kind == "triangles":
        o = np.asarray(witness["obstacle_triangle"], dtype=np.float64).reshape(3, 3)
        r = np.asarray(witness["robot_triangle"], dtype=np.float64).reshape(3, 3)
        return (parts.has_triangle(obstacle.mesh, o) and parts.has_triangle(parts.robot.mesh, r)
                and piece_holds(sub, o, r))
    v = np.asarray(witness["vertex"], dtype=np.float64).reshape(3)
    if kind == "robot_vertex":
        return (parts.is_solid(obstacle) and parts.has_vertex(parts.robot.mesh, v)
                and box_in_solid(sub + v, obstacle.mesh, parts.model(obstacle.mesh), parts.unit))
    if kind == "obstacle_vertex":
        return (parts.is_solid(parts.robot) and parts.has_vertex(obstacle.mesh, v)
                and box_in_solid(v - sub[::-1], parts.robot.mesh, parts.model(parts.robot.mesh),
                                 parts.unit))
    raise ValueError(f"kind = {kind!r}: not a witness kind")


def _shell_holds(kind: str, witness: dict[str, Any], sub: np.ndarray, tol: float,
                 parts: _Parts, shells: list[_Shell]) -> bool:
    """A ``robot_shell`` or ``obstacle_shell`` witness (see the module documentation):
    the point's box (over the part ``sub`` of translations) in the shell's odd region,
    the far vertex's box off the shell's box, both of one connected part."""
    index = _index(witness["shell"], "shell")
    if index >= len(shells):
        raise IndexError(f"shell = {index}: the certificate lists {len(shells)} shells")
    shell, name = shells[index], str(witness["obstacle"])
    if name not in parts.obstacles:
        return False
    robot_shell = kind == "robot_shell"
    if robot_shell != (shell.owner is None) or (not robot_shell and shell.owner != name):
        return False  # the shell is not the one this kind names
    mesh = parts.obstacles[name].mesh if robot_shell else parts.robot.mesh
    x = np.asarray(witness["point"], dtype=np.float64).reshape(3)
    tri = np.asarray(witness["point_triangle"], dtype=np.float64).reshape(3, 3)
    y = np.asarray(witness["far_vertex"], dtype=np.float64).reshape(3)
    nearest = closest_points_on_triangles(tri[None], x[None])[0]
    on_triangle = float(np.linalg.norm(x - nearest)) <= tol
    x = nearest  # the box is tested about the triangle's own point
    part = parts.part_of(mesh, tri[0])
    same_part = part is not None and parts.part_of(mesh, y) == part
    # robot at t: the obstacle's x inside the shell + t (x − t); the robot's x + t inside
    moved = (lambda p: p - sub[::-1]) if robot_shell else (lambda p: p + sub)
    return bool(parts.has_triangle(mesh, tri) and on_triangle and same_part
                and shell.holds_inside(moved(x), tol) and shell.misses(moved(y), tol))



def _uncovered_faces(component: np.ndarray, walls: np.ndarray, tol: float) -> list[str]:
    """The faces of component cells not covered by faces of other cells (component or
    wall) across their plane, one line each. Faces are grouped by their plane (rounded
    to ``tol``, neighbouring roundings included), then the overlaps of each group's
    rectangles are summed."""
    boxes = np.concatenate([component, walls]) if len(walls) else component
    problems = []
    for axis in range(3):
        across = [(axis + 1) % 3, (axis + 2) % 3]
        for upper in (0, 1):
            keys = np.round(component[:, upper, axis] / tol).astype(np.int64)
            other_keys = np.round(boxes[:, 1 - upper, axis] / tol).astype(np.int64)
            order = np.argsort(other_keys)
            sorted_keys = other_keys[order]
            by_key = np.argsort(keys)
            groups, starts = np.unique(keys[by_key], return_index=True)
            for key, faces in zip(groups, np.split(by_key, starts[1:]), strict=True):
                a, b = np.searchsorted(sorted_keys, [key - 1, key + 1], side="left")[0], \
                    np.searchsorted(sorted_keys, key + 1, side="right")
                near = boxes[order[a:b]][:, :, across]
                covered = _covered(component[faces][:, :, across], near)
                for i, fraction in zip(faces[covered < 1 - 1e-9],
                                       covered[covered < 1 - 1e-9], strict=True):
                    side = f"{'-+'[upper]}{'xyz'[axis]}"
                    problems.append(f"component cell {int(i)}: its {side} face is not "
                                    f"covered by neighbouring cells ({fraction:.6g} of it)")
    return problems


def _covered(faces: np.ndarray, near: np.ndarray, block: int = 256) -> np.ndarray:
    """The fraction of each rectangle ``faces`` (n, 2, 2) that the rectangles ``near``
    (m, 2, 2; disjoint) cover: blocks of faces sorted along the first axis, each against
    the rectangles that meet the block's bounding rectangle."""
    area = np.prod(faces[:, 1] - faces[:, 0], axis=1)
    total = np.zeros(len(faces))
    order = np.argsort(faces[:, 0, 0])
    for start in range(0, len(faces), block):
        rows = order[start:start + block]
        f = faces[rows]
        lo, hi = f[:, 0].min(axis=0), f[:, 1].max(axis=0)
        meets = np.all((near[:, 0] < hi) & (near[:, 1] > lo), axis=1)
        n = near[meets]
        sides = np.clip(np.minimum(f[:, None, 1], n[None, :, 1])
                        - np.maximum(f[:, None, 0], n[None, :, 0]), 0.0, None)
        total[rows] = np.prod(sides, axis=2).sum(axis=1)
    return total / np.where(area > 0, area, 1.0)
