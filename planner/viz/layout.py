"""Scenes for minkplan's results: the one layout, filled from what each entry point has.

- :func:`scene_for_minkowski` -- operands and their Minkowski sum (or a C-obstacle).
- :func:`scene_for_plan` -- a scenario, optionally its plan (``PlanOutcome``, the
  ``path.json`` dict or file), the C-space octree and the C-obstacle surfaces.
- :func:`cells_from_cspace`, :func:`roadmap_from_cspace` -- plain arrays from the native
  ``CSpace`` (or anything with the same methods).
- :func:`compute_c_obstacles` -- one C-obstacle surface per obstacle, from the core.
- :func:`as_scene` -- whatever :func:`planner.viz.show` is given, as a :class:`Scene`.

Every function is tolerant of missing optional parts: no plan, a ``not_found`` plan
without waypoints, a dict lacking ``waypoints``, no C-space: the scene simply has fewer
layers.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from planner.errors import InvalidParameterError, ResourceLimitError

from .scene import (
    COLORS,
    EMPTY,
    MINKOWSKI_A,
    MINKOWSKI_B,
    MINKOWSKI_SUM,
    ROADMAP,
    Scene,
)

__all__ = [
    "as_scene",
    "cells_from_cspace",
    "compute_c_obstacles",
    "plan_parts",
    "roadmap_from_cspace",
    "scene_for_minkowski",
    "scene_for_plan",
]

log = logging.getLogger(__name__)


def scene_for_minkowski(result, a=None, b=None, *, c_obstacle: bool = False,
                        title: str | None = None) -> Scene:
    """The operands and their sum.

    Args:
        result: a ``MinkowskiResult`` (or a bare mesh of the sum).
        a, b: the operand meshes (optional).
        c_obstacle: ``result`` is ``planner.c_obstacle(a, b)``: then ``a`` is drawn as an
            obstacle, ``b`` as the robot at translation 0 and the surface at
            ``cspace/c_obstacle``; else at ``minkowski/a``, ``minkowski/b``,
            ``minkowski/sum``.
        title: page title.
    """
    scene = Scene(title or ("C-obstacle" if c_obstacle else "Minkowski sum"))
    if c_obstacle:
        if a is not None:
            scene.add_obstacles({"obstacle": a})
        if b is not None:
            scene.add_robot(b, start=np.zeros(3))
        scene.add_c_obstacle(result)
        return scene
    if a is not None:
        scene.add_mesh(MINKOWSKI_A, a, color=COLORS["operand_a"])
    if b is not None:
        scene.add_mesh(MINKOWSKI_B, b, color=COLORS["operand_b"])
    scene.add_mesh(MINKOWSKI_SUM, result, color=COLORS["sum"], opacity=0.4)
    return scene


# ---- the C-space -----------------------------------------------------------------------

def cells_from_cspace(cspace) -> tuple[np.ndarray, np.ndarray]:
    """``(boxes (n, 2, 3), labels (n,))`` of every leaf of a native ``CSpace`` (leaf
    ``i`` has lattice corner ``ijk[i]`` in units of ``floor`` from ``origin`` and size
    ``floor * 2**level[i]``)."""
    leaves = cspace.leaves()
    ijk = np.asarray(leaves["ijk"], dtype=np.float64).reshape(-1, 3)
    level = np.asarray(leaves["level"], dtype=np.float64).reshape(-1)
    labels = np.asarray(leaves["label"], dtype=np.int64).reshape(-1)
    floor = float(cspace.floor)
    lo = np.asarray(cspace.origin, dtype=np.float64) + ijk * floor
    hi = lo + (floor * 2.0 ** level)[:, None]
    return np.stack([lo, hi], axis=1), labels


def roadmap_from_cspace(cspace, boxes: np.ndarray | None = None) -> np.ndarray:
    """Roadmap edges ``(2 m, 2, 3)``: every face-adjacent pair of EMPTY leaves joined
    centre -> shared-face centre -> centre (two segments per edge)."""
    if boxes is None:
        boxes, _ = cells_from_cspace(cspace)
    pairs, portals = cspace.adjacency([EMPTY])
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    portals = np.asarray(portals, dtype=np.float64).reshape(-1, 3)
    if len(pairs) == 0:
        return np.zeros((0, 2, 3))
    centres = boxes.mean(axis=1)
    first = np.stack([centres[pairs[:, 0]], portals], axis=1)
    second = np.stack([portals, centres[pairs[:, 1]]], axis=1)
    return np.concatenate([first, second])


MAX_ROADMAP_SEGMENTS = 40_000
"""The page draws at most this many roadmap segments (about 1 MB), those nearest the path
(or the start and goal): a fine C-space has hundreds of thousands, which made pages of
tens of MB and show nothing more. The layer's count is the roadmap's full size."""


def shown_roadmap(segments: np.ndarray, near: np.ndarray) -> np.ndarray:
    """At most :data:`MAX_ROADMAP_SEGMENTS` of ``segments`` ``(m, 2, 3)``: the ones whose
    midpoints lie nearest the points ``near`` ``(k, 3)``, in their original order."""
    if len(segments) <= MAX_ROADMAP_SEGMENTS or len(near) == 0:
        return segments[:MAX_ROADMAP_SEGMENTS]
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(near).query(segments.mean(axis=1))
    keep = np.argsort(distance, kind="stable")[:MAX_ROADMAP_SEGMENTS]
    return segments[np.sort(keep)]


def roadmap_note(shown: int, total: int, near_path: bool) -> str:
    """What a roadmap layer of ``shown`` of ``total`` segments draws, in words."""
    if shown >= total:
        return f"all {total:,} segments"
    return (f"the {shown:,} segments nearest the {'path' if near_path else 'start and goal'}, "
            f"of {total:,}")


def _densified(points: np.ndarray, pieces: int = 64) -> np.ndarray:
    """Points along the polyline ``points`` (``pieces`` per segment)."""
    if len(points) < 2:
        return points
    t = np.linspace(0.0, 1.0, pieces, endpoint=False)[:, None]
    along = [a + t * (b - a) for a, b in zip(points[:-1], points[1:], strict=True)]
    return np.vstack([*along, points[-1:]])


def _cspace_arrays(cspace) -> dict[str, np.ndarray]:
    """Cells and roadmap from a native ``CSpace``, a mapping ``{"boxes", "labels",
    "roadmap"}`` (each optional) or a ``(boxes, labels)`` pair."""
    if cspace is None:
        return {}
    if hasattr(cspace, "leaves") and hasattr(cspace, "adjacency"):
        boxes, labels = cells_from_cspace(cspace)
        return {"boxes": boxes, "labels": labels,
                "roadmap": roadmap_from_cspace(cspace, boxes)}
    if isinstance(cspace, Mapping):
        return {k: np.asarray(cspace[k]) for k in ("boxes", "labels", "roadmap")
                if cspace.get(k) is not None}
    if isinstance(cspace, (tuple, list)) and len(cspace) == 2:
        return {"boxes": np.asarray(cspace[0]), "labels": np.asarray(cspace[1])}
    raise InvalidParameterError(
        f"cspace: expected a CSpace, a mapping with boxes/labels/roadmap or (boxes, labels), "
        f"got {type(cspace).__name__}")


DISPLAY_EPS_REL = 0.01
"""Resolution of the C-obstacle surfaces drawn in a scene, as a fraction of the diagonal
of the scenario's bounds: a picture, not the planner's geometry (which is exact), so it
follows the scene's size, not the surface's."""

DISPLAY_MAX_CELLS = 4_000_000
"""Most octree cells of one drawn C-obstacle surface (about 2.5 GB); fewer when the
memory limit is smaller (:func:`display_max_cells`)."""


DISPLAY_MAX_SURFACE_PAIRS = 5_000_000
"""Most triangle pairs of an obstacle and the robot, one of them a surface, whose
C-obstacle a scene draws: every pair's piece is a boundary candidate there, so a picture
of OMPL.app's escape (15,744 × 32,796 triangles) took minutes and gigabytes before it was
refused; such an obstacle is left out with a note (the plan does not need the drawing)."""


def display_max_cells() -> int | None:
    """The cell budget of one drawn surface: :data:`DISPLAY_MAX_CELLS`, or ``None`` (what
    the memory limit allows, :mod:`planner.budget`) when that is less."""
    from planner import budget

    return None if budget.current().surface_cells() < DISPLAY_MAX_CELLS else DISPLAY_MAX_CELLS


def display_eps(scenario) -> float:
    """The resolution the scene's C-obstacle surfaces are drawn at (see
    :data:`DISPLAY_EPS_REL`)."""
    lo, hi = scenario.bounds
    return DISPLAY_EPS_REL * float(np.linalg.norm(np.asarray(hi) - np.asarray(lo)))


def compute_c_obstacles(scenario, *, source=None, eps: float | None = None,
                        cache_dir=None, progress: bool | None = False
                        ) -> dict[str, trimesh.Trimesh]:
    """``{obstacle name: C-obstacle surface}`` from :func:`planner.c_obstacle` on
    ``source`` (a plan's ``outcome.source``: the C-obstacles it planned on), or on the
    source the scenario's settings choose; at ``eps`` (default :func:`display_eps`), not
    refined further where features are thinner (a picture), within
    :func:`display_max_cells`. An obstacle whose C-obstacle is over the memory limit is
    left out, with a warning (a picture is not worth refusing the page for).
    """
    from planner.minkowski import c_obstacle
    from planner.sources import choose_for

    if source is None:
        source = choose_for([scenario.robot, *scenario.obstacles], scenario.settings,
                            cache_dir=cache_dir, progress=progress)
    eps = display_eps(scenario) if eps is None else eps
    surfaces = {}
    robot = scenario.robot
    for body in scenario.obstacles:
        pairs = len(body.mesh.faces) * len(robot.mesh.faces)
        if not (body.solid and robot.solid) and pairs > DISPLAY_MAX_SURFACE_PAIRS:
            log.warning("the scene leaves out the C-obstacle of %s: %d triangle pairs with a "
                        "surface (more than %d) are too many to draw", body.name, pairs,
                        DISPLAY_MAX_SURFACE_PAIRS)
            continue
        try:  # a picture's complex cells are no warning
            surfaces[body.name] = c_obstacle(
                body, scenario.robot, eps=eps, progress=progress, source=source,
                max_refinements=0, max_cells=display_max_cells(), warn_complex=False).mesh
        except ResourceLimitError as error:
            log.warning("the scene leaves out the C-obstacle of %s: %s", body.name, error)
    return surfaces


# ---- the plan --------------------------------------------------------------------------

def _read_json(path: Path) -> Any:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def plan_parts(plan) -> dict[str, Any]:
    """What a scene needs of a plan: ``status``, ``reason``, ``waypoints`` ``(k, 3)``,
    ``certificate`` (dict or ``None``), ``cspace`` and ``source`` (or ``None``).

    ``plan`` is ``None``, a ``PlanOutcome``, the ``path.json`` dict (optionally with a
    ``"certificate"``) or the path of a ``path.json`` file (a ``certificate.json`` beside
    it is read too). Missing parts come back empty.
    """
    parts: dict[str, Any] = {"status": None, "reason": None, "waypoints": np.zeros((0, 3)),
                             "certificate": None, "cspace": None, "source": None}
    if plan is None:
        return parts
    if isinstance(plan, (str, os.PathLike)):
        path = Path(plan)
        document = _read_json(path)
        if not isinstance(document, Mapping):
            raise InvalidParameterError(f"{path}: expected a JSON object (path.json)")
        document = dict(document)
        beside = path.with_name("certificate.json")
        if "certificate" not in document and beside.is_file():
            document["certificate"] = _read_json(beside)
        plan = document
    if hasattr(plan, "path_json"):  # a PlanOutcome
        document = dict(plan.path_json())
        document["certificate"] = getattr(plan, "certificate", None)
        parts["cspace"] = getattr(plan, "cspace", None)
        parts["source"] = getattr(plan, "source", None)
        plan = document
    if not isinstance(plan, Mapping):
        raise InvalidParameterError(
            f"plan: expected a PlanOutcome, a path.json dict or file, got {type(plan).__name__}")
    parts["status"] = plan.get("status")
    parts["reason"] = plan.get("reason")
    waypoints = plan.get("waypoints")
    if waypoints is not None and len(waypoints):
        array = np.asarray(waypoints, dtype=np.float64)
        if array.ndim != 2 or array.shape[1] != 3:
            raise InvalidParameterError(
                f"plan waypoints: expected [[x, y, z], ...], got shape {array.shape}")
        parts["waypoints"] = array
    parts["certificate"] = plan.get("certificate")
    if plan.get("cspace") is not None:
        parts["cspace"] = plan["cspace"]
    return parts


def _certificate_boxes(certificate) -> tuple[np.ndarray, np.ndarray | None]:
    """Wall boxes and component boxes from a certificate in either form: the reports'
    (``walls: [{"box": ...}]``, ``component: {"boxes": ...}``) or the core's
    (``wall_boxes``)."""
    if certificate is None:
        return np.zeros((0, 2, 3)), None
    if "wall_boxes" in certificate:
        walls = np.asarray(certificate["wall_boxes"], dtype=np.float64)
    else:
        walls = np.asarray([w["box"] for w in certificate.get("walls") or []], dtype=np.float64)
    component = certificate.get("component")
    comp = None
    if isinstance(component, Mapping) and component.get("boxes") is not None:
        comp = np.asarray(component["boxes"], dtype=np.float64).reshape(-1, 2, 3)
    return walls.reshape(-1, 2, 3), comp


def scene_for_plan(scenario, plan=None, cspace=None, *, c_obstacle=None, certificate=None,
                   animate: bool = True, cell_style: str = "auto",
                   title: str | None = None) -> Scene:
    """The scene of a planning problem, and of its result when given.

    Args:
        scenario: a ``Scenario`` or the path of a scenario YAML.
        plan: ``None``, a ``PlanOutcome``, a ``path.json`` dict or file (see
            :func:`plan_parts`); its waypoints give the path and the animation, its
            certificate the wall cells.
        cspace: octree leaves and roadmap: a native ``CSpace``, a mapping with ``boxes``
            ``(n, 2, 3)``, ``labels`` ``(n,)``, ``roadmap`` ``(m, 2, 3)`` (each optional)
            or ``(boxes, labels)``; default: the plan's, if it carries one.
        c_obstacle: C-obstacle surface(s): a mesh, a ``MinkowskiResult``, a mapping
            ``{name: mesh}``, or ``True`` to compute them with the core
            (:func:`compute_c_obstacles`, on the plan's source when it is a
            ``PlanOutcome``: what is drawn is what was planned).
        certificate: a no-path certificate, overriding the plan's.
        animate: add the robot moving along the path.
        cell_style: how to draw cells (see :meth:`Scene.add_boxes`).
        title: page title (default: the scenario's name and the plan's status).
    """
    if isinstance(scenario, (str, os.PathLike)):
        from planner.io import load_scenario

        scenario = load_scenario(scenario)
    parts = plan_parts(plan)
    status = parts["status"]
    scene = Scene(title or (f"{scenario.name}: {status}" if status else scenario.name))
    scene.add_obstacles(scenario.obstacles)
    reason = parts["reason"] or ""
    scene.add_robot(
        scenario.robot.mesh, scenario.start, scenario.goal,
        start_color=COLORS["robot_collision"] if reason == "start_in_collision" else None,
        goal_color=COLORS["robot_collision"] if reason == "goal_in_collision" else None,
    )

    note = ""
    if c_obstacle is True:  # on the source the plan used, if it says
        c_obstacle = compute_c_obstacles(scenario, source=parts["source"])
        note = (f"drawn at a display resolution of {display_eps(scenario):.3g} "
                f"{scenario.units} (a picture: the planner's are exact)")
        left_out = [o.name for o in scenario.obstacles if o.name not in c_obstacle]
        if left_out:
            note += f"; not drawn, over the memory limit: {', '.join(left_out)}"
    if c_obstacle is not None and c_obstacle is not False:
        scene.add_c_obstacle(c_obstacle, note=note)

    arrays = _cspace_arrays(cspace if cspace is not None else parts["cspace"])
    if arrays.get("boxes") is not None and arrays.get("labels") is not None:
        scene.add_cells(arrays["boxes"], arrays["labels"], style=cell_style)
    waypoints = parts["waypoints"]
    roadmap = arrays.get("roadmap")
    if roadmap is not None and len(roadmap):
        ends = np.stack([scenario.start, scenario.goal])
        near = _densified(np.asarray(waypoints, dtype=np.float64).reshape(-1, 3)) \
            if len(waypoints) else ends
        shown = shown_roadmap(np.asarray(roadmap), near)
        scene.add_segments(ROADMAP, shown, color=COLORS["roadmap"], count=len(roadmap),
                           note=roadmap_note(len(shown), len(roadmap), bool(len(waypoints))))

    if len(waypoints):
        scene.add_path(waypoints)
        if animate and len(waypoints) >= 2:
            scene.add_motion(scenario.robot.mesh, waypoints)

    walls, component = _certificate_boxes(certificate if certificate is not None
                                          else parts["certificate"])
    if len(walls) or component is not None:
        scene.add_certificate(walls, component)
    # an obstacle enclosing what the answer is about would hide it
    scene.see_through(np.vstack([np.reshape(waypoints, (-1, 3)), [scenario.start],
                                 [scenario.goal], walls.mean(axis=1)]))
    return scene


# ---- anything to a scene ---------------------------------------------------------------

def as_scene(obj, **kwargs) -> Scene:
    """``obj`` as a :class:`Scene`:

    - a ``Scene``: itself;
    - a ``MinkowskiResult`` (has ``.mesh`` and ``.error_bound``): :func:`scene_for_minkowski`
      (``a=``, ``b=``, ``c_obstacle=`` as keywords);
    - a ``Scenario`` or a scenario path: :func:`scene_for_plan` (``plan=``, ``cspace=``...);
    - a ``PlanOutcome`` or a ``path.json`` dict: :func:`scene_for_plan` with
      ``scenario=`` given as a keyword;
    - a ``trimesh.Trimesh``: that mesh alone (at ``workspace/obstacles/mesh``).
    """
    if isinstance(obj, Scene):
        if kwargs:
            raise TypeError(f"as_scene: unexpected keywords for a Scene: {sorted(kwargs)}")
        return obj
    if hasattr(obj, "error_bound") and hasattr(obj, "mesh"):
        return scene_for_minkowski(obj, **kwargs)
    if isinstance(obj, trimesh.Trimesh):
        scene = Scene(kwargs.pop("title", "mesh"))
        scene.add_obstacles({"mesh": obj})
        return scene
    if hasattr(obj, "robot") and hasattr(obj, "obstacles") or isinstance(obj, (str, os.PathLike)):
        return scene_for_plan(obj, **kwargs)
    if hasattr(obj, "path_json") or isinstance(obj, Mapping):
        scenario = kwargs.pop("scenario", None)
        if scenario is None:
            raise TypeError("as_scene: a plan needs its scenario: as_scene(plan, scenario=...)")
        return scene_for_plan(scenario, obj, **kwargs)
    raise TypeError(f"as_scene: cannot make a scene of {type(obj).__name__}")
