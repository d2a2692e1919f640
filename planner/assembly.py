"""Assembly sequencing by disassembly: which part can leave, and along which path.

Entry points:

- :func:`load_assembly` / :func:`parse_assembly` -- read an assembly YAML (see
  ``docs/assembly.md``) into an :class:`Assembly`.
- :func:`plan_assembly` -- the disassembly search; returns an :class:`AssemblyResult`
  (``status`` ``"sequence"`` or ``"interlocked"``, the assembly order with every part's
  insertion path, ``sequence_json()``, ``report_json()``, ``exit_code``).

Search: while movable parts remain, find one that can translate from its assembled pose
to outside the remaining parts' bounding box (its own included) grown by a margin, with
the other remaining parts as obstacles. Cheap first: straight removals along ``±x, ±y,
±z`` (shortest exit first), then along the escape directions of FCL's contact normals at
the assembled pose, checked by :meth:`FclChecker.check_segment`; a direction
blocked by a part stays blocked while that part is present, so it is not re-checked.
Then, for each part in turn, the octree planner (:func:`planner.planning.plan`) on a
:class:`~planner.scenario.Scenario` whose robot is the part (start ``0``) and whose goal
lies outside that box (the region outside it is connected, so one goal decides). The
reverse of the removal order is an assembly order; each insertion path is the removal
path reversed. When no part can leave, the remaining movable parts are reported as
interlocked.

Contact: assembled parts touch face to face. One contact tolerance ``delta`` (the file's
``contact_tolerance``, else ``DEFAULT_CONTACT_REL`` times the assembly's diagonal) is
used by the straight-line checks, the planner (``planner.contact_tolerance``) and the
final FCL validation of every reported path, and it is written in the output.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from .errors import ScenarioError
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
    "assemble_command",
    "benchmark_removals",
    "load_assembly",
    "parse_assembly",
    "plan_assembly",
    "removal_scenario",
    "scene_for_assembly",
]

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
        interlocked: names of the movable parts that could not leave (empty when a
            sequence exists), with ``attempts`` saying why for each.
        base: the fixed part, or ``None``.
        contact_tolerance: ``delta`` used everywhere.
        seconds: total time.
        attempts: per part, the last planning outcome when it could not leave.
    """

    assembly: Assembly
    status: str
    removal: list[AssemblyStep]
    interlocked: list[str]
    base: str | None
    contact_tolerance: float
    seconds: float
    attempts: dict[str, dict[str, Any]] = field(default_factory=dict)

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
        """For an interlocked result: every stuck part's no-path was proved (octree
        certificate); ``False`` when some planner only gave up."""
        return not self.found and all(self.attempts.get(n, {}).get("proved", False)
                                      for n in self.interlocked)

    @property
    def message(self) -> str:
        if self.found:
            return f"assembly order: {' -> '.join(self.order)}"
        how = "proved" if self.proved else "not proved: some planner gave up"
        return f"no sequence: interlocked parts {', '.join(self.interlocked)} ({how})"

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
            "parts": parts, "interlocked": self.interlocked, "proved": self.proved,
            "message": self.message,
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
            "interlocked": self.interlocked, "attempts": self.attempts,
            "settings": dataclasses.asdict(self.assembly.settings),
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


def _contact_directions(checker: FclChecker) -> list[tuple[str, np.ndarray]]:
    """Escape directions from FCL's contact normals at the assembled pose that are not
    axis directions (those are tried anyway)."""
    found: list[tuple[str, np.ndarray]] = []
    for part in checker.obstacles:
        for d in checker._escape_directions(part, np.zeros(3)):  # noqa: SLF001
            if np.max(np.abs(d)) > 1.0 - 1e-9:
                continue
            if any(float(np.dot(d, u)) > 1.0 - 1e-6 for _, u in found):
                continue
            found.append(("[" + ", ".join(f"{v:.4g}" for v in d) + "]", d))
    return found


def _validate(part: Body, others: list[Body], path: np.ndarray, delta: float) -> dict:
    checker = FclChecker(part.mesh, [p.mesh for p in others], contact_tolerance=delta,
                         names=[p.name for p in others])
    check = checker.check_path(path)
    return {"valid": bool(check.valid), "min_clearance": check.min_clearance,
            "n_checks": check.n_checks, "contact_tolerance": delta,
            "obstacle": check.obstacle}


GOAL_SIDE = "+z"
"""Side of the exit box where a planned removal's goal lies."""


def removal_scenario(assembly: Assembly, part: str, obstacles: list[str]) -> Scenario:
    """The planning problem of removing ``part`` with ``obstacles`` present: the part as
    the robot (its own frame is the world frame, start ``0``), the goal just outside the
    exit box on its ``GOAL_SIDE`` side, bounds the exit box grown by the margin, and the
    assembly's settings (with its contact tolerance)."""
    parts = {p.name: p for p in assembly.parts}
    body = parts[part]
    others = [parts[n] for n in obstacles]
    margin = ESCAPE_MARGIN_REL * assembly.diagonal
    lo, hi = _exit_box(body, others, margin)
    goal = _exit_point(DIRECTIONS[GOAL_SIDE], (lo, hi), margin)
    return Scenario(name=f"{assembly.name}: remove {part}", units=assembly.units,
                    robot=Robot(body.name, body.mesh, body.source), obstacles=others,
                    start=np.zeros(3), goal=goal, orientation=np.eye(3),
                    bounds=(lo - margin, hi + margin), settings=assembly.settings)


def plan_assembly(assembly: Assembly, *, planner: str = "minkplan", cache_dir=None,
                  progress: bool | None = False, plan_parts: bool = True) -> AssemblyResult:
    """Find an assembly sequence by disassembly (see the module docstring).

    Args:
        assembly: from :func:`load_assembly`.
        planner: for the full planning steps: ``"minkplan"`` or ``"ompl:NAME"``.
        cache_dir: decomposition cache for the planner.
        progress: the planner's status line.
        plan_parts: run the planner when no straight removal exists (else give up there).
    """
    from .planning import plan  # noqa: PLC0415 (lazy: native planner)

    t_start = time.perf_counter()
    delta = assembly.contact_tolerance
    margin = ESCAPE_MARGIN_REL * assembly.diagonal
    remaining = list(assembly.parts)
    blocked: dict[tuple[str, str], str | None] = {}  # (part, dir) -> blocking part
    steps: list[AssemblyStep] = []
    attempts: dict[str, dict[str, Any]] = {}

    def movable() -> list[Body]:
        return [p for p in reversed(remaining) if p.name != assembly.base]

    while len(remaining) > 1 and movable():
        names_left = {p.name for p in remaining}
        step = None
        # 1. Straight removals, all parts.
        for part in movable():
            t0 = time.perf_counter()
            others = [p for p in remaining if p is not part]
            box = _exit_box(part, others, margin)
            checker = FclChecker(part.mesh, [p.mesh for p in others],
                                 contact_tolerance=delta, names=[p.name for p in others])
            # Shortest exits first: less sliding along touching faces (slow to certify);
            # then the escape directions of the contact normals.
            goals = sorted(((float(np.linalg.norm(_exit_point(d, box, margin))), i, dname,
                             _exit_point(d, box, margin))
                            for i, (dname, d) in enumerate(DIRECTIONS.items())),
                           key=lambda item: item[:2])
            goals += [(0.0, 0, dname, _exit_point(d, box, margin))
                      for dname, d in _contact_directions(checker)]
            for _, _, dname, goal in goals:
                key = (part.name, dname)
                if key in blocked and blocked[key] in names_left:
                    continue
                seg = checker.check_segment(np.zeros(3), goal)
                if seg.valid:
                    path = np.array([np.zeros(3), goal])
                    step = AssemblyStep(part.name, "straight", dname, path,
                                        [p.name for p in others], 0.0,
                                        _validate(part, others, path, delta))
                    break
                blocked[key] = seg.obstacle
            if step is not None:
                step.seconds = time.perf_counter() - t0
                break
        # 2. Full planning, one part at a time.
        if step is None and plan_parts:
            for part in movable():
                t0 = time.perf_counter()
                others = [p for p in remaining if p is not part]
                dname = GOAL_SIDE
                scenario = removal_scenario(assembly, part.name, [p.name for p in others])
                outcome = plan(scenario, planner=planner, cache_dir=cache_dir,
                               progress=progress)
                if outcome.status == FOUND:
                    path = np.asarray(outcome.waypoints, dtype=np.float64)
                    validation = _validate(part, others, path, delta)
                    if validation["valid"]:
                        step = AssemblyStep(part.name, "planned", dname, path,
                                            [p.name for p in others],
                                            time.perf_counter() - t0, validation)
                        break
                    attempts[part.name] = {"status": "validation_failed",
                                           "validation": validation}
                    continue
                attempts[part.name] = {
                    "status": outcome.status, "reason": outcome.reason,
                    "message": outcome.message, "obstacles": [p.name for p in others],
                    "proved": outcome.status == NO_PATH,
                    "seconds": time.perf_counter() - t0}
        if step is None:
            stuck = sorted(p.name for p in movable())
            return AssemblyResult(assembly, INTERLOCKED, steps, stuck, assembly.base, delta,
                                  time.perf_counter() - t_start,
                                  {k: v for k, v in attempts.items() if k in stuck})
        steps.append(step)
        attempts.pop(step.part, None)
        remaining = [p for p in remaining if p.name != step.part]
    return AssemblyResult(assembly, SEQUENCE, steps, [], assembly.base, delta,
                          time.perf_counter() - t_start)


def benchmark_removals(result: AssemblyResult, planners=("minkplan", "ompl:RRTConnect"),
                       *, cache_dir=None) -> list[dict[str, Any]]:
    """Per-step planning time of several planners on the removal problems of a result
    (every removal step, straight or planned, as a :func:`removal_scenario`).

    Returns:
        One row per step and planner: ``part``, ``planner``, ``status``, ``seconds``
        (wall clock of :func:`planner.planning.plan`, decomposition included; use a warm
        ``cache_dir`` to leave it out), ``length`` and FCL ``valid``.
    """
    from .planning import plan  # noqa: PLC0415

    rows = []
    for step in result.removal:
        scenario = removal_scenario(result.assembly, step.part, step.obstacles)
        for name in planners:
            t0 = time.perf_counter()
            outcome = plan(scenario, planner=name, cache_dir=cache_dir, progress=False)
            seconds = time.perf_counter() - t0
            valid = None
            if outcome.status == FOUND:
                parts = {p.name: p for p in result.assembly.parts}
                valid = _validate(parts[step.part], [parts[n] for n in step.obstacles],
                                  np.asarray(outcome.waypoints), result.contact_tolerance)["valid"]
            rows.append({"part": step.part, "planner": name, "status": outcome.status,
                         "seconds": seconds, "length": outcome.length, "valid": valid})
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
