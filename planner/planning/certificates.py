"""No-path certificates as ``report.json`` and ``certificate.json`` keep them: the
walled-off component of EMPTY and MIXED leaves and the FULL leaves around it, each
re-verified by the core and named by the obstacle (or the bounds) that blocks it.

Each wall cell carries its *witnesses*, one per part of its box (the core splits a box
into octants where no single witness holds all of it), so that a check that trusts
nothing of minkplan can confirm it, a robot translation ``t`` of the part at a time:

- ``"triangles"``: ``robot_triangle + t`` meets ``obstacle_triangle`` (the robot's
  triangle in its own frame; the set of such ``t`` is convex, so the part's eight corners
  decide);
- ``"robot_vertex"``: ``vertex + t`` lies inside the solid ``obstacle``;
- ``"obstacle_vertex"``: ``vertex`` (the obstacle's) lies inside the solid robot placed
  at ``t``;
- ``"robot_shell"``: ``point`` (on the obstacle's ``point_triangle``) lies inside the
  robot's closed shell ``shell`` placed at ``t`` (odd parity: the shell is closed mod 2,
  orientation aside), and the obstacle's ``far_vertex``, in the same connected part of
  its triangles, lies outside that shell's box: the part's surface crosses the shell;
- ``"obstacle_shell"``: the same with the roles swapped (the robot's ``point + t`` inside
  the obstacle's shell, its ``far_vertex + t`` outside);
- ``"bounds"``: the part lies beyond the bounds' ``side`` (``2 · axis + upper``);
- ``"primitive"``: (decomposition source) the convex primitive holds the box.

The shells are listed once, under ``"shells"``: whose (``of``: ``"robot"`` or
``"obstacle"`` with its name) and which of its triangles (``faces``: indices into the
mesh as the scenario loads it).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from planner.problem import Scenario

__all__ = ["certificate_document"]


def _named(witnesses: list[dict[str, Any]] | None,
           obstacle_of: Callable[[int], str]) -> list[dict[str, Any]] | None:
    """The core's witnesses of one wall cell, each obstacle index replaced by its name."""
    if witnesses is None:
        return None
    return [{**w, "obstacle": obstacle_of(int(w["obstacle"]))} if "obstacle" in w else w
            for w in witnesses]


def _face_indices(mesh: trimesh.Trimesh, triangles: np.ndarray) -> list[int]:
    """The indices of ``mesh``'s faces with the corners ``triangles`` (n, 3, 3), matched
    exactly (a face listed twice in the mesh is matched once per listing)."""
    faces: dict[frozenset[tuple[float, ...]], list[int]] = {}
    for i, corners in enumerate(np.asarray(mesh.vertices)[np.asarray(mesh.faces)].tolist()):
        faces.setdefault(frozenset(map(tuple, corners)), []).append(i)
    out = []
    for corners in np.asarray(triangles, dtype=np.float64).tolist():
        matches = faces.get(frozenset(map(tuple, corners)))
        if not matches:
            raise ValueError(f"a shell triangle {corners} is not a face of the mesh")
        out.append(matches.pop())
    return out


def _shells(raw: list[dict[str, Any]], scenario: Scenario,
            obstacle_of: Callable[[int], str]) -> list[dict[str, Any]]:
    """The closed shells the witnesses name, as face indices of the scenario's meshes."""
    meshes = {o.name: o.mesh for o in scenario.obstacles}
    out = []
    for shell in raw:
        if shell["of"] == "robot":
            entry: dict[str, Any] = {"of": "robot"}
            mesh = scenario.robot.mesh
        else:
            name = obstacle_of(int(shell["obstacle"]))
            entry, mesh = {"of": "obstacle", "obstacle": name}, meshes[name]
        out.append({**entry, "faces": _face_indices(mesh, shell["triangles"])})
    return out


def certificate_document(cs, raw: dict[str, Any], ends: dict[str, np.ndarray], *, exact: bool,
                         source_kind: str, relative_to: str,
                         obstacle_of: Callable[[int], str],
                         scenario: Scenario) -> dict[str, Any]:
    """The certificate as stored: summary, the walled-off component and its wall cells
    with the primitive and obstacle verified for each (``raw``: the core's)."""
    prims = np.asarray(raw["wall_prims"], dtype=np.int64)
    boxes = np.asarray(raw["wall_boxes"], dtype=np.float64)
    leaves = np.asarray(raw["wall_leaves"], dtype=np.int64)
    obstacles = [obstacle_of(int(p)) for p in prims]
    walled = "start" if raw["walls_around_start"] else "goal"
    component = [int(i) for i in raw["component_leaves"]]
    comp_boxes = np.array([cs.cell_box(i) for i in component]).reshape(-1, 2, 3)
    volume = float(np.prod(comp_boxes[:, 1] - comp_boxes[:, 0], axis=1).sum())
    return {
        "exact": exact,
        "source": source_kind,
        "relative_to": relative_to,
        "verified": bool(raw["verified"]),
        "walled": walled,
        "walled_point": ends[walled].tolist(),
        "robot_orientation": np.asarray(scenario.orientation, dtype=np.float64).tolist(),
        "component_cells": len(component),
        "component_volume": volume,
        "start_component_cells": int(raw["start_component_size"]),
        "goal_component_cells": int(raw["goal_component_size"]),
        "components": int(raw["n_components"]),
        "wall_cells": int(len(prims)),
        "wall_cells_without_primitive": int((prims < 0).sum()),
        "wall_cells_by_obstacle": dict(Counter(obstacles)),
        "floor": cs.floor,
        "contact": "touching counts as collision (contact tolerance 0 for the proof)",
        "walls": [
            {"leaf": int(leaf), "box": box.tolist(), "primitive": int(p), "obstacle": name,
             "witnesses": _named(why, obstacle_of)}
            for leaf, box, p, name, why in zip(leaves, boxes, prims, obstacles,
                                               raw["wall_witnesses"], strict=True)
        ],
        "shells": _shells(raw.get("shells", []), scenario, obstacle_of),
        "component": {"leaves": component, "boxes": comp_boxes.tolist()},
    }
