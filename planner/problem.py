"""The problems minkplan solves, as typed objects that know nothing of files.

- :class:`Part` (also :data:`Body`, :data:`Robot`): a mesh with its name, source and kind
  (solid or surface).
- :class:`Scenario`: a translational planning problem (robot, obstacles, start, goal,
  bounds, :class:`PlannerSettings`).
- :class:`Assembly`: parts at their assembled pose, for disassembly planning.
- :class:`Pose`, :func:`default_bounds`.

The readers in :mod:`planner.io` build these from files; code can build them directly.

Conventions:

- The robot's orientation is fixed for the whole motion. At the configuration ``t`` (a
  translation, ``(3,)``) the robot occupies ``Scenario.robot.mesh + t``: the robot mesh
  is stored in its own frame with the orientation already applied. ``start`` and
  ``goal`` are such translations, i.e. positions of the robot mesh's origin.
- Lengths are in the problem's ``units`` (recorded, never converted).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import trimesh
from trimesh import transformations as tf

from .errors import InvalidParameterError
from .meshes.solids import SOLID_REASON
from .sources import check_exact
from .tolerances import tol
from .values import check_bool, check_optional, check_real, check_seed

__all__ = [
    "DEFAULT_BOUNDS_MARGIN",
    "DEFAULT_CONTACT_REL",
    "Assembly",
    "Body",
    "Part",
    "PlannerSettings",
    "Pose",
    "Robot",
    "SETTING_CHECKS",
    "Scenario",
    "default_bounds",
    "outside_bounds",
]


DEFAULT_BOUNDS_MARGIN = 0.1
"""Default bounds grow on every side by this fraction of their largest side."""


def outside_bounds(point: Any, bounds: tuple[Any, Any]) -> list[str]:
    """Per axis on which ``point`` lies outside the box ``bounds`` (``(lo, hi)``), what
    that is (``"z = 60 not in [0, 50]"``); empty when it lies inside."""
    return [f"{axis} = {v:g} not in [{a:g}, {b:g}]"
            for axis, v, a, b in zip("xyz", point, *bounds, strict=True) if not a <= v <= b]


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
class Part:
    """A rigid part: an obstacle, the robot, or a part of an assembly.

    Attributes:
        name: unique name within its problem (used in reports).
        mesh: triangle mesh; an obstacle's is posed in the world frame, the robot's is in
            its own frame with its fixed orientation applied (at translation ``t`` it
            occupies ``mesh + t``). A solid (closed, winding number never negative)
            unless ``solid`` is false.
        source: where it came from: a resolved file path, ``"box [1, 2, 3]"``, ...
        solid: ``True``: a solid (a part inside it collides); ``False``: a surface, any
            set of triangles, which collides only where triangles meet (FCL's and
            OMPL.app's meaning).
        kind_reason: why it is a solid or a surface (for reports).
        checked: the mesh has been through :func:`planner.meshes.validate_solid` (the
            readers do it once); otherwise whoever needs a checked solid does.
        repairs: what was changed to make the mesh a solid (``{"t_junctions_split": 36}``,
            repair counts); empty when nothing was.
        escape_hints: unit directions known to free the part from a part it overlaps
            where it stands (the penetration depth's, of an accepted interference fit):
            FCL's tolerance checks with it as the moving part try them before the contact
            normals and the axes (:class:`planner.validation.FclChecker`).
    """

    name: str
    mesh: trimesh.Trimesh
    source: str
    solid: bool = True
    kind_reason: str = SOLID_REASON
    checked: bool = False
    repairs: dict[str, Any] = dataclasses.field(default_factory=dict)
    escape_hints: tuple[tuple[float, float, float], ...] = ()

    def describe(self) -> dict[str, Any]:
        """Name, source, kind (``"solid"`` / ``"surface"``), why, and what was repaired,
        for reports."""
        return {"name": self.name, "source": self.source,
                "kind": "solid" if self.solid else "surface", "kind_reason": self.kind_reason,
                "repairs": self.repairs}


Body = Part
"""An obstacle (a :class:`Part` posed in the world)."""

Robot = Part
"""The moving part (a :class:`Part` in its own frame, oriented)."""


SETTING_CHECKS = {
    "resolution": lambda v: check_optional(v, 0.0, strict=True),
    "time_limit": lambda v: check_real(v, 0.0, strict=True),
    "seed": check_seed,
    "contact_tolerance": lambda v: check_optional(v, 0.0, strict=False),
    "decomposition_threshold": lambda v: check_real(v, 0.01, strict=False, high=1.0),
    "exact": check_exact,
    "clearance": lambda v: check_real(v, 0.0, strict=False),
    "simplify": check_bool,
}
"""One check per planner setting (``ValueError`` with the problem): the YAML keys."""


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
        for name, check in SETTING_CHECKS.items():
            try:
                object.__setattr__(self, name, check(getattr(self, name)))
            except ValueError as error:
                raise InvalidParameterError(f"PlannerSettings.{name}: {error}") from None

    @classmethod
    def keys(cls) -> tuple[str, ...]:
        """The accepted setting names, in documentation order."""
        return tuple(f.name for f in dataclasses.fields(cls))


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
            "robot": self.robot.describe(),
            "obstacles": [b.describe() for b in self.obstacles],
            "start": self.start.tolist(),
            "goal": self.goal.tolist(),
            "orientation_wxyz": tf.quaternion_from_matrix(matrix).tolist(),
            "bounds": {"min": self.bounds[0].tolist(), "max": self.bounds[1].tolist()},
            "settings": dataclasses.asdict(self.settings),
            "notes": list(self.notes),
        }


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
    points = np.array(corners)
    lo, hi = points.min(axis=0), points.max(axis=0)
    size = float(np.max(hi - lo))
    if size <= 0:  # everything is one point (an empty robot): any positive size will do
        size = 1.0
    pad = margin * size
    return lo - pad, hi + pad



DEFAULT_CONTACT_REL = 1e-4
"""Default contact tolerance of an assembly, as a fraction of its bounding-box diagonal."""


@dataclass(frozen=True, eq=False)
class Assembly:
    """A validated assembly.

    Attributes:
        name, units: as in a scenario.
        parts: every part posed in the world at its assembled pose, file order.
        base: name of the fixed part (never removed), or ``None``.
        contact_tolerance: ``delta`` in units (given or default).
        settings: planner settings for the full planning steps (``contact_tolerance``
            set to :attr:`tolerance`).
        path: the file it came from, or ``None``.
        interference: overlap the user accepts in the assembled pose (export
            imprecision, interference fits), in units; ``0`` unless asked for.
        overlaps: the pairs of parts that overlap in the assembled pose by more than the
            contact tolerance but within :attr:`tolerance` (``part``, ``other``,
            ``penetration_depth``), found only when ``interference > 0``.
    """

    name: str
    units: str
    parts: list[Part]
    base: str | None
    contact_tolerance: float
    settings: PlannerSettings
    path: Path | None = None
    interference: float = 0.0
    overlaps: tuple[dict, ...] = ()

    @property
    def tolerance(self) -> float:
        """The penetration allowed everywhere (straight-line checks, the planner, the
        validation): the contact tolerance plus the interference tolerance."""
        return self.contact_tolerance + self.interference

    @property
    def diagonal(self) -> float:
        bounds = np.array([p.mesh.bounds for p in self.parts])
        return float(np.linalg.norm(bounds[:, 1].max(axis=0) - bounds[:, 0].min(axis=0)))
