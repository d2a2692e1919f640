"""Assembly sequencing by disassembly: which part can leave, and along which path.

Entry points:

- :func:`load_assembly` / :func:`parse_assembly` -- read an assembly YAML (see
  ``docs/assembly.md``) into an :class:`Assembly`.
- :func:`plan_assembly` -- the disassembly search; returns an :class:`AssemblyResult`
  (``status`` ``"sequence"`` or ``"interlocked"``, the assembly order with every part's
  insertion path, ``sequence_json()``, ``report_json()``, ``exit_code``).
- :func:`benchmark_removals` -- per-step planning times of several planners on a
  result's removal problems (``tests/benchmarks/bench_assembly.py``).

Search: while movable parts remain, find one that can translate from its assembled pose
to outside the remaining parts' bounding box (its own included) grown by a margin, with
the other remaining parts as obstacles. Cheap first: straight removals along ``±x, ±y,
±z`` (shortest exit first), then along the escape directions of FCL's contact normals at
the assembled pose. Whether part ``j`` alone blocks such a line for part ``i`` depends on
the pair only, so it is decided once per (part, obstacle, direction) by a
:class:`PairCache` -- from the pair's C-obstacle primitives ``O_j ⊕ (−R_i)``, built once
per pair and reused in every step, or by FCL on the two parts when the line only slides
along touching faces -- and a line no present part blocks is then checked with all of
them by :meth:`FclChecker.check_path`. Then, for each part in turn, the octree planner
(:func:`planner.planning.plan`) on a :class:`~planner.scenario.Scenario` whose robot is
the part (start ``0``) and whose goal lies outside that box on one of its six sides, the
most open first (the shallowest block of the straight line); the region outside the box
is connected, so the first path found, or a certificate walling off the start, settles
it. The reverse of the removal order is an assembly order; each insertion path is the
removal path reversed. When no part can leave, the stuck parts are shrunk to an
irreducible interlocked set by greedy deletion (each part left out in turn, the search
re-run on the rest), which is what the result reports.

Contact: assembled parts touch face to face. One contact tolerance ``delta`` (the file's
``contact_tolerance``, else ``DEFAULT_CONTACT_REL`` times the assembly's diagonal) is
used by the straight-line checks, the planner (``planner.contact_tolerance``) and the
final FCL validation of every reported path, and it is written in the output.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ._minkowski_core import Primitives
from .decompose import decompose
from .errors import InvalidParameterError, MinkplanError, ScenarioError
from .planning.outcome import FOUND, NO_PATH, jsonable
from .scenario import (
    OBSTACLE_KEYS,
    Body,
    PlannerSettings,
    Robot,
    Scenario,
    _assign_names,
    _build_mesh,
    _Document,
    _error,
    _load_yaml,
    _mapping,
    _name,
    _object_spec,
    _real,
)
from .validation import FclChecker

__all__ = [
    "DEFAULT_CONTACT_REL",
    "ESCAPE_MARGIN_REL",
    "Assembly",
    "AssemblyResult",
    "AssemblyStep",
    "PairCache",
    "RayVerdict",
    "assemble_command",
    "benchmark_removals",
    "load_assembly",
    "parse_assembly",
    "plan_assembly",
    "removal_problems",
    "removal_scenario",
    "scene_for_assembly",
]

log = logging.getLogger(__name__)

DEFAULT_CONTACT_REL = 1e-4
"""Default contact tolerance as a fraction of the assembly's bounding-box diagonal."""

ESCAPE_MARGIN_REL = 0.1
"""A part has left when its box is outside the remaining parts' box grown by this
fraction of the assembly's diagonal."""

TOP_LEVEL_KEYS = ("name", "units", "parts", "base", "contact_tolerance", "planner")
SEQUENCE = "sequence"
INTERLOCKED = "interlocked"
DIRECTIONS = {name: vec for name, vec in zip(
    ("+z", "-z", "+x", "-x", "+y", "-y"),
    np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], float))}


@dataclass(frozen=True, eq=False)
class Assembly:
    """A validated assembly.

    Attributes:
        name, units: as in a scenario.
        parts: every part posed in the world at its assembled pose (``Body``), file order.
        base: name of the fixed part (never removed), or ``None``.
        contact_tolerance: ``delta`` in units (given or default).
        settings: planner settings for the full planning steps (``contact_tolerance``
            set to ``delta``).
        path: the file it came from, or ``None``.
    """

    name: str
    units: str
    parts: list[Body]
    base: str | None
    contact_tolerance: float
    settings: PlannerSettings
    path: Path | None = None

    @property
    def diagonal(self) -> float:
        lo, hi = _box([p.mesh for p in self.parts])
        return float(np.linalg.norm(hi - lo))


@dataclass
class AssemblyStep:
    """One part's removal (in removal order) and hence insertion (reversed).

    Attributes:
        part: the part's name.
        method: ``"straight"`` (one segment along ``direction``) or ``"planned"``.
        direction: ``"+z"`` etc. for straight removals, the goal's side when planned.
        removal: ``(n, 3)`` translations from ``0`` (assembled) to outside.
        obstacles: the parts present while it moves.
        seconds: time spent finding it.
        validation: FCL's check of the removal path at the contact tolerance.
    """

    part: str
    method: str
    direction: str
    removal: np.ndarray
    obstacles: list[str]
    seconds: float
    validation: dict[str, Any]

    @property
    def insertion(self) -> np.ndarray:
        """Translations from outside to ``0`` (the removal reversed)."""
        return self.removal[::-1].copy()


@dataclass
class AssemblyResult:
    """Outcome of :func:`plan_assembly`.

    Attributes:
        status: ``"sequence"`` or ``"interlocked"``.
        removal: steps in removal order (for an interlocked result: those that worked).
        interlocked: an irreducible interlocked set (empty when a sequence exists): parts
            that cannot be taken apart, though leaving out any one of them makes that
            possible. It may include the base when the base takes part in the lock.
        base: the fixed part, or ``None``.
        contact_tolerance: ``delta`` used everywhere.
        seconds: total time.
        attempts: per stuck part, why it could not leave with the other remaining parts
            present (planner status, ``proved``, ``obstacles``, the goal ``sides`` tried).
        stuck: every movable part that could not leave when the search stopped (a
            superset of the movable parts of ``interlocked``).
        core_attempts: the same as ``attempts`` with only the ``interlocked`` set present.
        reuse: what the search computed and reused (see :class:`PairCache`).
    """

    assembly: Assembly
    status: str
    removal: list[AssemblyStep]
    interlocked: list[str]
    base: str | None
    contact_tolerance: float
    seconds: float
    attempts: dict[str, dict[str, Any]] = field(default_factory=dict)
    stuck: list[str] = field(default_factory=list)
    core_attempts: dict[str, dict[str, Any]] = field(default_factory=dict)
    reuse: dict[str, Any] = field(default_factory=dict)

    @property
    def found(self) -> bool:
        return self.status == SEQUENCE

    @property
    def exit_code(self) -> int:
        return 0 if self.found else 1

    @property
    def order(self) -> list[str]:
        """Assembly order: the base (if any) or the last part left, then the rest."""
        if not self.found:
            return []
        removed = [s.part for s in self.removal]
        first = [p.name for p in self.assembly.parts if p.name not in removed]
        return first + removed[::-1]

    @property
    def proved(self) -> bool:
        """For an interlocked result: with only the ``interlocked`` parts present, no
        movable one of them can leave, each proved by an octree certificate; ``False``
        when some planner only gave up."""
        movable = [n for n in self.interlocked if n != self.base]
        return not self.found and bool(movable) and all(
            self.core_attempts.get(n, {}).get("proved", False) for n in movable)

    @property
    def message(self) -> str:
        if self.found:
            return f"assembly order: {' -> '.join(self.order)}"
        how = "proved" if self.proved else "not proved: some planner gave up"
        text = f"no sequence: interlocked parts {', '.join(self.interlocked)} ({how})"
        others = [n for n in self.stuck if n not in self.interlocked]
        if others:
            text += f"; also stuck: {', '.join(others)}"
        return text

    def sequence_json(self) -> dict[str, Any]:
        """``sequence.json``: parts in assembly order, each with its insertion path."""
        steps = {s.part: s for s in self.removal}
        parts = []
        for name in self.order:
            step = steps.get(name)
            if step is None:
                parts.append({"part": name, "fixed": True, "insertion": [[0.0, 0.0, 0.0]]})
                continue
            parts.append({"part": name, "fixed": False, "method": step.method,
                          "direction": step.direction, "insertion": step.insertion,
                          "validation": step.validation})
        return jsonable({
            "name": self.assembly.name, "units": self.assembly.units, "status": self.status,
            "contact_tolerance": self.contact_tolerance, "base": self.base,
            "parts": parts, "interlocked": self.interlocked, "stuck": self.stuck,
            "proved": self.proved, "message": self.message,
        })

    def report_json(self) -> dict[str, Any]:
        """``report.json``: removal steps with timings, obstacles and attempts."""
        return jsonable({
            "name": self.assembly.name, "status": self.status, "message": self.message,
            "contact_tolerance": self.contact_tolerance, "seconds": self.seconds,
            "removal": [{"part": s.part, "method": s.method, "direction": s.direction,
                         "waypoints": s.removal, "obstacles": s.obstacles,
                         "seconds": s.seconds, "validation": s.validation}
                        for s in self.removal],
            "interlocked": self.interlocked, "stuck": self.stuck,
            "attempts": self.attempts, "interlocked_attempts": self.core_attempts,
            "reuse": self.reuse, "settings": dataclasses.asdict(self.assembly.settings),
        })


# --------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------


def load_assembly(path: str | os.PathLike[str]) -> Assembly:
    """Read and validate an assembly YAML file (mesh paths relative to its folder).

    Raises:
        ScenarioError: one line, ``"<file>:<line>: <field>: <problem>"``.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ScenarioError(f"{path}: assembly file not found "
                            f"(looked in {path.parent.resolve()})") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ScenarioError(f"{path}: cannot read the assembly file: {error}") from None
    return _parse(text, _Document(str(path)), path.parent, path.resolve(), path.stem)


def parse_assembly(source: str | Mapping[str, Any], base_dir: str | os.PathLike[str] | None = None,
                   *, filename: str | None = None) -> Assembly:
    """An :class:`Assembly` from YAML text or a mapping (see :func:`load_assembly`)."""
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    return _parse(source, _Document(filename or "<assembly>"), base, None, "assembly")


def _parse(source, document: _Document, base_dir: Path, path: Path | None,
           default_name: str) -> Assembly:
    data = _load_yaml(source, document) if isinstance(source, str) else source
    try:
        return _build(data, base_dir, path, default_name)
    except ScenarioError as error:
        raise document.locate(error) from None


def _build(data: Any, base_dir: Path, path: Path | None, default_name: str) -> Assembly:
    if data is None:
        raise _error("", "the assembly is empty; it needs a list of parts")
    if isinstance(data, Mapping) and "robot" in data and "parts" not in data:
        raise _error("robot", "this looks like a planning scenario (minkplan plan); an "
                              "assembly lists its parts under 'parts:'")
    top = _mapping(data, "", TOP_LEVEL_KEYS, ("parts",))
    name = default_name if top.get("name") is None else _name(top["name"], "name")
    units = "unitless" if top.get("units") is None else _name(top["units"], "units")
    settings = PlannerSettings.from_mapping(top.get("planner"), field="planner")
    raw = top["parts"]
    if not isinstance(raw, (list, tuple)) or len(raw) < 1:
        raise _error("parts", "expected a non-empty list of parts")
    specs = [_object_spec(value, f"parts[{i}]", OBSTACLE_KEYS, base_dir)
             for i, value in enumerate(raw)]
    names = _assign_names(specs)
    base = None
    if top.get("base") is not None:
        base = _name(top["base"], "base")
        if base not in names:
            raise _error("base", f"'{base}' is not a part (parts: {', '.join(names)})")
    delta = None
    if top.get("contact_tolerance") is not None:
        delta = _real(top["contact_tolerance"], "contact_tolerance")
        if delta < 0:
            raise _error("contact_tolerance", f"must be >= 0, got {delta:g}")
    if settings.contact_tolerance is not None:
        if delta is not None and not math.isclose(delta, settings.contact_tolerance):
            raise _error("planner.contact_tolerance",
                         f"{settings.contact_tolerance:g} differs from contact_tolerance "
                         f"{delta:g}; give it once")
        delta = settings.contact_tolerance
    cache: dict = {}
    parts = []
    for spec, part_name in zip(specs, names):
        mesh, source = _build_mesh(spec, cache)
        mesh.apply_transform(spec.pose.matrix)
        parts.append(Body(part_name, mesh, source))
    if delta is None:
        lo, hi = _box([p.mesh for p in parts])
        delta = DEFAULT_CONTACT_REL * float(np.linalg.norm(hi - lo))
    settings = dataclasses.replace(settings, contact_tolerance=delta)
    # The assembled pose must be valid: no part overlaps another beyond the tolerance.
    for i, part in enumerate(parts):
        others = [p for p in parts[i + 1:]]
        if not others:
            continue
        checker = FclChecker(part.mesh, [p.mesh for p in others], contact_tolerance=delta,
                             names=[p.name for p in others])
        if not checker.is_valid(np.zeros(3)):
            hit = checker.colliding_obstacle(np.zeros(3))
            other = hit[0] if hit else "another part"
            raise _error(f"parts[{i}]", f"part '{part.name}' collides with '{other}' in "
                                        f"the assembled pose (overlap beyond contact "
                                        f"tolerance {delta:g}, or clamped between faces "
                                        f"on opposite sides)")
    return Assembly(name=name, units=units, parts=parts, base=base, contact_tolerance=delta,
                    settings=settings, path=path)


# --------------------------------------------------------------------------------------
# Search
# --------------------------------------------------------------------------------------


def _box(meshes: list[trimesh.Trimesh]) -> tuple[np.ndarray, np.ndarray]:
    bounds = np.array([m.bounds for m in meshes])
    return bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)


def _exit_box(part: Body, others: list[Body], margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Translations at which the part's box meets the box of the remaining parts (the
    part itself included, at its assembled pose) grown by ``margin``: outside this box,
    the part has left. It always contains ``0``."""
    o_lo, o_hi = _box([p.mesh for p in [part, *others]])
    p_lo, p_hi = part.mesh.bounds
    return o_lo - margin - p_hi, o_hi + margin - p_lo


def _exit_point(direction: np.ndarray, box: tuple[np.ndarray, np.ndarray],
                margin: float) -> np.ndarray:
    """Where the ray from ``0`` along the unit ``direction`` leaves the exit box, plus
    half the margin."""
    lo, hi = box
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(direction > 0, hi / direction,
                         np.where(direction < 0, lo / direction, np.inf))
    return direction * (float(np.min(reach)) + margin / 2)


def _direction_vector(direction: str | np.ndarray) -> tuple[str, np.ndarray]:
    """``(name, unit vector)`` of an axis name (``"+z"``) or a vector."""
    if isinstance(direction, str):
        if direction not in DIRECTIONS:
            raise InvalidParameterError(f"direction {direction!r}: use one of "
                                        f"{', '.join(DIRECTIONS)} or a 3-vector")
        return direction, DIRECTIONS[direction]
    vec = np.asarray(direction, dtype=np.float64).reshape(-1)
    norm = float(np.linalg.norm(vec)) if vec.shape == (3,) else 0.0
    if not (norm > 0 and math.isfinite(norm)):
        raise InvalidParameterError(f"direction {direction!r}: expected a non-zero finite "
                                    f"3-vector")
    vec = vec / norm
    for name, axis in DIRECTIONS.items():
        if float(np.dot(vec, axis)) > 1.0 - 1e-12:
            return name, axis
    return _vector_name(vec), vec


def _vector_name(vec: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in vec) + "]"


def _validate(part: Body, others: list[Body], path: np.ndarray, delta: float) -> dict:
    checker = FclChecker(part.mesh, [p.mesh for p in others], contact_tolerance=delta,
                         names=[p.name for p in others])
    check = checker.check_path(path)
    return {"valid": bool(check.valid), "min_clearance": check.min_clearance,
            "n_checks": check.n_checks, "contact_tolerance": delta,
            "obstacle": check.obstacle}


GOAL_SIDE = "+z"
"""Default side of the exit box for :func:`removal_scenario`'s goal."""

RAY_SAMPLES = 7
"""Interior points per interval at which a ray's depth in a pair's C-obstacle is read."""


def removal_scenario(assembly: Assembly, part: str, obstacles: list[str],
                     direction: str | np.ndarray = GOAL_SIDE) -> Scenario:
    """The planning problem of removing ``part`` with ``obstacles`` present: the part as
    the robot (its own frame is the world frame, start ``0``), the goal just outside the
    exit box along ``direction`` (an axis name such as ``"-x"``, or a vector), bounds the
    exit box grown by the margin, and the assembly's settings (with its contact
    tolerance). The region outside the exit box and inside the bounds is free and
    connected, so every goal side poses the same question ("can the part leave?")."""
    parts = {p.name: p for p in assembly.parts}
    unknown = [n for n in [part, *obstacles] if n not in parts]
    if unknown:
        raise InvalidParameterError(f"{', '.join(map(repr, unknown))}: not a part of "
                                    f"{assembly.name} (parts: {', '.join(parts)})")
    if part in obstacles:
        raise InvalidParameterError(f"{part!r} is both the moving part and an obstacle")
    body = parts[part]
    others = [parts[n] for n in obstacles]
    margin = ESCAPE_MARGIN_REL * assembly.diagonal
    lo, hi = _exit_box(body, others, margin)
    _, vec = _direction_vector(direction)
    goal = _exit_point(vec, (lo, hi), margin)
    return Scenario(name=f"{assembly.name}: remove {part}", units=assembly.units,
                    robot=Robot(body.name, body.mesh, body.source), obstacles=others,
                    start=np.zeros(3), goal=goal, orientation=np.eye(3),
                    bounds=(lo - margin, hi + margin), settings=assembly.settings)


@dataclass
class RayVerdict:
    """Whether obstacle part ``obstacle`` alone blocks the straight removal of ``part``
    along a direction (the ray from ``0`` past the whole assembly's exit box).

    Attributes:
        blocked: the ray enters the pair's C-obstacle deeper than the contact tolerance.
        how: ``"primitives"`` (decided by the cached C-obstacle primitives: a sampled
            depth beyond the tolerance proves ``blocked``; a ray that misses every
            primitive of an exact decomposition is free) or ``"fcl"`` (a grazing ray,
            sliding along touching faces: decided by ``FclChecker.check_segment`` on
            the two parts alone).
        depth: deepest sampled penetration of the ray into one primitive of the pair's
            C-obstacle (a lower bound of the penetration depth there), ``0`` when the
            ray misses it or only grazes it.
    """

    blocked: bool
    how: str
    depth: float


class PairCache:
    """Per-pair data of one assembly, computed once and reused across removal steps.

    The C-obstacle of part ``j`` for moving part ``i``, ``CO_ij = O_j ⊕ (−R_i)`` (the
    pairwise convex sums of their decompositions,
    ``Primitives.pairwise_sums(pieces_j, pieces_i, subtract=True)``), depends on the two
    parts only: it does not change when other parts leave. So does whether ``j`` blocks a
    straight removal of ``i`` along a direction (the ray is taken past the exit box of the
    whole assembly; while ``j`` is present, the exit box contains ``j``'s box, so the
    shorter ray of a later step meets ``j`` exactly where the long one does). The search
    asks the cache; every answer is computed at most once.

    Attributes:
        stats: ``sums_computed`` (pairs whose sums were built), ``sums_reused`` (later
            requests served from the cache), ``primitives`` (total primitives built),
            ``verdicts_computed`` / ``verdicts_reused`` (ray verdicts), ``fcl_pair_checks``
            (grazing rays decided by FCL), ``decompositions``.
        computed: the ``(moving, obstacle)`` pairs in the order their sums were built.
        step: the search's current step (a counter over all its runs, set by the search).
        uses: per pair, the steps that asked for its primitives or verdicts.
    """

    def __init__(self, assembly: Assembly, cache_dir=None) -> None:
        self.assembly = assembly
        self.parts = {p.name: p for p in assembly.parts}
        self.cache_dir = cache_dir
        self.delta = assembly.contact_tolerance
        self.margin = ESCAPE_MARGIN_REL * assembly.diagonal
        self._decs: dict[str, Any] = {}
        self._sums: dict[tuple[str, str], Any] = {}
        self._verdicts: dict[tuple[str, str, str], RayVerdict] = {}
        self._rays: dict[tuple[str, str, str], tuple[bool, float]] = {}
        self._detours: dict[tuple[str, str, str], float] = {}
        self._plane_cache: dict[tuple[str, str], list[tuple[np.ndarray, np.ndarray]]] = {}
        self._far: dict[tuple[str, str], np.ndarray] = {}
        self._contacts: dict[tuple[str, str], list[np.ndarray]] = {}
        self._checkers: dict[tuple[str, str], FclChecker] = {}
        self.computed: list[tuple[str, str]] = []
        self.step = 0
        self.uses: dict[tuple[str, str], set[int]] = {}
        self.stats = {"decompositions": 0, "sums_computed": 0, "sums_reused": 0,
                      "sums_failed": 0, "primitives": 0, "verdicts_computed": 0,
                      "verdicts_reused": 0, "fcl_pair_checks": 0}

    def decomposition(self, name: str):
        """The part's convex decomposition (the planner's settings and disk cache, so
        the planner's own runs hit the same cache entries)."""
        if name not in self._decs:
            settings = self.assembly.settings
            self._decs[name] = decompose(
                self.parts[name].mesh, name=name, threshold=settings.decomposition_threshold,
                seed=settings.seed % 2**32, cache_dir=self.cache_dir, progress=False)
            self.stats["decompositions"] += 1
        return self._decs[name]

    def primitives(self, moving: str, obstacle: str):
        """``CO_ij``: the pairwise sums ``P_k ⊕ (−Q_l)`` of the obstacle's pieces ``P_k``
        and the moving part's pieces ``Q_l`` (built once per ordered pair)."""
        key = (moving, obstacle)
        self._use(moving, obstacle)
        if key in self._sums:
            self.stats["sums_reused"] += 1
            return self._sums[key]
        pieces_o = [np.ascontiguousarray(p, dtype=np.float64)
                    for p in self.decomposition(obstacle).pieces]
        pieces_m = [np.ascontiguousarray(p, dtype=np.float64)
                    for p in self.decomposition(moving).pieces]
        try:
            prims = Primitives.pairwise_sums(pieces_o, pieces_m, subtract=True)
        except MinkplanError as error:
            # e.g. a degenerate sum of nearly parallel pieces: FCL decides for this pair
            log.warning("C-obstacle of %s for %s: %s; using FCL only for this pair",
                        obstacle, moving, error)
            prims = None
            self.stats["sums_failed"] += 1
        self._sums[key] = prims
        self.computed.append(key)
        self.stats["sums_computed"] += 1
        self.stats["primitives"] += 0 if prims is None else len(prims)
        return prims

    def checker(self, moving: str, obstacle: str) -> FclChecker:
        """FCL checker of the moving part against the obstacle part alone."""
        key = (moving, obstacle)
        if key not in self._checkers:
            self._checkers[key] = FclChecker(
                self.parts[moving].mesh, [self.parts[obstacle].mesh],
                contact_tolerance=self.delta, names=[obstacle])
        return self._checkers[key]

    def contact_directions(self, moving: str, obstacle: str) -> list[np.ndarray]:
        """Escape directions of FCL's contact normals between the two parts at the
        assembled pose that are not axis directions (those are tried anyway)."""
        key = (moving, obstacle)
        if key not in self._contacts:
            checker = self.checker(moving, obstacle)
            found = []
            for d in checker._escape_directions(checker.obstacles[0], np.zeros(3)):  # noqa: SLF001
                if np.max(np.abs(d)) <= 1.0 - 1e-9:
                    found.append(d)
            self._contacts[key] = found
        return self._contacts[key]

    def _use(self, moving: str, obstacle: str) -> None:
        self.uses.setdefault((moving, obstacle), set()).add(self.step)

    def far_point(self, moving: str, dname: str, vec: np.ndarray) -> np.ndarray:
        """End of the ray along ``vec``: just outside the whole assembly's exit box."""
        key = (moving, dname)
        if key not in self._far:
            part = self.parts[moving]
            others = [p for p in self.assembly.parts if p.name != moving]
            self._far[key] = _exit_point(vec, _exit_box(part, others, self.margin),
                                         self.margin)
        return self._far[key]

    def ray(self, moving: str, obstacle: str, dname: str,
            vec: np.ndarray) -> tuple[bool, float]:
        """``(touches, depth)`` of the ray along ``vec`` in ``CO_ij``, from the cached
        primitives: whether it meets any primitive (touching included) and the deepest
        sampled penetration (inside one primitive: a lower bound of the true depth)."""
        key = (moving, obstacle, dname)
        if key not in self._rays:
            far = self.far_point(moving, dname, vec)
            prims = self.primitives(moving, obstacle)
            if prims is None:  # no primitives: undecided (FCL)
                self._rays[key] = (True, 0.0)
                return self._rays[key]
            depth = 0.0
            intervals = [(a, b) for a, b in prims.segment_intervals(np.zeros(3), far)]
            for a, b in intervals:
                if b <= a:
                    continue
                ts = a + (b - a) * np.linspace(0.0, 1.0, RAY_SAMPLES + 2)[1:-1]
                points = np.ascontiguousarray(ts[:, None] * far[None, :])
                depth = max(depth, -float(np.min(prims.signed_distance(points))))
            self._rays[key] = (bool(intervals), depth)
        return self._rays[key]

    def detour(self, moving: str, obstacle: str, dname: str, vec: np.ndarray) -> float:
        """How far the part must step aside, across the ray along ``vec``, to pass
        ``obstacle``: the largest distance, over sampled points of the ray inside a
        primitive of ``CO_ij``, to that primitive's boundary within the plane through
        the point perpendicular to the ray (``0`` when the ray misses ``CO_ij``). A thin
        wall across the ray is a long detour; a low stop a short one."""
        key = (moving, obstacle, dname)
        if key in self._detours:
            return self._detours[key]
        touches, _ = self.ray(moving, obstacle, dname, vec)
        best = 0.0
        if touches and self.primitives(moving, obstacle) is not None:
            far = self.far_point(moving, dname, vec)
            prims = self.primitives(moving, obstacle)
            points = np.concatenate([
                a + (b - a) * np.linspace(0.0, 1.0, RAY_SAMPLES + 2)[1:-1]
                for a, b in prims.segment_intervals(np.zeros(3), far) if b > a]
                or [np.zeros(0)])[:, None] * far[None, :]
            if len(points):
                for normals, offsets in self._planes(moving, obstacle):
                    slack = offsets[None, :] - points @ normals.T
                    inside = np.all(slack >= -1e-12 * (1.0 + np.abs(offsets)), axis=1)
                    if not inside.any():
                        continue
                    across = np.linalg.norm(normals - np.outer(normals @ vec, vec), axis=1)
                    keep = across > 1e-9
                    if not keep.any():
                        continue
                    side = np.min(slack[inside][:, keep] / across[keep], axis=1)
                    best = max(best, float(np.max(side)))
        self._detours[key] = best
        return best

    def _planes(self, moving: str, obstacle: str) -> list[tuple[np.ndarray, np.ndarray]]:
        """Facet planes ``(normals, offsets)`` (inside: ``n·x <= d``) of each primitive
        of ``CO_ij``, from its boundary triangles."""
        key = (moving, obstacle)
        if key not in self._plane_cache:
            prims = self.primitives(moving, obstacle)
            planes = []
            for i in range(len(prims)):
                vertices, faces = prims.polytope(i)
                tri = vertices[faces]
                normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                length = np.linalg.norm(normals, axis=1)
                ok = length > 0
                normals = normals[ok] / length[ok, None]
                offsets = np.einsum("ij,ij->i", normals, tri[ok, 0])
                # outward: the centroid is inside
                flip = normals @ vertices.mean(axis=0) > offsets
                normals[flip] *= -1.0
                offsets[flip] *= -1.0
                planes.append((normals, offsets))
            self._plane_cache[key] = planes
        return self._plane_cache[key]

    def verdict(self, moving: str, obstacle: str, dname: str, vec: np.ndarray, *,
                fcl: bool = True) -> RayVerdict | None:
        """Whether ``obstacle`` alone blocks the straight removal of ``moving`` along
        ``vec`` (see :class:`RayVerdict`). With ``fcl=False``, ``None`` instead of an
        FCL check when the primitives cannot decide (a grazing ray)."""
        key = (moving, obstacle, dname)
        self._use(moving, obstacle)
        if key in self._verdicts:
            self.stats["verdicts_reused"] += 1
            return self._verdicts[key]
        touches, depth = self.ray(moving, obstacle, dname, vec)
        dec_m, dec_o = self.decomposition(moving), self.decomposition(obstacle)
        # a depth inside one primitive is a lower bound of the penetration depth (up to
        # the decompositions' excess), so beyond the tolerance it proves a collision
        if depth > self.delta + dec_m.excess + dec_o.excess:
            result = RayVerdict(True, "primitives", depth)
        elif not touches and dec_m.exact and dec_o.exact:
            result = RayVerdict(False, "primitives", 0.0)
        elif not fcl:
            return None
        else:
            far = self.far_point(moving, dname, vec)
            seg = self.checker(moving, obstacle).check_segment(np.zeros(3), far)
            self.stats["fcl_pair_checks"] += 1
            result = RayVerdict(not seg.valid, "fcl", depth)
        self._verdicts[key] = result
        self.stats["verdicts_computed"] += 1
        return result


@dataclass
class _Run:
    """One disassembly attempt of a set of parts."""

    steps: list[AssemblyStep]
    remaining: list[str]           # parts left when it stopped (base included)
    stuck: list[str]               # movable parts among them (empty: done)
    attempts: dict[str, dict[str, Any]]


class _Search:
    """The disassembly search of one assembly, with every cache shared by its runs."""

    def __init__(self, assembly: Assembly, *, planner: str, cache_dir, progress,
                 plan_parts: bool) -> None:
        self.assembly = assembly
        self.parts = {p.name: p for p in assembly.parts}
        self.order = [p.name for p in assembly.parts]
        self.planner = planner
        self.cache_dir = cache_dir
        self.progress = progress
        self.plan_parts = plan_parts
        self.delta = assembly.contact_tolerance
        self.margin = ESCAPE_MARGIN_REL * assembly.diagonal
        self.pairs = PairCache(assembly, cache_dir)
        self._straight: dict[tuple[str, frozenset], AssemblyStep | None] = {}
        self._planned: dict[tuple[str, frozenset], tuple[AssemblyStep | None, dict]] = {}
        self.stats = {"planner_runs": 0, "planner_reused": 0, "runs": 0}

    # ---------------------------------------------------------------- one part

    def straight(self, part: str, others: list[str]) -> AssemblyStep | None:
        """A straight removal of ``part`` with ``others`` present, or ``None``."""
        key = (part, frozenset(others))
        if key in self._straight:
            return self._straight[key]
        t0 = time.perf_counter()
        body = self.parts[part]
        bodies = [self.parts[n] for n in others]
        box = _exit_box(body, bodies, self.margin)
        # Shortest exits first (less sliding along touching faces, slow to certify);
        # then the escape directions of the contact normals.
        goals = sorted(((float(np.linalg.norm(_exit_point(d, box, self.margin))), i, name, d)
                        for i, (name, d) in enumerate(DIRECTIONS.items())),
                       key=lambda item: item[:2])
        seen: list[np.ndarray] = []
        for other in others:
            for d in self.pairs.contact_directions(part, other):
                if not any(float(np.dot(d, u)) > 1.0 - 1e-6 for u in seen):
                    seen.append(d)
                    goals.append((0.0, 0, _vector_name(d), d))
        step = None
        for _, _, dname, vec in goals:
            # cheap first: a part that blocks the line alone (its primitives decide, or
            # FCL did in an earlier step); grazing pairs not decided yet give None
            verdicts = [self.pairs.verdict(part, o, dname, vec, fcl=False) for o in others]
            if any(v is not None and v.blocked for v in verdicts):
                continue
            grazing = [o for o, v in zip(others, verdicts) if v is None]
            # then the whole motion, with every part present (FCL)
            path = np.array([np.zeros(3), _exit_point(vec, box, self.margin)])
            validation = _validate(body, bodies, path, self.delta)
            if validation["valid"]:
                step = AssemblyStep(part, "straight", dname, path, list(others),
                                    time.perf_counter() - t0, validation)
                break
            # blocked: find out which grazing parts block it alone, once, for later steps
            for o in grazing:
                self.pairs.verdict(part, o, dname, vec)
        self._straight[key] = step
        return step

    def goal_sides(self, part: str, others: list[str]) -> list[str]:
        """The six axis sides, most open first: by the longest sideways detour the
        straight line would need around a present part (:meth:`PairCache.detour`), then
        by the distance to the exit."""
        body = self.parts[part]
        box = _exit_box(body, [self.parts[n] for n in others], self.margin)
        keys = []
        for i, (dname, vec) in enumerate(DIRECTIONS.items()):
            detour = max((self.pairs.detour(part, other, dname, vec) for other in others),
                         default=0.0)
            keys.append((round(detour, 12),
                         float(np.linalg.norm(_exit_point(vec, box, self.margin))), i, dname))
        return [k[-1] for k in sorted(keys)]

    def planned(self, part: str, others: list[str]) -> tuple[AssemblyStep | None, dict]:
        """Plan the removal of ``part`` with ``others`` present: goals on the most open
        sides first (see :meth:`goal_sides`), stopping at the first path, at a proof that
        the part cannot leave (the region outside the exit box is connected, so a
        certificate walling off the start answers for every side), or after a side used
        up the time limit (so a stuck part costs one time limit, not six)."""
        from .planning import plan  # noqa: PLC0415 (lazy: native planner)

        key = (part, frozenset(others))
        if key in self._planned:
            self.stats["planner_reused"] += 1
            return self._planned[key]
        t0 = time.perf_counter()
        body = self.parts[part]
        bodies = [self.parts[n] for n in others]
        sides: list[dict[str, Any]] = []
        step, attempt = None, None
        for dname in self.goal_sides(part, others):
            t_side = time.perf_counter()
            scenario = removal_scenario(self.assembly, part, list(others), dname)
            self.stats["planner_runs"] += 1
            try:
                outcome = plan(scenario, planner=self.planner, cache_dir=self.cache_dir,
                               progress=self.progress)
            except (InvalidParameterError, ScenarioError):
                raise  # bad settings: the user's to fix
            except MinkplanError as error:  # e.g. geometry the native core rejects
                sides.append({"direction": dname, "status": "error", "reason": "error",
                              "message": str(error),
                              "seconds": time.perf_counter() - t_side})
                continue
            side = {"direction": dname, "status": outcome.status, "reason": outcome.reason,
                    "message": outcome.message, "seconds": time.perf_counter() - t_side}
            sides.append(side)
            if outcome.status == FOUND:
                path = np.asarray(outcome.waypoints, dtype=np.float64)
                validation = _validate(body, bodies, path, self.delta)
                if validation["valid"]:
                    step = AssemblyStep(part, "planned", dname, path, list(others),
                                        time.perf_counter() - t0, validation)
                    break
                side.update(status="validation_failed", validation=validation)
                continue
            walled = (outcome.certificate or {}).get("walled")
            if outcome.status == NO_PATH and walled != "goal":
                attempt = {"status": NO_PATH, "reason": outcome.reason,
                           "message": outcome.message, "direction": dname, "proved": True}
                break
            if side["seconds"] >= self.assembly.settings.time_limit:
                break  # out of time here: the other sides pose the same question
        if step is None and attempt is None:
            last = sides[-1] if sides else {"status": "skipped", "reason": "", "message": ""}
            attempt = {"status": last["status"], "reason": last["reason"],
                       "message": last["message"], "direction": sides[0]["direction"]
                       if sides else None, "proved": False}
        if attempt is not None:
            attempt.update(obstacles=list(others), sides=sides,
                           seconds=time.perf_counter() - t0)
        self._planned[key] = (step, attempt or {})
        return step, attempt or {}

    # ---------------------------------------------------------------- a set of parts

    def disassemble(self, names: list[str], base: str | None) -> _Run:
        """Remove parts of ``names`` one at a time (straight removals of every part
        first, then planned ones) until only the base (or one part) is left, or none
        can leave."""
        self.stats["runs"] += 1
        remaining = [n for n in self.order if n in names]
        steps: list[AssemblyStep] = []
        attempts: dict[str, dict[str, Any]] = {}

        def movable() -> list[str]:
            return [n for n in reversed(remaining) if n != base]

        while len(remaining) > 1 and movable():
            self.pairs.step += 1
            step = None
            for part in movable():
                step = self.straight(part, [n for n in remaining if n != part])
                if step is not None:
                    break
            if step is None and self.plan_parts:
                for part in movable():
                    step, attempt = self.planned(part, [n for n in remaining if n != part])
                    if step is not None:
                        break
                    attempts[part] = attempt
            if step is None:
                if not self.plan_parts:
                    for part in movable():
                        attempts.setdefault(part, {
                            "status": "skipped", "reason": "plan_parts", "proved": False,
                            "message": "no straight removal; planning was not asked for",
                            "obstacles": [n for n in remaining if n != part]})
                stuck = sorted(movable())
                return _Run(steps, list(remaining), stuck,
                            {k: v for k, v in attempts.items() if k in stuck})
            steps.append(step)
            attempts.pop(step.part, None)
            remaining = [n for n in remaining if n != step.part]
        return _Run(steps, list(remaining), [], {})

    def irreducible(self, run: _Run, base: str | None) -> _Run:
        """Shrink a stuck run's remaining parts to a set that still cannot be taken
        apart but where leaving out any one part makes it possible (greedy deletion:
        drop a part, re-run the search on the rest; when that gets stuck, continue from
        what it could not take apart). Taking parts away never blocks a removal, so a
        part kept once stays needed."""
        core = run
        tried: set[str] = set()
        while True:
            order = [base] if base in core.remaining else []
            order += [n for n in core.remaining if n != base
                      and not core.attempts.get(n, {}).get("proved")]
            order += [n for n in core.remaining if n not in order]
            candidate = next((n for n in order if n not in tried), None)
            if candidate is None:
                return core
            tried.add(candidate)
            rest = [n for n in core.remaining if n != candidate]
            rest_base = base if base in rest else None
            if len([n for n in rest if n != rest_base]) == 0 or len(rest) < 2:
                continue  # a single part, or the base alone, is taken apart trivially
            sub = self.disassemble(rest, rest_base)
            if sub.stuck:
                core = sub
                log.info("interlocked set reduced to %s", ", ".join(sub.remaining))

    def reuse(self) -> dict[str, Any]:
        """What was computed and what was reused (see :class:`PairCache`)."""
        several = sum(len(steps) > 1 for steps in self.pairs.uses.values())
        return {**self.pairs.stats, "pairs": len(self.pairs.computed),
                "pairs_reused_across_steps": several, "steps": self.pairs.step, **self.stats}


def plan_assembly(assembly: Assembly, *, planner: str = "minkplan", cache_dir=None,
                  progress: bool | None = False, plan_parts: bool = True,
                  minimize: bool = True) -> AssemblyResult:
    """Find an assembly sequence by disassembly (see the module docstring).

    Args:
        assembly: from :func:`load_assembly`.
        planner: for the full planning steps: ``"minkplan"`` or ``"ompl:NAME"``.
        cache_dir: decomposition cache (the planner's and the pair cache's).
        progress: the planner's status line.
        plan_parts: run the planner when no straight removal exists (else give up there).
        minimize: when stuck, shrink the stuck parts to an irreducible interlocked set
            (more searches on subsets, sharing every cache).
    """
    t_start = time.perf_counter()
    search = _Search(assembly, planner=planner, cache_dir=cache_dir, progress=progress,
                     plan_parts=plan_parts)
    base = assembly.base
    run = search.disassemble([p.name for p in assembly.parts], base)
    if not run.stuck:
        return AssemblyResult(assembly, SEQUENCE, run.steps, [], base,
                              assembly.contact_tolerance, time.perf_counter() - t_start,
                              reuse=search.reuse())
    if minimize and plan_parts:
        core = search.irreducible(run, base)
        interlocked = sorted(core.remaining)
    else:  # the stuck movable parts, as found
        core, interlocked = run, list(run.stuck)
    return AssemblyResult(assembly, INTERLOCKED, run.steps, interlocked, base,
                          assembly.contact_tolerance, time.perf_counter() - t_start,
                          dict(run.attempts), stuck=list(run.stuck),
                          core_attempts=dict(core.attempts),
                          reuse=search.reuse())


def removal_problems(result: AssemblyResult) -> list[dict[str, Any]]:
    """The removal problems a result was decided on: every removal step (expected
    ``found``; the goal on the side it left by, or along its straight direction) and,
    for an interlocked result, each movable part of the interlocked set with the rest of
    the set present (expected ``no_path`` when that was proved)."""
    problems = []
    for step in result.removal:
        end = np.asarray(step.removal[-1], dtype=np.float64)
        direction = step.direction if step.direction in DIRECTIONS else end
        problems.append({"part": step.part, "obstacles": list(step.obstacles),
                         "direction": direction, "expected": FOUND, "method": step.method})
    for name in result.interlocked:
        attempt = result.core_attempts.get(name)
        if name == result.base or not attempt:
            continue
        problems.append({"part": name, "obstacles": list(attempt["obstacles"]),
                         "direction": attempt.get("direction") or GOAL_SIDE,
                         "expected": NO_PATH if attempt.get("proved") else "unknown",
                         "method": "interlocked"})
    return problems


def benchmark_removals(result: AssemblyResult, planners=("minkplan", "ompl:RRTConnect"),
                       *, cache_dir=None, runs: int = 1,
                       time_limit: float | None = None) -> list[dict[str, Any]]:
    """Per-step planning time of several planners on the removal problems of a result
    (:func:`removal_problems`, each as a :func:`removal_scenario`).

    Args:
        result: from :func:`plan_assembly`.
        planners: ``"minkplan"`` and/or ``"ompl:NAME"``.
        cache_dir: decomposition cache (use a warm one to leave decomposition out).
        runs: runs per problem and planner; OMPL run ``k`` uses seed ``k`` (minkplan is
            deterministic and keeps the assembly's seed).
        time_limit: seconds per run (default: the assembly's ``planner.time_limit``).

    Returns:
        One row per problem, planner and run: ``part``, ``method``, ``obstacles``,
        ``direction``, ``expected``, ``planner``, ``run``, ``seed``, ``status``,
        ``seconds`` (wall clock of :func:`planner.planning.plan`), ``planning_seconds``
        (the same without its validation), ``length`` and FCL ``valid`` (at the
        assembly's contact tolerance; ``None`` when no path was found).
    """
    from .planning import plan  # noqa: PLC0415

    if runs < 1:
        raise InvalidParameterError(f"runs = {runs}: must be >= 1")
    parts = {p.name: p for p in result.assembly.parts}
    rows = []
    for problem in removal_problems(result):
        scenario = removal_scenario(result.assembly, problem["part"], problem["obstacles"],
                                    problem["direction"])
        direction = _direction_vector(problem["direction"])[0]
        for name in planners:
            for run in range(runs):
                seed = scenario.settings.seed if name == "minkplan" else run
                settings = dataclasses.replace(
                    scenario.settings, seed=seed,
                    time_limit=scenario.settings.time_limit if time_limit is None
                    else time_limit)
                t0 = time.perf_counter()
                outcome = plan(dataclasses.replace(scenario, settings=settings), planner=name,
                               cache_dir=cache_dir, progress=False)
                seconds = time.perf_counter() - t0
                valid = None
                if outcome.status == FOUND:
                    valid = _validate(parts[problem["part"]],
                                      [parts[n] for n in problem["obstacles"]],
                                      np.asarray(outcome.waypoints),
                                      result.contact_tolerance)["valid"]
                rows.append({
                    "part": problem["part"], "method": problem["method"],
                    "obstacles": problem["obstacles"], "direction": direction,
                    "expected": problem["expected"], "planner": name, "run": run,
                    "seed": seed, "status": outcome.status, "reason": outcome.reason,
                    "seconds": seconds,
                    "planning_seconds": outcome.timings.get("total", seconds)
                    - outcome.timings.get("validate", 0.0),
                    "length": outcome.length, "valid": valid})
    return jsonable(rows)


# --------------------------------------------------------------------------------------
# Command line (``minkplan assemble``)
# --------------------------------------------------------------------------------------


PART_COLORS = (0x2DA44E, 0x2F6FDE, 0xE6007E, 0x7E57C2, 0x00A3BF, 0xF2B705, 0x8D6E63,
               0xC62828)
"""Colours of the moving parts in the animation (cycled); fixed parts are orange."""


def scene_for_assembly(result: AssemblyResult, *, seconds_per_part: float = 3.0):
    """A meshcat :class:`~planner.viz.Scene` assembling the parts one after another.

    Every part is a layer ``assembly/<name>``. With a sequence, each part waits at the
    start of its insertion path (outside), then moves along it in its turn
    (``seconds_per_part`` each, in assembly order) and stays in place. Without one, the
    parts are shown assembled and the interlocked ones in red.
    """
    from planner.viz import COLORS, Scene  # noqa: PLC0415 (lazy: optional viewer)

    scene = Scene(f"{result.assembly.name}: {result.message}")
    steps = {s.part: s for s in result.removal}
    turn = {name: i for i, name in enumerate(result.order)}
    for k, part in enumerate(result.assembly.parts):
        step = steps.get(part.name)
        if part.name in result.interlocked:
            color = 0xD0021B
        elif step is None:
            color = COLORS["obstacle"]
        else:
            color = PART_COLORS[k % len(PART_COLORS)]
        path = f"assembly/{node_name(part.name)}"
        start = np.zeros(3) if step is None else step.insertion[0]
        transform = np.eye(4)
        transform[:3, 3] = start
        scene.add_mesh(path, part.mesh, color=color, transform=transform)
        if step is None or not result.found:
            continue
        waypoints = step.insertion
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(waypoints, axis=0),
                                                              axis=1))])
        t0 = turn[part.name] * seconds_per_part
        times = t0 + (arc / arc[-1] if arc[-1] > 0 else arc) * seconds_per_part
        scene.animate(path, np.concatenate([[0.0], times]),
                      np.vstack([waypoints[:1], waypoints]))
    scene.frame()
    return scene


def node_name(name: str) -> str:
    """A meshcat path segment for a part name (letters, digits, ``_ . -``)."""
    return "".join(c if c.isalnum() or c in "_.-" else "_" for c in name) or "part"


def assemble_command(path: str | os.PathLike[str], out: str | os.PathLike[str], *,
                     html: bool = False, cache_dir=None, progress: bool | None = None,
                     write=None) -> int:
    """``minkplan assemble FILE --out DIR [--html]``: write ``DIR/sequence.json`` and
    ``DIR/report.json`` (and ``DIR/assembly.html``, a self-contained meshcat animation,
    with ``html``), print one line; return the exit code (0 sequence, 1 none, 2 bad
    output directory). ``ScenarioError`` propagates (the CLI turns it into exit 2).

    Args:
        write: ``write(path, data)`` for JSON files (default: plain ``json.dump``).
    """
    import json  # noqa: PLC0415
    import sys  # noqa: PLC0415

    out = Path(out)
    if out.exists() and not out.is_dir():
        sys.stderr.write(f"minkplan: error: --out {out}: exists and is not a directory\n")
        return 2
    assembly = load_assembly(path)
    result = plan_assembly(assembly, cache_dir=cache_dir, progress=progress)
    if write is None:
        def write(target: Path, data: Any) -> None:
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(json.dumps(data, indent=2) + "\n")
    write(out / "sequence.json", result.sequence_json())
    write(out / "report.json", result.report_json())
    sys.stdout.write(f"{assembly.name}: {result.message} (contact tolerance "
                     f"{result.contact_tolerance:.3g}); {result.seconds:.2f} s; "
                     f"wrote {out}/sequence.json\n")
    if html:
        from planner.viz import write_html  # noqa: PLC0415

        page = write_html(scene_for_assembly(result), out / "assembly.html")
        sys.stdout.write(f"wrote {page} (self-contained; open it in a browser)\n")
    return result.exit_code
