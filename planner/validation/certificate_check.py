"""A no-path certificate checked without the native core: what ``minkplan verify`` runs.

A certificate (``certificate.json``) claims that the walled point (the start or the goal)
lies in a *component* of cells that no translation leaves without entering a *wall* cell,
and that every translation in a wall cell is blocked. :func:`check_certificate` confirms
both with independent libraries, from the scenario's meshes:

1. the walled point lies in a component cell;
2. the component is closed: every face of every component cell is covered by faces of
   other component cells and of wall cells (areas summed across the face's plane);
3. every wall cell is blocked: its witnesses' parts cover its box, and each holds —
   ``"triangles"``: the parts' corners lie in the convex hull of ``o − r`` over the two
   triangles' corners (scipy's Qhull; the set of translations where they meet is that
   hull, so the corners decide); ``"robot_vertex"`` / ``"obstacle_vertex"``: the vertex's
   box lies in the solid (trimesh's containment of its centre, and FCL's box against the
   solid's triangles: no contact); ``"bounds"``: the part lies beyond the bounds' face;
   ``"primitive"`` (a decomposition's convex piece) is not checked here and is counted.

Rounding: coordinates match within :data:`SLACK` of the scene's size. The check speaks of
the meshes as the scenario loads them (solids and surfaces), as the certificate does.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import fcl
import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from planner.problem import Scenario

__all__ = ["SLACK", "CertificateCheck", "box_in_solid", "check_certificate", "piece_holds"]

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


class _Solids:
    """FCL models of the solids a check asks about, built once each."""

    def __init__(self) -> None:
        self.models: dict[int, fcl.BVHModel] = {}

    def model(self, mesh: trimesh.Trimesh) -> fcl.BVHModel:
        key = id(mesh)
        if key not in self.models:
            model = fcl.BVHModel()
            model.beginModel(len(mesh.vertices), len(mesh.faces))
            model.addSubModel(np.asarray(mesh.vertices, dtype=np.float64),
                              np.asarray(mesh.faces, dtype=np.int32))
            model.endModel()
            self.models[key] = model
        return self.models[key]


def box_in_solid(box: np.ndarray, solid: trimesh.Trimesh, models: _Solids | None = None) -> bool:
    """Whether the box lies inside the closed mesh ``solid``: its centre inside
    (trimesh), and no triangle meets it (FCL's box against the triangles)."""
    centre, half = box.mean(axis=0), (box[1] - box[0]) / 2
    if not solid.contains([centre])[0]:
        return False
    model = (models or _Solids()).model(solid)
    grown = fcl.Box(*(2 * half * (1 + SLACK)))
    result = fcl.CollisionResult()
    return not fcl.collide(fcl.CollisionObject(grown, fcl.Transform(centre)),
                           fcl.CollisionObject(model, fcl.Transform()),
                           fcl.CollisionRequest(), result)


def check_certificate(certificate: dict[str, Any], scenario: Scenario) -> CertificateCheck:
    """Check ``certificate`` (as ``certificate.json`` holds it) against ``scenario``'s
    meshes and bounds (see the module documentation)."""
    t0 = time.perf_counter()
    out = CertificateCheck()
    component = np.asarray(certificate["component"]["boxes"], dtype=np.float64).reshape(-1, 2, 3)
    walls = certificate["walls"]
    wall_boxes = np.asarray([w["box"] for w in walls], dtype=np.float64).reshape(-1, 2, 3)
    lo, hi = (np.asarray(b, dtype=np.float64) for b in scenario.bounds)
    scale = float(np.abs(np.concatenate([component.reshape(-1, 3), wall_boxes.reshape(-1, 3),
                                         [lo, hi]])).max())
    tol = SLACK * max(scale, 1.0)
    point = np.asarray(certificate["walled_point"], dtype=np.float64)
    out.point_in_component = bool(np.any(np.all((component[:, 0] - tol <= point)
                                                 & (point <= component[:, 1] + tol), axis=1)))
    if not out.point_in_component:
        out.fail(f"the walled point {point.tolist()} lies in no component cell")
    uncovered = _uncovered_faces(component, wall_boxes, tol)
    out.component_closed = not uncovered
    for message in uncovered:
        out.fail(message)
    solids = _Solids()
    for wall in walls:
        out.walls += 1
        _check_wall(wall, scenario, lo, hi, tol, solids, out)
    out.seconds = time.perf_counter() - t0
    return out


def _check_wall(wall: dict[str, Any], scenario: Scenario, lo: np.ndarray, hi: np.ndarray,
                tol: float, solids: _Solids, out: CertificateCheck) -> None:
    """Check one wall cell's witnesses (see the module documentation)."""
    box = np.asarray(wall["box"], dtype=np.float64)
    parts = wall.get("witnesses")
    name = f"wall cell {wall['leaf']}"
    if not parts:
        out.fail(f"{name} has no witness")
        return
    boxes = np.asarray([p["box"] if "box" in p else wall["box"] for p in parts])
    volume = float(np.prod(boxes[:, 1] - boxes[:, 0], axis=1).sum())
    inside = np.all(boxes[:, 0] >= box[0] - tol) and np.all(boxes[:, 1] <= box[1] + tol)
    if not inside or not np.isclose(volume, float(np.prod(box[1] - box[0])), rtol=1e-9):
        out.fail(f"{name}: its witnesses' parts do not cover its box")
    obstacles = {o.name: o for o in scenario.obstacles}
    for part, sub in zip(parts, boxes, strict=True):
        kind = part["kind"]
        out.witnesses[kind] = out.witnesses.get(kind, 0) + 1
        if kind == "primitive":
            out.unchecked += 1
            continue
        if not _part_holds(kind, part, sub, scenario, obstacles, lo, hi, tol, solids):
            out.fail(f"{name}: its {kind} witness does not hold for the box {sub.tolist()}")


def _part_holds(kind: str, part: dict[str, Any], sub: np.ndarray, scenario: Scenario,
                obstacles: dict, lo: np.ndarray, hi: np.ndarray, tol: float,
                solids: _Solids) -> bool:
    """Whether one witness part holds (see the module documentation)."""
    if kind == "triangles":
        return piece_holds(sub, np.asarray(part["obstacle_triangle"], dtype=np.float64),
                           np.asarray(part["robot_triangle"], dtype=np.float64))
    if kind == "robot_vertex":
        solid = obstacles.get(part["obstacle"])
        return bool(solid is not None and solid.solid and box_in_solid(
            sub + np.asarray(part["vertex"], dtype=np.float64), solid.mesh, solids))
    if kind == "obstacle_vertex":
        return scenario.robot.solid and box_in_solid(
            np.asarray(part["vertex"], dtype=np.float64) - sub[::-1], scenario.robot.mesh,
            solids)
    if kind == "bounds":
        axis, upper = divmod(int(part["side"]), 2)
        return bool(sub[0][axis] >= hi[axis] - tol if upper else sub[1][axis] <= lo[axis] + tol)
    return False


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
