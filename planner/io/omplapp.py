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
  (rows ``x y z qx qy qz qw``) and the ``(4, 4)`` pose of one row;
  :func:`write_omplapp_path` writes a translational path in that format.

The meshes are read as OMPL.app reads them (:mod:`planner.io.omplapp_meshes`: its frame,
its reference point, the world as solids and surfaces). A state ``(p, R)`` places a robot
vertex ``v`` at ``R @ (v - c) + p``, with ``c`` the reference point.

Orientations: minkplan only translates the robot. Start and goal orientations equal
within ``tol.orientation_deg`` are one orientation, applied to the robot mesh once. When
they really differ (a 6-DOF problem), the translation-only reading holds one of them
throughout (``hold_orientation="start"`` or ``"goal"``, the CLI's
``--hold-orientation``) and says so in ``Scenario.notes``; without it that is an error
that offers the reading. ``Scenario.notes`` records every decision of the import.

Duplicate keys are accepted as OMPL.app accepts them (the last one counts): its own
``cubicles_opt.cfg`` lists ``aps=`` twice under ``[planner]``; one repeated in
``[problem]`` is noted (and logged as a warning). A section, or a key of ``[problem]`` or
``[benchmark]``, that OMPL.app does not define is an error when it is close to one it
does (``[benchmrk]``, ``volume.mx.z``, ``time_limt``: a typo that would silently change
the problem), and is noted and logged as ignored otherwise (OMPL.app passes other
``[problem]`` keys to its planners as parameters; minkplan has none to give them to).
``control`` (a kinodynamic system) is refused.
"""

from __future__ import annotations

import configparser
import difflib
import logging
import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np
from trimesh import transformations as tf

from planner.errors import InvalidMeshError, ScenarioError
from planner.meshes import SOLID_REASON, not_solid_reason, validate_solid
from planner.problem import Body, PlannerSettings, Robot, Scenario, default_bounds
from planner.tolerances import tol

from .fields import rotation_angle_deg
from .omplapp_meshes import (
    APP_FROM_ZUP,
    read_app_mesh,
    robot_reference_point,
    single_sided,
    world_parts,
)

__all__ = [
    "APP_FROM_ZUP",
    "load_omplapp",
    "path_rows",
    "path_state_transform",
    "read_app_mesh",
    "read_omplapp_path",
    "robot_reference_point",
    "write_omplapp_path",
]


# ------------------------------------------------------------------------------ meshes


# ------------------------------------------------------------------------------ config

log = logging.getLogger(__name__)

_POSE_KEYS = ("x", "y", "z", "theta", "axis.x", "axis.y", "axis.z")
_KNOWN_SECTIONS = ("problem", "benchmark", "planner")
#: The keys OMPL.app defines, per section whose keys it checks (its documentation and its
#: benchmark program's options).
_KNOWN_KEYS = {
    "problem": ("name", "robot", "world", "objective", "objective.threshold", "control",
                "sampler", "threshold", "solution_length",
                *(f"{end}.{key}" for end in ("start", "goal") for key in _POSE_KEYS),
                *(f"volume.{end}.{axis}" for end in ("min", "max") for axis in "xyz")),
    "benchmark": ("time_limit", "mem_limit", "run_count", "output", "save_paths",
                  "simplify"),
}
#: How alike an unknown key must be to a known one to be taken for its typo.
_TYPO_CUTOFF = 0.8


def _section_line(text: str, section: str) -> int | None:
    return _first_line(text, rf"^\s*\[\s*{re.escape(section)}\s*\]")


def _repeated_problem_keys(text: str) -> list[str]:
    """Keys given more than once in ``[problem]`` (the last one counts)."""
    seen: dict[str, int] = {}
    section = None
    for line in text.splitlines():
        header = re.match(r"^\s*\[\s*([^\]]+?)\s*\]", line)
        if header:
            section = header.group(1).lower()
            continue
        entry = re.match(r"^\s*([^#;\s=:][^=:]*?)\s*[=:]", line)
        if section == "problem" and entry:
            key = entry.group(1).lower()
            seen[key] = seen.get(key, 0) + 1
    return [key for key, count in seen.items() if count > 1]


def _cfg_line(text: str, key: str) -> int | None:
    return _first_line(text, rf"^\s*{re.escape(key)}\s*[=:]")


def _first_line(text: str, pattern: str) -> int | None:
    """The number of the first line that ``pattern`` matches (case-insensitive)."""
    compiled = re.compile(pattern, re.IGNORECASE)
    for number, line in enumerate(text.splitlines(), start=1):
        if compiled.match(line):
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
        # OMPL.app accepts repeated keys (its cubicles_opt.cfg has two "aps="): so do we
        parser = configparser.ConfigParser(interpolation=None, strict=False)
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

    def unknown_keys(self) -> list[str]:
        """Sections and keys OMPL.app does not define, as ``[section]`` and
        ``section.key``; raises for a likely typo of one it does."""
        unknown = []
        for section in self.parser.sections():
            if section in _KNOWN_SECTIONS:
                continue
            close = difflib.get_close_matches(section, _KNOWN_SECTIONS, n=1,
                                              cutoff=_TYPO_CUTOFF)
            if close:
                line = _section_line(self.text, section)
                where = self.label if line is None else f"{self.label}:{line}"
                raise ScenarioError(f"{where}: [{section}]: unknown section; did you mean "
                                    f"[{close[0]}]?", field=section, line=line)
            unknown.append(f"[{section}]")
        for section, known in _KNOWN_KEYS.items():
            if not self.parser.has_section(section):
                continue
            for key in self.parser[section]:
                if key in known:
                    continue
                close = difflib.get_close_matches(key, known, n=1, cutoff=_TYPO_CUTOFF)
                if close:
                    raise self.key_error(section, key, f"unknown key; did you mean "
                                                       f"{close[0]!r}?")
                unknown.append(f"{section}.{key}")
        return unknown

    def error(self, key: str, problem: str) -> ScenarioError:
        return self.key_error("problem", key, problem)

    def key_error(self, section: str, key: str, problem: str) -> ScenarioError:
        field = f"{section}.{key}"
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


def load_omplapp(cfg_path: str | os.PathLike[str], *,
                 hold_orientation: str | None = None) -> Scenario:
    """Read an OMPL.app SE(3) problem as a translational :class:`Scenario`.

    The robot mesh is expressed relative to its reference point (see
    :func:`robot_reference_point`) with the start orientation applied (the goal's with
    ``hold_orientation="goal"``), so the scenario's ``start``/``goal`` are the ``.cfg``'s
    positions. The world becomes one obstacle per
    connected piece (named ``"<world file stem>_<k>"``), each a validated solid; what the
    import had to change is listed in ``Scenario.notes`` (see the module doc).
    ``volume`` becomes the bounds; ``[benchmark] time_limit``, when present, the
    planner's time limit. Units are ``"unitless"`` (the files state none).

    Raises:
        ScenarioError: missing or malformed keys (field ``problem.<key>``, with its line),
            missing or unusable meshes, a 2D (SE(2)) problem, a goal orientation that
            differs from the start's (unless ``hold_orientation`` says which to keep),
            start or goal outside the volume, a key that looks like a typo of one
            OMPL.app defines, a kinodynamic (``control``) problem.
    """
    path = Path(cfg_path)
    cfg = _Cfg(path)
    base = path.parent
    ignored = cfg.unknown_keys()
    if cfg.has("control"):
        raise cfg.error("control", f"{cfg.problem['control'].strip()!r}: kinodynamic "
                                   "problems are not supported, only rigid-body ones")
    if not cfg.has("start.z") and cfg.has("start.x"):
        raise cfg.error("start.z", "missing: 2D (SE(2)) problems are not supported, only "
                                   "3D rigid bodies")
    start = cfg.vector("start")
    goal = cfg.vector("goal")
    notes: list[str] = []
    if ignored:
        notes.append(f"sections and keys OMPL.app does not define, ignored: "
                     f"{', '.join(ignored)}")
    repeated = _repeated_problem_keys(cfg.text)
    if repeated:
        notes.append(f"keys given more than once in [problem] (the last one counts, as "
                     f"OMPL.app reads them): {', '.join(repeated)}")
    for note in notes:
        log.warning("%s: %s", path, note)
    orientation = _held_orientation(cfg, hold_orientation, notes)
    robot_file = cfg.mesh_path("robot", base)
    world_file = cfg.mesh_path("world", base)
    try:
        raw_robot = read_app_mesh(robot_file)
        centre = robot_reference_point(raw_robot)
        single, dropped = single_sided(raw_robot)
        if dropped:
            notes.append(f"robot: dropped {dropped} back-side duplicate triangles "
                         "(double-sided export)")
    except InvalidMeshError as error:
        raise cfg.error("robot", str(error)) from None
    robot_solid, robot_why = True, SOLID_REASON
    try:
        robot_mesh = validate_solid(single, name=robot_file.stem)
    except InvalidMeshError as error:
        robot_mesh, robot_solid = single, False
        robot_why = not_solid_reason(error)
        notes.append(f"robot: a surface (triangles, as OMPL.app and FCL see them): {robot_why}")
    robot_mesh.apply_translation(-centre)
    robot_mesh.apply_transform(_homogeneous(orientation))
    robot = Robot(robot_file.stem, robot_mesh,
                  f"{robot_file.resolve()} (OMPL.app frame, reference point "
                  f"{np.round(centre, 6).tolist()})", robot_solid, robot_why, checked=robot_solid)

    try:
        parts = world_parts(read_app_mesh(world_file), world_file.stem, notes)
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


def _held_orientation(cfg: _Cfg, hold: str | None, notes: list[str]) -> np.ndarray:
    """The robot's one orientation: the start's when the goal's equals it (within
    ``tol.orientation_deg``), else the one ``hold`` names, noted; else an error that
    offers that reading."""
    start, goal = cfg.rotation("start"), cfg.rotation("goal")
    degrees = rotation_angle_deg(start, goal)
    if hold not in (None, "start", "goal"):
        raise ScenarioError(f"hold_orientation = {hold!r}: use 'start' or 'goal'")
    if degrees <= tol.orientation_deg:
        return start
    if hold is None:
        raise cfg.error("goal.theta", f"goal orientation differs from the start's by "
                                      f"{degrees:.4g} degrees; minkplan only translates the "
                                      "robot: plan with one orientation throughout with "
                                      "--hold-orientation start (or goal), a translation-only "
                                      "reading of the problem")
    notes.append(f"translation-only reading: the robot keeps the {hold} orientation "
                 f"throughout (the other differs by {degrees:.4g} degrees)")
    return start if hold == "start" else goal


def _benchmark_time_limit(cfg: _Cfg) -> float | None:
    if not cfg.parser.has_option("benchmark", "time_limit"):
        return None
    raw = cfg.parser["benchmark"]["time_limit"].strip()
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise cfg.key_error("benchmark", "time_limit", f"expected a number > 0, got {raw!r}")
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


def path_rows(waypoints: Any, orientation: Any) -> np.ndarray:
    """A translational path as OMPL SE(3) states: rows ``x y z qx qy qz qw``, each
    waypoint with the robot's one orientation ``(3, 3)`` (quaternion scalar last, sign
    chosen with ``qw >= 0``)."""
    matrix = np.eye(4)
    matrix[:3, :3] = np.asarray(orientation, dtype=np.float64)
    qw, qx, qy, qz = tf.quaternion_from_matrix(matrix)
    quaternion = np.array([qx, qy, qz, qw]) * (1.0 if qw >= 0 else -1.0)
    points = np.asarray(waypoints, dtype=np.float64).reshape(-1, 3)
    return np.hstack([points, np.tile(quaternion, (len(points), 1))])


def write_omplapp_path(path: str | os.PathLike[str], waypoints: Any, orientation: Any) -> None:
    """Write a path in OMPL's SE(3) path format (what ``PathGeometric::printAsMatrix``
    prints and OMPL.app reads: a state per line), atomically; :func:`read_omplapp_path`
    reads it back."""
    from planner.output import atomic_write

    text = "".join(" ".join(repr(float(v)) for v in row) + "\n"
                   for row in path_rows(waypoints, orientation))
    atomic_write(Path(path), lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
