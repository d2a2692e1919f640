"""Scenario files: read a scenario YAML, validate it and return typed, posed geometry.

This module is the edge of the planner: it is the only place that reads scenario files,
resolves mesh paths, applies poses and records units and seeds. Everything downstream
receives a :class:`Scenario`.

Entry points:

- :func:`load_scenario` -- read a ``.yaml`` file (or an OMPL.app ``.cfg`` through
  :func:`planner.omplapp.load_omplapp`) into a :class:`Scenario`.
- :func:`parse_scenario` -- the same from YAML text or an already-loaded mapping.
- :func:`parse_orientation` -- one orientation spec to a ``(3, 3)`` rotation matrix.
- :func:`default_bounds` -- the translation bounds used when the file gives none.
- :class:`PlannerSettings` -- the ``planner:`` block, also usable on its own
  (``PlannerSettings.from_mapping({"time_limit": 5})``).

Conventions (see ``docs/scenario.md`` for the whole format):

- The robot's orientation is fixed for the whole motion. At the configuration ``t`` (a
  translation, ``(3,)``) the robot occupies ``Scenario.robot.mesh + t``: the robot mesh
  is stored in its own frame with the orientation already applied. ``start`` and
  ``goal`` are such translations, i.e. positions of the robot mesh's origin.
- Quaternions are written ``[w, x, y, z]`` (scalar first). ``{rpy: [r, p, y]}`` is in
  degrees, about the fixed axes x, then y, then z: ``R = Rz(y) @ Ry(p) @ Rx(r)``.
  ``{axis: [x, y, z], angle_deg: a}`` turns by ``a`` degrees about ``axis``
  (right-hand rule).
- An obstacle's vertices ``v`` map to the world as ``position + R @ (scale * v)``.
- Lengths are in the scenario's ``units`` (recorded, never converted).

Every problem raises :class:`~planner.errors.ScenarioError` with a one-line message
``"<file>:<line>: <field>: <problem>"`` (``":<line>"`` only when the field has a line in
the file), and its ``field`` and ``line`` attributes set.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import trimesh
import yaml
from trimesh import transformations as tf

from .errors import InvalidParameterError, ScenarioError
from .meshes import MESH_SUFFIXES
from .primitives import PRIMITIVE_KINDS, make_primitive
from .tolerances import tol

__all__ = [
    "DEFAULT_BOUNDS_MARGIN",
    "ORIENTATION_TOLERANCE_DEG",
    "Body",
    "PlannerSettings",
    "Pose",
    "Robot",
    "Scenario",
    "default_bounds",
    "load_scenario",
    "parse_orientation",
    "parse_scenario",
]

ORIENTATION_TOLERANCE_DEG = 1e-4
"""Start and goal orientations may differ by at most this angle (degrees)."""

QUATERNION_NORM_TOLERANCE = 1e-3
"""A quaternion ``[w, x, y, z]`` is accepted (and normalised) when ``|norm - 1|`` is at
most this; anything else is almost surely a typo or a wrong component order."""

DEFAULT_BOUNDS_MARGIN = 0.1
"""Default bounds grow on every side by this fraction of their largest side."""

TOP_LEVEL_KEYS = ("name", "units", "robot", "obstacles", "start", "goal", "bounds", "planner")
ROBOT_KEYS = ("name", "mesh", *PRIMITIVE_KINDS, "scale", "repair")
OBSTACLE_KEYS = ("name", "mesh", *PRIMITIVE_KINDS, "position", "orientation", "scale", "repair")
ENDPOINT_KEYS = ("position", "orientation")
BOUNDS_KEYS = ("min", "max")
ORIENTATION_KEYS = ("quaternion", "rpy", "axis", "angle_deg")


# --------------------------------------------------------------------------------------
# Typed result
# --------------------------------------------------------------------------------------


def _frozen_array(value: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
    array = np.array(value, dtype=np.float64)  # a copy: callers keep their own array
    if array.shape != shape:
        raise InvalidParameterError(f"{what}: expected shape {shape}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidParameterError(f"{what}: values must be finite")
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Pose:
    """A rigid pose: ``x_world = rotation @ x_local + position``.

    Attributes:
        position: ``(3,)`` translation.
        rotation: ``(3, 3)`` rotation matrix (orthonormal, det +1).
    """

    position: np.ndarray
    rotation: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", _frozen_array(self.position, (3,), "Pose.position"))
        object.__setattr__(self, "rotation", _frozen_array(self.rotation, (3, 3), "Pose.rotation"))

    @property
    def matrix(self) -> np.ndarray:
        """The ``(4, 4)`` homogeneous transform (a new, writable array)."""
        matrix = np.eye(4)
        matrix[:3, :3] = self.rotation
        matrix[:3, 3] = self.position
        return matrix

    @classmethod
    def identity(cls) -> Pose:
        return cls(np.zeros(3), np.eye(3))


@dataclass(frozen=True, eq=False)
class Body:
    """An obstacle.

    Attributes:
        name: unique name within the scenario (used in reports).
        mesh: triangle mesh, posed in the world frame: a solid (closed, winding number
            never negative) unless ``solid`` is false.
        source: where it came from: a resolved file path, ``"box [1, 2, 3]"``, ...
        solid: ``True``: a solid (a robot inside it collides); ``False``: a surface, any
            set of triangles, which collides only where triangles meet (FCL's and
            OMPL.app's meaning).
        kind_reason: why it is a solid or a surface (for reports).
    """

    name: str
    mesh: trimesh.Trimesh
    source: str
    solid: bool = True
    kind_reason: str = "closed and its winding number never negative"


@dataclass(frozen=True, eq=False)
class Robot:
    """The moving part.

    Attributes:
        name: unique name within the scenario.
        mesh: triangle mesh in the robot's own frame with the (fixed) orientation
            and scale applied but not translated: at configuration ``t`` the robot
            occupies ``mesh + t``.
        source: where it came from (resolved file path or primitive description).
        solid: a solid (``True``) or a surface, as for :class:`Body`.
        kind_reason: why (for reports).
    """

    name: str
    mesh: trimesh.Trimesh
    source: str
    solid: bool = True
    kind_reason: str = "closed and its winding number never negative"


def _check_optional(value: Any, low: float, *, strict: bool) -> float | None:
    return None if value is None else _check_real(value, low, strict=strict)


def _check_real(value: Any, low: float, *, strict: bool, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"expected a number, got {_describe(value)}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, got {value!r}")
    if (number <= low) if strict else (number < low):
        raise ValueError(f"must be {'>' if strict else '>='} {low:g}, got {value!r}")
    if high is not None and number > high:
        raise ValueError(f"must be <= {high:g}, got {value!r}")
    return number


def _check_seed(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"expected an integer, got {_describe(value)}")
    if not 0 <= int(value) < 2**63:
        raise ValueError(f"must be in 0 .. 2**63 - 1, got {value!r}")
    return int(value)


def _check_exact(value: Any) -> bool | Literal["auto"]:
    if value == "auto" or isinstance(value, bool):
        return value
    raise ValueError(f"expected auto, true or false, got {_describe(value)}")


def _check_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    raise ValueError(f"expected true or false, got {_describe(value)}")


_SETTING_CHECKS = {
    "resolution": lambda v: _check_optional(v, 0.0, strict=True),
    "time_limit": lambda v: _check_real(v, 0.0, strict=True),
    "seed": _check_seed,
    "contact_tolerance": lambda v: _check_optional(v, 0.0, strict=False),
    "decomposition_threshold": lambda v: _check_real(v, 0.01, strict=False, high=1.0),
    "exact": _check_exact,
    "clearance": lambda v: _check_real(v, 0.0, strict=False),
    "simplify": _check_bool,
}


@dataclass(frozen=True)
class PlannerSettings:
    """Planner settings; the field names are the keys of the scenario's ``planner:`` block.

    Attributes:
        resolution: finest octree cell size in scenario units; ``None``: automatic
            (from the scene's size, see :mod:`planner.tolerances`).
        time_limit: wall-clock budget in seconds, ``> 0``.
        seed: seed of every random choice (recorded in reports), ``>= 0``.
        contact_tolerance: distance below which touching counts as contact, not
            collision, in scenario units; ``None``: relative to the scene's size.
        decomposition_threshold: CoACD concavity threshold, ``0.01 .. 1``.
        exact: ``"auto"`` (exact where the decomposition is exact), ``True`` (insist:
            fail rather than approximate) or ``False`` (always approximate).
        clearance: requested margin between robot and obstacles along the path, ``>= 0``.
        simplify: shortcut the path after the graph search.
    """

    resolution: float | None = None
    time_limit: float = 30.0
    seed: int = 0
    contact_tolerance: float | None = None
    decomposition_threshold: float = tol.coacd_threshold
    exact: bool | Literal["auto"] = "auto"
    clearance: float = 0.0
    simplify: bool = True

    def __post_init__(self) -> None:
        for name, check in _SETTING_CHECKS.items():
            try:
                object.__setattr__(self, name, check(getattr(self, name)))
            except ValueError as error:
                raise InvalidParameterError(f"PlannerSettings.{name}: {error}") from None

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The accepted setting names, in documentation order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def from_mapping(cls, mapping: Mapping[str, Any] | None, *,
                     field: str = "planner") -> PlannerSettings:
        """Settings from a mapping such as the YAML ``planner:`` block.

        Missing keys and ``null`` values take the defaults.

        Raises:
            ScenarioError: an unknown key (with a suggestion) or a bad value; ``field`` is
                ``"<field>.<key>"``; no file or line (the scenario loader adds them).
        """
        if mapping is None:
            return cls()
        values = _mapping(mapping, field, cls.keys())
        kwargs = {}
        for name, value in values.items():
            if value is None:
                continue
            try:
                kwargs[name] = _SETTING_CHECKS[name](value)
            except ValueError as error:
                raise _error(f"{field}.{name}", str(error)) from None
        return cls(**kwargs)


@dataclass(frozen=True, eq=False)
class Scenario:
    """A validated scenario.

    Attributes:
        name: the scenario's name (default: the file's stem).
        units: length unit of every number and mesh (recorded, never converted).
        robot: the moving part, oriented, in its own frame.
        obstacles: the fixed parts, posed in the world frame.
        start: ``(3,)`` start translation of the robot.
        goal: ``(3,)`` goal translation of the robot.
        orientation: ``(3, 3)`` the robot's fixed orientation (already applied to
            ``robot.mesh``; recorded for reports and visualisation).
        bounds: ``(lo, hi)``, two ``(3,)`` arrays: the box of allowed translations.
        settings: planner settings.
        path: resolved path of the file it was read from, or ``None``.
        notes: remarks made while loading (e.g. repairs of imported meshes).
    """

    name: str
    units: str
    robot: Robot
    obstacles: list[Body]
    start: np.ndarray
    goal: np.ndarray
    orientation: np.ndarray
    bounds: tuple[np.ndarray, np.ndarray]
    settings: PlannerSettings
    path: Path | None = None
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _frozen_array(self.start, (3,), "Scenario.start"))
        object.__setattr__(self, "goal", _frozen_array(self.goal, (3,), "Scenario.goal"))
        object.__setattr__(self, "orientation",
                           _frozen_array(self.orientation, (3, 3), "Scenario.orientation"))
        lo, hi = self.bounds
        object.__setattr__(self, "bounds", (_frozen_array(lo, (3,), "Scenario.bounds[0]"),
                                            _frozen_array(hi, (3,), "Scenario.bounds[1]")))
        object.__setattr__(self, "notes", tuple(self.notes))

    @property
    def start_pose(self) -> Pose:
        """The robot's start pose (its mesh file's frame in the world)."""
        return Pose(self.start, self.orientation)

    @property
    def goal_pose(self) -> Pose:
        """The robot's goal pose."""
        return Pose(self.goal, self.orientation)

    def robot_at(self, translation: Sequence[float] | np.ndarray) -> trimesh.Trimesh:
        """A copy of the robot mesh placed at the translation ``(3,)``."""
        mesh = self.robot.mesh.copy()
        mesh.apply_translation(np.asarray(translation, dtype=np.float64))
        return mesh

    def describe(self) -> dict[str, Any]:
        """A JSON-serialisable summary (for reports): name, units, file, robot, obstacles,
        start, goal, orientation as quaternion ``[w, x, y, z]``, bounds and settings."""
        matrix = np.eye(4)
        matrix[:3, :3] = self.orientation
        return {
            "name": self.name,
            "units": self.units,
            "path": None if self.path is None else str(self.path),
            "robot": _describe_part(self.robot),
            "obstacles": [_describe_part(b) for b in self.obstacles],
            "start": self.start.tolist(),
            "goal": self.goal.tolist(),
            "orientation_wxyz": tf.quaternion_from_matrix(matrix).tolist(),
            "bounds": {"min": self.bounds[0].tolist(), "max": self.bounds[1].tolist()},
            "settings": dataclasses.asdict(self.settings),
            "notes": list(self.notes),
        }


def _describe_part(part: Body | Robot) -> dict[str, Any]:
    return {"name": part.name, "source": part.source,
            "kind": "solid" if part.solid else "surface", "kind_reason": part.kind_reason}


# --------------------------------------------------------------------------------------
# Validation helpers: each raises ScenarioError(field=...) without file or line; the
# entry points add those (see _Document.locate).
# --------------------------------------------------------------------------------------


def _error(field: str, problem: str) -> ScenarioError:
    """``field`` ``""`` is the document itself (reported as "top level", field None)."""
    return ScenarioError(f"{field or 'top level'}: {problem}", field=field or None)


def _describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"string {value!r}"
    if isinstance(value, (int, float)):
        return f"number {value!r}"
    if isinstance(value, Mapping):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)}"
    return type(value).__name__


def _join(field: str, key: Any) -> str:
    return f"{field}.{key}" if field else str(key)


def _mapping(value: Any, field: str, allowed: Sequence[str],
             required: Sequence[str] = ()) -> dict[str, Any]:
    """Check that ``value`` is a mapping with only ``allowed`` keys and all ``required``."""
    if not isinstance(value, Mapping):
        what = f"a mapping with keys {', '.join(allowed)}"
        raise _error(field, f"expected {what}, got {_describe(value)}")
    for key in value:
        if not isinstance(key, str) or key not in allowed:
            close = difflib.get_close_matches(str(key), allowed, n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise _error(_join(field, key),
                         f"unknown key{hint} (allowed here: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            raise _error(_join(field, key), "missing required field")
    return dict(value)


def _real(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise _error(field, f"expected a number, got {_describe(value)}")
    number = float(value)
    if not math.isfinite(number):
        raise _error(field, f"expected a finite number, got {value!r}")
    return number


def _vector(value: Any, field: str, size: int = 3, form: str = "[x, y, z]") -> np.ndarray:
    if not isinstance(value, (list, tuple)):
        raise _error(field, f"expected a list of {size} numbers {form}, got {_describe(value)}")
    if len(value) != size:
        raise _error(field, f"expected {size} numbers {form}, got {len(value)}")
    return np.array([_real(v, f"{field}[{i}]") for i, v in enumerate(value)])


def _name(value: Any, field: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _error(field, f"expected a non-empty string, got {_describe(value)}")
    return value.strip()


def parse_orientation(value: Any, *, field: str = "orientation") -> np.ndarray:
    """An orientation spec as a ``(3, 3)`` rotation matrix.

    Accepted forms:

    - ``[w, x, y, z]`` or ``{quaternion: [w, x, y, z]}``: a unit quaternion, scalar first;
      normalised when its norm is within :data:`QUATERNION_NORM_TOLERANCE` of 1.
    - ``{rpy: [r, p, y]}``: degrees about the fixed x, y, z axes, applied in that order:
      ``R = Rz(y) @ Ry(p) @ Rx(r)``.
    - ``{axis: [x, y, z], angle_deg: a}``: ``a`` degrees about ``axis`` (right-hand rule).
    - ``null``: the identity.

    Raises:
        ScenarioError: with ``field`` (and no file/line) for anything else.
    """
    if value is None:
        return np.eye(3)
    if isinstance(value, (list, tuple)):
        if len(value) == 3:
            raise _error(field, "3 numbers are ambiguous: write a quaternion [w, x, y, z], "
                                "{rpy: [roll, pitch, yaw]} in degrees or "
                                "{axis: [x, y, z], angle_deg: a}")
        return _quaternion(value, field)
    if not isinstance(value, Mapping):
        raise _error(field, "expected a quaternion [w, x, y, z], {rpy: [r, p, y]} or "
                            f"{{axis: [x, y, z], angle_deg: a}}, got {_describe(value)}")
    spec = _mapping(value, field, ORIENTATION_KEYS)
    if "angle_deg" in spec and "axis" not in spec:
        raise _error(_join(field, "axis"), "missing required field (angle_deg needs an axis)")
    forms = [k for k in ("quaternion", "rpy", "axis") if k in spec]
    if not forms:
        raise _error(field, "empty orientation: give quaternion, rpy or axis + angle_deg")
    if len(forms) > 1:
        raise _error(field, f"give only one of {', '.join(forms)}")
    if "quaternion" in spec:
        return _quaternion(spec["quaternion"], _join(field, "quaternion"))
    if "rpy" in spec:
        roll, pitch, yaw = np.radians(_vector(spec["rpy"], _join(field, "rpy"),
                                              form="[roll, pitch, yaw] in degrees"))
        return tf.euler_matrix(roll, pitch, yaw, axes="sxyz")[:3, :3]
    axis = _vector(spec["axis"], _join(field, "axis"))
    if "angle_deg" not in spec:
        raise _error(_join(field, "angle_deg"), "missing required field (the angle about axis)")
    angle = _real(spec["angle_deg"], _join(field, "angle_deg"))
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        raise _error(_join(field, "axis"), "axis must not be the zero vector")
    return tf.rotation_matrix(math.radians(angle), axis / norm)[:3, :3]


def _quaternion(value: Any, field: str) -> np.ndarray:
    q = _vector(value, field, 4, "[w, x, y, z]")
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise _error(field, f"quaternion [w, x, y, z] must have unit length, its norm is "
                            f"{norm:.6g}")
    return tf.quaternion_matrix(q / norm)[:3, :3]


def _rotation_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of the rotation taking orientation ``a`` to ``b``, in degrees."""
    cosine = (np.trace(a.T @ b) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, cosine))))


# --------------------------------------------------------------------------------------
# YAML with line numbers
# --------------------------------------------------------------------------------------


class _Loader(yaml.SafeLoader):
    """SafeLoader that also reads ``1e3`` as a float (as YAML 1.2 does), not a string."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)

_FIELD_TAIL = re.compile(r"(?:\.[^.\[\]]+|\[\d+\])$")


class _Document:
    """Where the scenario came from: its label (file name) and the line of every field."""

    def __init__(self, label: str, lines: dict[str, int] | None = None) -> None:
        self.label = label
        self.lines = lines or {}

    def line_of(self, field: str | None) -> int | None:
        """Line of ``field``, or of its nearest ancestor that has one."""
        while field:
            if field in self.lines:
                return self.lines[field]
            shorter = _FIELD_TAIL.sub("", field)
            if shorter == field:
                break
            field = shorter
        return None

    def locate(self, error: ScenarioError) -> ScenarioError:
        """The same error with ``"<file>:<line>: "`` in front and ``line`` set."""
        line = error.line if error.line is not None else self.line_of(error.field)
        where = self.label if line is None else f"{self.label}:{line}"
        return ScenarioError(f"{where}: {error}", field=error.field, line=line)


def _record_lines(node: yaml.Node, field: str, lines: dict[str, int], document: _Document,
                  stack: set[int]) -> None:
    """Record the 1-based line of every mapping key and list item below ``node``."""
    if id(node) in stack:  # a recursive alias: nothing new below
        return
    stack.add(id(node))
    if isinstance(node, yaml.MappingNode):
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode) or key_node.value == "<<":
                continue
            key = key_node.value
            child = _join(field, key)
            line = key_node.start_mark.line + 1
            if key in seen:
                raise document.locate(ScenarioError(
                    f"{child}: duplicate key (first given on line {seen[key]})",
                    field=child, line=line))
            seen[key] = line
            lines[child] = line
            _record_lines(value_node, child, lines, document, stack)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            child = f"{field}[{index}]"
            lines[child] = item.start_mark.line + 1
            _record_lines(item, child, lines, document, stack)
    stack.discard(id(node))


def _load_yaml(text: str, document: _Document) -> Any:
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        document.lines[""] = node.start_mark.line + 1
        _record_lines(node, "", document.lines, document, set())
        return loader.construct_document(node)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        if (mark is not None and error.context_mark is not None
                and mark.index >= len(text.rstrip())):
            mark = error.context_mark  # "end of file": point at what was left open
        line = None if mark is None else mark.line + 1
        column = "" if mark is None else f" (column {mark.column + 1})"
        problem = error.problem or error.context or "invalid YAML"
        if error.problem and error.context and error.context_mark is not None:
            column = (f"{column[:-1]}; {error.context} that started on line "
                      f"{error.context_mark.line + 1})")
        where = document.label if line is None else f"{document.label}:{line}"
        raise ScenarioError(f"{where}: YAML syntax error: {problem}{column}",
                            line=line) from None
    except yaml.YAMLError as error:
        raise ScenarioError(f"{document.label}: YAML error: {error}") from None
    finally:
        loader.dispose()


# --------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------


@dataclass
class _ObjectSpec:
    field: str
    name: str | None
    mesh_path: Path | None
    primitive: dict[str, Any] | None
    scale: np.ndarray
    pose: Pose
    repair: bool = False


def _object_spec(value: Any, field: str, allowed: Sequence[str], base_dir: Path) -> _ObjectSpec:
    if isinstance(value, str):
        raise _error(field, f"expected a mapping such as {{mesh: {value}}} or "
                            f"{{box: [sx, sy, sz]}}, got {_describe(value)}")
    if field == "robot" and isinstance(value, Mapping):
        if "orientation" in value:
            raise _error("robot.orientation", "the robot's orientation is the start's: write "
                                              "start: {position: [x, y, z], orientation: ...}")
        if "position" in value:
            raise _error("robot.position", "the robot's position is given by start and goal; "
                                           "remove it")
    spec = _mapping(value, field, allowed)
    sources = [key for key in ("mesh", *PRIMITIVE_KINDS) if key in spec]
    if not sources:
        raise _error(_join(field, "mesh"),
                     "missing required field (or a primitive: box, sphere, cylinder)")
    if len(sources) > 1:
        raise _error(_join(field, sources[1]),
                     f"give only one of {', '.join(sources)} (a mesh file or one primitive)")
    name = None if spec.get("name") is None else _name(spec["name"], _join(field, "name"))
    mesh_path = None
    primitive = None
    if sources[0] == "mesh":
        mesh_path = _resolve_mesh(spec["mesh"], _join(field, "mesh"), base_dir)
    else:
        primitive = {sources[0]: spec[sources[0]]}
    scale = np.ones(3)
    if spec.get("scale") is not None:
        scale_field = _join(field, "scale")
        raw = spec["scale"]
        if isinstance(raw, (list, tuple)):
            scale = _vector(raw, scale_field, form="[sx, sy, sz]")
        else:
            scale = np.full(3, _real(raw, scale_field))
        if np.any(scale <= 0):
            raise _error(scale_field, f"scale factors must be > 0, got {raw!r}")
    position = np.zeros(3)
    if spec.get("position") is not None:
        position = _vector(spec["position"], _join(field, "position"))
    rotation = parse_orientation(spec.get("orientation"), field=_join(field, "orientation"))
    repair = False
    if spec.get("repair") is not None:
        if not isinstance(spec["repair"], bool):
            raise _error(_join(field, "repair"),
                         f"expected true or false, got {_describe(spec['repair'])}")
        if mesh_path is None:
            raise _error(_join(field, "repair"), "only mesh files can be repaired")
        repair = spec["repair"]
    return _ObjectSpec(field, name, mesh_path, primitive, scale, Pose(position, rotation),
                       repair)


def _resolve_mesh(value: Any, field: str, base_dir: Path) -> Path:
    if not isinstance(value, str) or not value.strip():
        raise _error(field, f"expected a file path (relative to the scenario file), got "
                            f"{_describe(value)}")
    path = Path(os.path.expanduser(value.strip()))
    if not path.is_absolute():
        path = base_dir / path
    if path.is_file():
        return path
    folder = path.parent.resolve()
    hint = ""
    if folder.is_dir():
        # only mesh files are worth suggesting for a mesh
        names = sorted(p.name for p in folder.iterdir()
                       if p.is_file() and p.suffix.lower() in MESH_SUFFIXES)
        close = difflib.get_close_matches(path.name, names, n=1, cutoff=0.6)
        if close:
            hint = f"; did you mean '{close[0]}'?"
    elif not path.exists():
        hint = "; that folder does not exist either"
    if path.exists():
        raise _error(field, f"'{value}' is not a file (looked in {folder})")
    raise _error(field, f"file '{value}' not found (looked in {folder}){hint}")


_MeshCache = dict[tuple[Path, bool], tuple[trimesh.Trimesh, str]]


def _build_mesh(spec: _ObjectSpec, cache: _MeshCache) -> tuple[trimesh.Trimesh, str]:
    """The object's mesh in its own frame with the scale applied, and its source."""
    if spec.mesh_path is not None:
        key = (spec.mesh_path.resolve(), spec.repair)
        if key not in cache:
            cache[key] = _load_solid(key[0], spec)
        mesh, source = cache[key]
        mesh = mesh.copy()
    else:
        assert spec.primitive is not None
        mesh = make_primitive(spec.primitive, field=spec.field)
        ((kind, value),) = spec.primitive.items()
        source = f"{kind} {value}"
    if not np.allclose(spec.scale, 1.0):
        mesh.apply_scale(spec.scale)  # positive factors: winding is kept
        source += f" scaled {spec.scale.tolist()}"
    return mesh, source


def _load_solid(path: Path, spec: _ObjectSpec) -> tuple[trimesh.Trimesh, str]:
    """Read a mesh file and check (or, with ``repair: true``, repair) that it is a solid."""
    from .meshes import load_mesh, repair_mesh, validate_solid  # noqa: PLC0415 (lazy)

    field = _join(spec.field, "mesh")
    label = spec.name or path.stem
    try:
        mesh = load_mesh(path, name=label)
        if spec.repair:
            mesh, report = repair_mesh(mesh, name=label)
            done = {k: v for k, v in report.items()
                    if k.startswith(("removed_", "merged_", "fixed_", "filled_", "flipped_"))
                    and k != "removed_faces" and v}
            source = f"{path} (repaired: {done or 'nothing to do'})"
        else:
            mesh = validate_solid(mesh, name=label)
            source = str(path)
    except (ValueError, OSError) as error:  # InvalidMeshError is a ValueError
        hint = ""
        if not spec.repair and "repair_mesh" in str(error):
            hint = " (in a scenario: add 'repair: true' to this object)"
        raise _error(field, f"{error}{hint}") from None
    return mesh, source


def _bounds_of(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return points.min(axis=0), points.max(axis=0)


def default_bounds(
    robot: trimesh.Trimesh,
    obstacles: Sequence[trimesh.Trimesh],
    start: Sequence[float] | np.ndarray,
    goal: Sequence[float] | np.ndarray,
    *,
    margin: float = DEFAULT_BOUNDS_MARGIN,
) -> tuple[np.ndarray, np.ndarray]:
    """The translation bounds used when a scenario gives none.

    The smallest box holding: ``start`` and ``goal``; the robot's box at ``start`` and
    at ``goal`` (``robot.bounds + t``); every obstacle's box; and every obstacle's
    C-obstacle box ``[O.min - R.max, O.max - R.min]`` (every translation at which the
    robot can touch that obstacle). It then grows on every side by
    ``margin * (its largest side)``, so that the planner has free space to go around
    every C-obstacle.

    Args:
        robot: the robot mesh in its own frame (oriented), as in ``Scenario.robot.mesh``.
        obstacles: obstacle meshes in the world frame.
        start, goal: ``(3,)`` translations.
        margin: relative growth, ``>= 0``.

    Returns:
        ``(lo, hi)``, two ``(3,)`` arrays (``lo < hi`` when ``margin > 0``).
    """
    start = np.asarray(start, dtype=np.float64)
    goal = np.asarray(goal, dtype=np.float64)
    r_lo, r_hi = np.asarray(robot.bounds, dtype=np.float64)
    corners = [start, goal, r_lo + start, r_hi + start, r_lo + goal, r_hi + goal]
    for mesh in obstacles:
        o_lo, o_hi = np.asarray(mesh.bounds, dtype=np.float64)
        corners += [o_lo, o_hi, o_lo - r_hi, o_hi - r_lo]
    lo, hi = _bounds_of(np.array(corners))
    size = float(np.max(hi - lo))
    if size <= 0:  # everything is one point (an empty robot): any positive size will do
        size = 1.0
    pad = margin * size
    return lo - pad, hi + pad


# --------------------------------------------------------------------------------------
# Entry points
# --------------------------------------------------------------------------------------


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario file.

    Args:
        path: a scenario ``.yaml``/``.yml`` file; mesh paths inside it are relative to
            its folder. An OMPL.app problem ``.cfg`` is read by
            :func:`planner.omplapp.load_omplapp`.

    Returns:
        The validated :class:`Scenario` (``name`` defaults to the file's stem).

    Raises:
        ScenarioError: the file cannot be read or is invalid; the message is one line,
            ``"<path>:<line>: <field>: <problem>"``.
    """
    path = Path(path)
    label = str(path)
    if path.suffix.lower() == ".cfg":
        from .omplapp import load_omplapp  # noqa: PLC0415 (omplapp imports this module)

        return load_omplapp(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(f"{label}: scenario file not found "
                            f"(looked in {path.parent.resolve()})") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ScenarioError(f"{label}: cannot read the scenario file: {error}") from None
    return _parse(text, _Document(label), path.parent, path.resolve(), path.stem)


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
        ScenarioError: as :func:`load_scenario`.
    """
    if isinstance(source, os.PathLike):
        raise TypeError("parse_scenario takes YAML text or a mapping; use load_scenario "
                        "for a file")
    document = _Document(filename or "<scenario>")
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    return _parse(source, document, base, None, "scenario")


def _parse(source: str | Mapping[str, Any], document: _Document, base_dir: Path,
           path: Path | None, default_name: str) -> Scenario:
    data = _load_yaml(source, document) if isinstance(source, str) else source
    try:
        return _build(data, base_dir, path, default_name)
    except ScenarioError as error:
        raise document.locate(error) from None


def _build(data: Any, base_dir: Path, path: Path | None, default_name: str) -> Scenario:
    if data is None:
        raise _error("", "the scenario is empty; it needs at least robot, start and goal")
    top = _mapping(data, "", TOP_LEVEL_KEYS, ("robot", "start", "goal"))

    name = default_name if top.get("name") is None else _name(top["name"], "name")
    units = "unitless" if top.get("units") is None else _name(top["units"], "units")
    settings = PlannerSettings.from_mapping(top.get("planner"), field="planner")

    # Start, goal and the fixed orientation.
    start, start_rotation = _endpoint(top["start"], "start")
    goal, goal_rotation = _endpoint(top["goal"], "goal")
    if start_rotation is not None and goal_rotation is not None:
        angle = _rotation_angle_deg(start_rotation, goal_rotation)
        if angle > ORIENTATION_TOLERANCE_DEG:
            raise _error("goal.orientation",
                         f"differs from start.orientation by {angle:.4g} degrees; the part "
                         "only translates, so start and goal orientations must be equal")
    orientation = next((r for r in (start_rotation, goal_rotation) if r is not None),
                       np.eye(3))

    explicit_bounds = None
    if top.get("bounds") is not None:
        spec = _mapping(top["bounds"], "bounds", BOUNDS_KEYS, BOUNDS_KEYS)
        lo = _vector(spec["min"], "bounds.min")
        hi = _vector(spec["max"], "bounds.max")
        bad = [axis for axis, a, b in zip("xyz", lo, hi) if a >= b]
        if bad:
            raise _error("bounds.max", f"max must be greater than min on every axis; "
                                       f"not on {', '.join(bad)} (min {lo.tolist()}, "
                                       f"max {hi.tolist()})")
        explicit_bounds = (lo, hi)

    # Every object's spec (cheap checks, file existence) before loading any mesh.
    robot_spec = _object_spec(top["robot"], "robot", ROBOT_KEYS, base_dir)
    raw_obstacles = top.get("obstacles")
    if raw_obstacles is None:
        raw_obstacles = []
    if not isinstance(raw_obstacles, (list, tuple)):
        raise _error("obstacles", f"expected a list of objects, got {_describe(raw_obstacles)}")
    obstacle_specs = [_object_spec(value, f"obstacles[{i}]", OBSTACLE_KEYS, base_dir)
                      for i, value in enumerate(raw_obstacles)]

    names = _assign_names([robot_spec, *obstacle_specs])
    cache: _MeshCache = {}

    robot_mesh, robot_source = _build_mesh(robot_spec, cache)
    robot_mesh.apply_transform(_rotation4(orientation))
    robot = Robot(names[0], robot_mesh, robot_source)

    obstacles = []
    for spec, body_name in zip(obstacle_specs, names[1:]):
        mesh, source = _build_mesh(spec, cache)
        mesh.apply_transform(spec.pose.matrix)
        obstacles.append(Body(body_name, mesh, source))

    if explicit_bounds is None:
        bounds = default_bounds(robot.mesh, [b.mesh for b in obstacles], start, goal)
    else:
        bounds = explicit_bounds
        for field, point in (("start", start), ("goal", goal)):
            outside = [f"{axis} = {v:g} not in [{a:g}, {b:g}]"
                       for axis, v, a, b in zip("xyz", point, *bounds) if not a <= v <= b]
            if outside:
                target = f"{field}.position" if isinstance(top[field], Mapping) else field
                raise _error(target, f"{point.tolist()} is outside bounds ({'; '.join(outside)})")

    return Scenario(name=name, units=units, robot=robot, obstacles=obstacles, start=start,
                    goal=goal, orientation=orientation, bounds=bounds, settings=settings,
                    path=path)


def _assign_names(specs: Sequence[_ObjectSpec]) -> list[str]:
    """Unique names: explicit ones must not repeat; a default is the mesh file's stem or
    the primitive's kind (``"robot"`` for a primitive robot), made unique with the
    object's index (``block_3``)."""
    taken: dict[str, str] = {}
    for spec in specs:
        if spec.name is not None:
            if spec.name in taken:
                raise _error(_join(spec.field, "name"),
                             f"name '{spec.name}' is already used by {taken[spec.name]}")
            taken[spec.name] = spec.field
    names = []
    for spec in specs:
        if spec.name is not None:
            names.append(spec.name)
            continue
        if spec.mesh_path is not None:
            base = spec.mesh_path.stem
        elif spec.field == "robot":
            base = "robot"
        else:
            base = next(iter(spec.primitive or {"obstacle": None}))
        index = spec.field.rsplit("[", 1)[-1].rstrip("]") if "[" in spec.field else ""
        candidate, counter = base, 1
        while candidate in taken:
            candidate = f"{base}_{index}" if counter == 1 and index else f"{base}_{counter}"
            counter += 1
        taken[candidate] = spec.field
        names.append(candidate)
    return names


def _rotation4(rotation: np.ndarray) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    return matrix


def _endpoint(value: Any, field: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``[x, y, z]`` or ``{position: [x, y, z], orientation: ...}``."""
    if isinstance(value, Mapping):
        spec = _mapping(value, field, ENDPOINT_KEYS, ("position",))
        position = _vector(spec["position"], _join(field, "position"))
        if spec.get("orientation") is None:
            return position, None
        return position, parse_orientation(spec["orientation"],
                                           field=_join(field, "orientation"))
    if isinstance(value, (list, tuple)):
        return _vector(value, field), None
    raise _error(field, f"expected [x, y, z] or {{position: [x, y, z], orientation: ...}}, "
                        f"got {_describe(value)}")
