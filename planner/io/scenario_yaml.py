"""The scenario YAML reader (the format is in ``docs/scenario.md``).

Entry points: :func:`read_scenario` (a file) and :func:`parse_scenario` (text or a
mapping), both to a validated :class:`~planner.problem.Scenario`. Every problem raises
:class:`~planner.errors.ScenarioError` with a one-line message
``"<file>:<line>: <field>: <problem>"`` (``":<line>"`` only when the field has a line in
the file), and its ``field`` and ``line`` attributes set.

Conventions (see ``docs/scenario.md``): quaternions are ``[w, x, y, z]`` (scalar first);
``{rpy: [r, p, y]}`` is in degrees about the fixed axes x, then y, then z; an obstacle's
vertices ``v`` map to the world as ``position + R @ (scale * v)``; start and goal
orientations must be equal (the robot only translates).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from planner.problem import Scenario, default_bounds, outside_bounds
from planner.tolerances import tol
from planner.values import describe_value

from .fields import (
    Document,
    check_mapping,
    field_error,
    join,
    name_of,
    parse_document,
    parse_orientation,
    read_text,
    rotation_angle_deg,
    settings_from_mapping,
    vector,
)
from .parts import (
    OBSTACLE_KEYS,
    ROBOT_KEYS,
    MeshCache,
    assign_names,
    build_part,
    object_spec,
    rotation4,
)

__all__ = ["parse_scenario", "read_scenario"]


TOP_LEVEL_KEYS = ("name", "units", "robot", "obstacles", "start", "goal", "bounds", "planner")


ENDPOINT_KEYS = ("position", "orientation")


BOUNDS_KEYS = ("min", "max")


def read_scenario(path: str | os.PathLike[str], *,
                  hold_orientation: str | None = None) -> Scenario:
    """Read and validate a scenario YAML file.

    Args:
        path: a scenario ``.yaml``/``.yml`` file; mesh paths inside it are relative to
            its folder.
        hold_orientation: ``"start"`` or ``"goal"``: when start and goal orientations
            differ, the robot keeps that one throughout (a translation-only reading,
            noted in ``Scenario.notes``); ``None``: that is an error.

    Returns:
        The validated :class:`Scenario` (``name`` defaults to the file's stem).

    Raises:
        ScenarioError: the file cannot be read or is invalid; the message is one line,
            ``"<path>:<line>: <field>: <problem>"``.
    """
    path = Path(path)
    return parse_document(read_text(path, "scenario"), Document(str(path)),
                          lambda data: _build(data, path.parent, path.resolve(), path.stem,
                                              hold_orientation))


def parse_scenario(
    source: str | Mapping[str, Any],
    base_dir: str | os.PathLike[str] | None = None,
    *,
    filename: str | None = None,
) -> Scenario:
    """Validate a scenario given as YAML text or as an already-loaded mapping.

    Args:
        source: YAML text, or a mapping with the same structure (no line numbers then).
        base_dir: folder that relative mesh paths are resolved against (default: the
            current directory).
        filename: name used in error messages (default ``"<scenario>"``).

    Raises:
        ScenarioError: as :func:`read_scenario`.
    """
    if isinstance(source, os.PathLike):
        raise TypeError("parse_scenario takes YAML text or a mapping; use "
                        "planner.load_scenario for a file")
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    return parse_document(source, Document(filename or "<scenario>"),
                          lambda data: _build(data, base, None, "scenario"))


def _held_orientation(start: np.ndarray | None, goal: np.ndarray | None, hold: str | None,
                      notes: list[str]) -> np.ndarray:
    """The robot's one orientation: the start's (or the goal's, or the identity) when they
    agree within ``tol.orientation_deg``; else the one ``hold`` names, noted."""
    if start is not None and goal is not None:
        angle = rotation_angle_deg(start, goal)
        if angle > tol.orientation_deg:
            if hold is None:
                raise field_error("goal.orientation",
                                  f"differs from start.orientation by {angle:.4g} degrees; "
                                  "the part only translates, so start and goal orientations "
                                  "must be equal (or plan with one of them throughout: "
                                  "--hold-orientation start or goal)")
            notes.append(f"translation-only reading: the robot keeps the {hold} orientation "
                         f"throughout (the other differs by {angle:.4g} degrees)")
            return goal if hold == "goal" else start
    return next((r for r in (start, goal) if r is not None), np.eye(3))


def _build(data: Any, base_dir: Path, path: Path | None, default_name: str,
           hold_orientation: str | None = None) -> Scenario:
    if data is None:
        raise field_error("", "the scenario is empty; it needs at least robot, start and goal")
    top = check_mapping(data, "", TOP_LEVEL_KEYS, ("robot", "start", "goal"))

    name = default_name if top.get("name") is None else name_of(top["name"], "name")
    units = "unitless" if top.get("units") is None else name_of(top["units"], "units")
    settings = settings_from_mapping(top.get("planner"), field="planner")

    # Start, goal and the fixed orientation.
    start, start_rotation = _endpoint(top["start"], "start")
    goal, goal_rotation = _endpoint(top["goal"], "goal")
    notes: list[str] = []
    orientation = _held_orientation(start_rotation, goal_rotation, hold_orientation, notes)

    explicit_bounds = None
    if top.get("bounds") is not None:
        spec = check_mapping(top["bounds"], "bounds", BOUNDS_KEYS, BOUNDS_KEYS)
        lo = vector(spec["min"], "bounds.min")
        hi = vector(spec["max"], "bounds.max")
        bad = [axis for axis, a, b in zip("xyz", lo, hi) if a >= b]
        if bad:
            raise field_error("bounds.max", f"max must be greater than min on every axis; "
                                       f"not on {', '.join(bad)} (min {lo.tolist()}, "
                                       f"max {hi.tolist()})")
        explicit_bounds = (lo, hi)

    # Every object's spec (cheap checks, file existence) before loading any mesh.
    robot_spec = object_spec(top["robot"], "robot", ROBOT_KEYS, base_dir)
    raw_obstacles = top.get("obstacles")
    if raw_obstacles is None:
        raw_obstacles = []
    if not isinstance(raw_obstacles, (list, tuple)):
        raise field_error("obstacles", f"expected a list of objects, got "
                                       f"{describe_value(raw_obstacles)}")
    obstacle_specs = [object_spec(value, f"obstacles[{i}]", OBSTACLE_KEYS, base_dir)
                      for i, value in enumerate(raw_obstacles)]

    names = assign_names([robot_spec, *obstacle_specs])
    cache: MeshCache = {}

    robot = build_part(robot_spec, names[0], cache, rotation4(orientation))
    obstacles = [build_part(spec, name, cache, spec.pose.matrix)
                 for spec, name in zip(obstacle_specs, names[1:], strict=True)]

    if explicit_bounds is None:
        bounds = default_bounds(robot.mesh, [b.mesh for b in obstacles], start, goal)
    else:
        bounds = explicit_bounds
        for field, point in (("start", start), ("goal", goal)):
            outside = outside_bounds(point, bounds)
            if outside:
                target = f"{field}.position" if isinstance(top[field], Mapping) else field
                raise field_error(target, f"{point.tolist()} is outside bounds "
                                          f"({'; '.join(outside)})")

    return Scenario(name=name, units=units, robot=robot, obstacles=obstacles, start=start,
                    goal=goal, orientation=orientation, bounds=bounds, settings=settings,
                    path=path, notes=tuple(notes))


def _endpoint(value: Any, field: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``[x, y, z]`` or ``{position: [x, y, z], orientation: ...}``."""
    if isinstance(value, Mapping):
        spec = check_mapping(value, field, ENDPOINT_KEYS, ("position",))
        position = vector(spec["position"], join(field, "position"))
        if spec.get("orientation") is None:
            return position, None
        return position, parse_orientation(spec["orientation"],
                                           field=join(field, "orientation"))
    if isinstance(value, (list, tuple)):
        return vector(value, field), None
    raise field_error(field, f"expected [x, y, z] or {{position: [x, y, z], orientation: ...}}, "
                        f"got {describe_value(value)}")
