"""minkplan's own planner: an octree roadmap of the Minkowski-sum C-space.

Pipeline (:func:`plan_octree`):

1. Convex pieces of the robot and of every obstacle (:func:`planner.decompose`, exact for
   convex bodies, else CoACD, cached).
2. C-obstacle primitives ``M_ij = P_i ⊕ (−Q_j)`` for all obstacles at once
   (``Primitives.pairwise_sums``), remembering which obstacle each came from; grown by
   the requested clearance plus the decompositions' measured deficits (a cube margin).
3. The native :class:`~planner._minkowski_core.CSpace`: the primitives, walls filling
   everything outside the bounds, and an octree with cells of 1/64 of the bounds'
   largest side whose lattice reaches a floor of ``floor_rel`` times the bounds'
   diagonal (or ``planner.resolution``). EMPTY leaves meet no primitive (exactly free),
   FULL leaves lie inside one (exactly blocked), MIXED leaves are undecided.
4. Start and goal: inside a primitive means collision (named obstacle and depth), unless
   FCL accepts the point within the contact tolerance (then a short escape segment,
   checked by FCL, leads out). Each attaches to its EMPTY leaf, or from a MIXED leaf to
   nearby EMPTY leaves by exact segment tests.
5. Rounds: A* through EMPTY leaves (face-adjacent leaves joined through the centre of
   their shared face: every segment lies in one closed EMPTY leaf, so the path is
   exactly free). If there is none, A* finds the cheapest channel of EMPTY and MIXED
   leaves (MIXED ones cost more) and its MIXED leaves (and their MIXED neighbours) are
   split; repeat. When no channel avoids MIXED leaves at the floor: if start and goal
   lie in different components of the EMPTY ∪ MIXED leaves, that is a proof that no
   path exists (the FULL leaves around one component wall it off, each inside one
   primitive); otherwise "not found down to the floor".
6. Shortcutting with segment tests that keep a small margin, then validation on the
   original meshes: FCL (conservative advancement) and OMPL's ``PathGeometric.check``.
   A path that fails either is never reported as found.

Everything is deterministic: no random choice is made after the decomposition (whose
CoACD seed is ``planner.seed``). ``planner.time_limit`` bounds the refinement rounds; the
decomposition (cached on disk) is preprocessing and does not count against it.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner._minkowski_core import CSpace, Primitives
from planner.decompose import decompose
from planner.errors import ResourceLimitError, ScenarioError
from planner.minkowski import convex_bodies, mesh_arrays
from planner.scenario import Scenario
from planner.validation import FclChecker

from .outcome import FOUND, NO_PATH, NOT_FOUND, PlanOutcome
from .validate import validate_path

__all__ = ["OctreeParams", "default_contact_tolerance", "plan_octree"]

log = logging.getLogger(__name__)

LABELS = ("empty", "full", "mixed")
WALL = "bounds"
"""Obstacle name reported for the walls outside the bounds."""


@dataclass(frozen=True)
class OctreeParams:
    """Parameters of the octree planner (defaults work for scenes of any size: every
    length is relative to the scenario's bounds).

    Attributes:
        coarse_divisions: the first octree's cells are the bounds' largest side over this.
        floor_rel: refinement floor as a fraction of the bounds' diagonal (when the
            scenario sets no ``planner.resolution``).
        contact_rel: default contact tolerance as a fraction of the scene's scale.
        mixed_penalty: a channel pays ``1 + mixed_penalty`` per length in MIXED leaves.
        refine_levels: levels a channel leaf is split per round.
        ring: also split the MIXED neighbours of a channel's MIXED leaves.
        attach_rings: face-steps searched to attach a point in a MIXED leaf.
        max_leaves: leaf budget of the octree.
        max_rounds: refinement rounds at most.
        shortcut_passes: greedy shortcutting passes.
        escape_rel: longest escape from a tolerated contact, in contact tolerances.
    """

    coarse_divisions: int = 64
    floor_rel: float = 1e-5
    contact_rel: float = 1e-6
    mixed_penalty: float = 2.0
    refine_levels: int = 1
    ring: bool = True
    attach_rings: int = 2
    max_leaves: int = 20_000_000
    max_rounds: int = 400
    shortcut_passes: int = 3
    escape_rel: float = 2.0


def default_contact_tolerance(scenario: Scenario, params: OctreeParams | None = None) -> float:
    """``planner.contact_tolerance``, or ``contact_rel`` times the scene's scale (the
    diagonal of the bounds)."""
    if scenario.settings.contact_tolerance is not None:
        return float(scenario.settings.contact_tolerance)
    params = params or OctreeParams()
    lo, hi = scenario.bounds
    return params.contact_rel * float(np.linalg.norm(hi - lo))


class _Clock:
    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def add(self, key: str, seconds: float) -> None:
        self.seconds[key] = self.seconds.get(key, 0.0) + seconds

    def stage(self, key: str):
        clock = self

        class _Stage:
            def __enter__(self):
                self.t0 = time.perf_counter()

            def __exit__(self, *exc):
                clock.add(key, time.perf_counter() - self.t0)

        return _Stage()


class _Progress:
    """One status line on stderr, rewritten in place (only when asked or on a TTY)."""

    def __init__(self, enabled: bool | None) -> None:
        self.enabled = sys.stderr.isatty() if enabled is None else bool(enabled)
        self.shown = False

    def show(self, text: str) -> None:
        if self.enabled:
            sys.stderr.write(f"\r\033[K{text}")
            sys.stderr.flush()
            self.shown = True

    def close(self) -> None:
        if self.shown:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()


def choose_source(scenario: Scenario) -> tuple[str, str]:
    """``("exact" | "decomposition", why)`` for the scenario's ``planner.exact``: ``true``
    the exact boundary-convolution source, ``false`` the convex decomposition, ``auto``
    the decomposition when every body of every part is convex (then it is exact, and the
    fastest), else the exact source (CoACD's hulls would over-approximate)."""
    setting = scenario.settings.exact
    parts = [scenario.robot, *scenario.obstacles]
    surfaces = [p.name for p in parts if not p.solid]
    if setting is True:
        return "exact", "planner.exact: true"
    if setting is False:
        if surfaces:
            raise ScenarioError(
                f"planner.exact: false: {', '.join(surfaces)} "
                f"{'is a surface' if len(surfaces) == 1 else 'are surfaces'} (not closed "
                f"solids), which the convex decomposition cannot represent; use exact: auto",
                field="planner.exact")
        return "decomposition", "planner.exact: false"
    if surfaces:
        return "exact", f"auto: {', '.join(surfaces)} not solid (surfaces)"
    nonconvex = [p.name for p in parts if not convex_bodies(p.mesh)]
    if nonconvex:
        return "exact", f"auto: {', '.join(nonconvex)} not convex"
    return "decomposition", "auto: every body is convex (the decomposition is exact)"


def _decompositions(scenario: Scenario, cache_dir, progress: bool | None):
    settings = scenario.settings
    kwargs = dict(threshold=settings.decomposition_threshold, seed=settings.seed % 2**32,
                  cache_dir=cache_dir, progress=progress)
    robot = decompose(scenario.robot.mesh, name=scenario.robot.name, **kwargs)
    obstacles = [decompose(b.mesh, name=b.name, **kwargs) for b in scenario.obstacles]
    return robot, obstacles


def _describe_decomposition(name: str, d) -> dict[str, Any]:
    return {"name": name, "pieces": len(d.pieces), "exact": d.exact, "method": d.method,
            "excess": d.excess, "deficit": d.deficit, "cache_hit": d.cache_hit,
            "seconds": d.seconds}


class _Problem:
    """Primitives (or meshes, with the exact source), their owners and the C-space of one
    scenario. ``robot_dec`` ``None``: the exact source."""

    def __init__(self, scenario: Scenario, params: OctreeParams, robot_dec, obstacle_decs,
                 clock: _Clock) -> None:
        self.scenario = scenario
        self.params = params
        names = [b.name for b in scenario.obstacles]
        self.source = "decomposition" if robot_dec is not None else "exact"
        with clock.stage("primitives"):
            if self.source == "exact":
                self.meshes = [_part_arrays(b) for b in scenario.obstacles]
                self.robot_mesh = _part_arrays(scenario.robot)
                self.prims = None
                self.owner = np.arange(len(names), dtype=np.int64)
                robot_dec, obstacle_decs = _ExactDec(), [_ExactDec() for _ in names]
            else:
                pieces, owner = [], []
                for k, d in enumerate(obstacle_decs):
                    pieces += [np.ascontiguousarray(p, dtype=np.float64) for p in d.pieces]
                    owner += [k] * len(d.pieces)
                robot_pieces = [np.ascontiguousarray(p, dtype=np.float64)
                                for p in robot_dec.pieces]
                self.prims = (Primitives.pairwise_sums(pieces, robot_pieces, subtract=True)
                              if pieces else None)
                self.owner = np.repeat(np.asarray(owner, dtype=np.int64), len(robot_pieces))
        self.names = names
        self.exact = robot_dec.exact and all(d.exact for d in obstacle_decs)
        self.deficit = robot_dec.deficit + max((d.deficit for d in obstacle_decs), default=0.0)
        self.excess = robot_dec.excess + max((d.excess for d in obstacle_decs), default=0.0)
        lo, hi = scenario.bounds
        self.bounds = np.stack([lo, hi])
        self.side = float(np.max(hi - lo))
        self.diagonal = float(np.linalg.norm(hi - lo))
        resolution = scenario.settings.resolution
        self.floor_asked = float(resolution) if resolution else params.floor_rel * self.diagonal
        self.coarse = max(self.side / params.coarse_divisions, self.floor_asked)

    def obstacle_of(self, prim: int, n_obstacle_prims: int) -> str:
        if prim < 0:
            return "unknown"
        if prim >= n_obstacle_prims:
            return WALL
        return self.names[int(self.owner[prim])]

    def build(self, margin: float, clock: _Clock) -> CSpace:
        with clock.stage("octree"):
            if self.source == "exact":
                return CSpace.exact(self.meshes, self.robot_mesh, self.bounds, self.floor_asked,
                                    self.coarse, margin=margin,
                                    max_leaves=self.params.max_leaves,
                                    solid=[b.solid for b in self.scenario.obstacles],
                                    robot_solid=self.scenario.robot.solid)
            return CSpace(self.prims, self.bounds, self.floor_asked, self.coarse, margin=margin,
                          max_leaves=self.params.max_leaves)


def _part_arrays(part) -> tuple[np.ndarray, np.ndarray]:
    """A solid's checked arrays, or a surface's triangles as they are."""
    if part.solid:
        return mesh_arrays(part.mesh, part.name)
    return (np.ascontiguousarray(part.mesh.vertices, dtype=np.float64),
            np.ascontiguousarray(part.mesh.faces, dtype=np.int64))


@dataclass
class _ExactDec:
    """Stands in for a decomposition when the exact source is used: exact, no hulls."""

    exact: bool = True
    deficit: float = 0.0
    excess: float = 0.0


@dataclass
class _SearchResult:
    status: str
    reason: str
    message: str
    waypoints: np.ndarray | None = None
    min_leaf_size: float = float("nan")
    certificate: dict[str, Any] | None = None


def _search(problem: _Problem, cs: CSpace, start: np.ndarray, goal: np.ndarray,
            clock: _Clock, rounds: list[dict], deadline: float,
            progress: _Progress) -> _SearchResult:
    """Refinement rounds until a free path, a certificate, the floor or a limit."""
    params = problem.params
    s, g = start.tolist(), goal.tolist()
    if cs.segment_is_free(s, g):
        return _SearchResult(FOUND, "path", "the straight segment is free",
                             waypoints=np.array([s, g]), min_leaf_size=float("inf"))
    for index in range(params.max_rounds + 1):
        with clock.stage("search"):
            path = cs.free_path(s, g, rings=params.attach_rings)
        if path is not None:
            return _SearchResult(FOUND, "path", f"roadmap path after {index} refinement rounds",
                                 waypoints=np.asarray(path["waypoints"]),
                                 min_leaf_size=float(path["min_leaf_size"]))
        with clock.stage("search"):
            channel = cs.channel(s, g, penalty=params.mixed_penalty, refinable_only=True)
        if channel is None:
            with clock.stage("certificate"):
                certificate = cs.certificate(s, g)
            if certificate is not None and not certificate["verified"]:
                unverified = int((np.asarray(certificate["wall_prims"]) < 0).sum())
                log.warning("a no-path certificate did not pass re-verification: %d of %d "
                            "wall cells could not be shown blocked", unverified,
                            len(certificate["wall_prims"]))
                return _SearchResult(
                    NOT_FOUND, "certificate_unverified",
                    f"start and goal lie in different components of the EMPTY and MIXED "
                    f"cells, but {unverified} of the {len(certificate['wall_prims'])} FULL "
                    f"cells walling them apart could not be re-verified as blocked; no proof "
                    f"is claimed")
            if certificate is not None:
                return _SearchResult(NO_PATH, "certificate",
                                     "start and goal lie in different components of the "
                                     "EMPTY and MIXED cells", certificate=certificate)
            return _SearchResult(
                NOT_FOUND, "floor",
                f"no path found down to the floor cell size {cs.floor:.3g}: every channel "
                f"from start to goal crosses MIXED cells at the floor")
        if index == params.max_rounds:
            break
        if time.perf_counter() > deadline:
            return _SearchResult(NOT_FOUND, "time_limit",
                                 f"time limit reached after {index} refinement rounds")
        try:
            with clock.stage("refine"):
                stats = cs.refine(channel["leaves"], ring=params.ring,
                                  levels=params.refine_levels)
        except ResourceLimitError as exc:
            return _SearchResult(NOT_FOUND, "budget", f"octree budget exhausted: {exc}")
        if stats["refined"] == 0:
            return _SearchResult(
                NOT_FOUND, "floor",
                f"no path found down to the floor cell size {cs.floor:.3g}: the start or "
                f"goal cannot be attached to the roadmap")
        rounds.append({
            "round": index + 1,
            "channel_leaves": len(channel["leaves"]),
            "channel_min_cell": channel["min_leaf_size"],
            "refined": stats["refined"],
            "created": stats["created"],
            "leaves": len(cs),
        })
        progress.show(f"minkplan: round {index + 1}: {len(cs)} cells, channel of "
                      f"{len(channel['leaves'])} cells down to {channel['min_leaf_size']:.3g}")
    return _SearchResult(NOT_FOUND, "rounds", f"{params.max_rounds} refinement rounds used up")


def _point_report(problem: _Problem, cs: CSpace, checker: FclChecker, p: np.ndarray,
                  which: str) -> dict[str, Any]:
    """Which obstacle a colliding start or goal is in, and how deep."""
    inside = cs.containing(p.tolist())
    by_obstacle: dict[str, float] = {}
    for prim, depth in inside:
        name = problem.obstacle_of(prim, cs.n_obstacle_prims)
        by_obstacle[name] = max(by_obstacle.get(name, 0.0), depth)
    fcl_hit = checker.colliding_obstacle(p)
    report: dict[str, Any] = {"which": which, "position": p.tolist()}
    if fcl_hit is not None:
        report["obstacle"] = fcl_hit[0]
        report["depth_upper_bound"] = fcl_hit[1]
        report["depth_lower_bound"] = by_obstacle.get(fcl_hit[0], 0.0)
    elif by_obstacle:
        name = max(by_obstacle, key=by_obstacle.get)
        report["obstacle"] = name
        report["depth_lower_bound"] = by_obstacle[name]
    report["depth_by_obstacle"] = by_obstacle
    return report


def _escape(cs: CSpace, checker: FclChecker, p: np.ndarray, reach: float) -> np.ndarray | None:
    """A point outside every primitive within ``reach`` of ``p`` whose segment from ``p``
    FCL accepts (for a ``p`` in tolerated contact), or ``None``."""
    directions = [s * e for e in np.eye(3) for s in (1.0, -1.0)]
    if cs.is_exact:
        # no facet planes to follow: a fan of directions (cube faces, edges and corners)
        fan = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)
                        if (x, y, z) != (0, 0, 0) and abs(x) + abs(y) + abs(z) > 1], float)
        directions += list(fan / np.linalg.norm(fan, axis=1)[:, None])
    else:
        for prim, _depth in cs.containing(p.tolist()):
            normals, offsets = cs.primitive_planes(prim)
            slack = offsets - normals @ p
            for k in np.argsort(slack, kind="stable")[:3]:
                directions.append(normals[k])
    candidates = []
    for d in directions:
        for length in reach * np.array([0.05, 0.1, 0.25, 0.5, 1.0]):
            candidates.append((length, tuple(d)))
    for length, d in sorted(candidates):
        q = p + length * np.asarray(d)
        if not cs.contains(q[None, :])[0] and checker.check_segment(p, q).valid:
            return q
    return None


def plan_octree(scenario: Scenario, *, params: OctreeParams | None = None, cache_dir=None,
                progress: bool | None = None, validate: bool = True) -> PlanOutcome:
    """Plan with minkplan's octree roadmap; see the module docstring.

    Args:
        scenario: the problem.
        params: :class:`OctreeParams` (defaults are scale-free).
        cache_dir: decomposition cache directory (default: ``planner.decompose``'s).
        progress: a status line on stderr (``None``: only on a TTY).
        validate: validate a found path with FCL and OMPL (a path that fails is never
            reported as found); ``False`` only for tests of the planner itself.

    Returns:
        :class:`~planner.planning.outcome.PlanOutcome`.
    """
    params = params or OctreeParams()
    t_start = time.perf_counter()
    settings = scenario.settings
    clock = _Clock()
    bar = _Progress(progress)
    start = np.asarray(scenario.start, dtype=np.float64)
    goal = np.asarray(scenario.goal, dtype=np.float64)
    delta = default_contact_tolerance(scenario, params)
    checker = FclChecker(scenario.robot.mesh, [b.mesh for b in scenario.obstacles],
                         contact_tolerance=delta, names=[b.name for b in scenario.obstacles],
                         solid=[b.solid for b in scenario.obstacles],
                         robot_solid=scenario.robot.solid)

    source, why = choose_source(scenario)
    robot_dec, obstacle_decs = None, None
    if source == "decomposition":
        bar.show("minkplan: decomposing")
        with clock.stage("decompose"):
            robot_dec, obstacle_decs = _decompositions(scenario, cache_dir, progress)
    # The time limit is for planning; a (cached) decomposition is preprocessing.
    deadline = time.perf_counter() + settings.time_limit
    problem = _Problem(scenario, params, robot_dec, obstacle_decs, clock)
    margin = settings.clearance + problem.deficit
    bar.show("minkplan: building the C-space")
    cs = problem.build(margin, clock)
    if source == "exact":
        decomposition = {"method": "none (exact boundary-convolution source)", "exact": True,
                         "excess": 0.0, "deficit": 0.0}
        triangles = {"robot": int(len(problem.robot_mesh[1])),
                     "obstacles": [int(len(f)) for _, f in problem.meshes]}
    else:
        decomposition = {
            "robot": _describe_decomposition(scenario.robot.name, robot_dec),
            "obstacles": [_describe_decomposition(b.name, d)
                          for b, d in zip(scenario.obstacles, obstacle_decs)],
            "exact": problem.exact,
            "excess": problem.excess,
            "deficit": problem.deficit,
        }
        triangles = None
    report: dict[str, Any] = {
        "scenario": scenario.describe(),
        "source": {"used": source, "why": why, "triangles": triangles},
        "decomposition": decomposition,
        "primitives": {"obstacle": cs.n_obstacle_prims, "walls": cs.n_primitives
                       - cs.n_obstacle_prims, "margin": margin},
        "contact_tolerance": delta,
        "resolution": {"coarse": cs.floor * 2**cs.coarse_level, "floor": cs.floor,
                       "floor_rel_diagonal": cs.floor / problem.diagonal},
    }
    rounds: list[dict] = []

    def finish(status: str, reason: str, message: str, *, waypoints=None, certificate=None,
               collision=None, validation=None, clearance=float("nan"),
               space: CSpace = cs) -> PlanOutcome:
        bar.close()
        counts = space.level_counts()
        report["cells"] = _cell_report(counts, space.floor)
        with clock.stage("graph"):
            nodes, edges = space.roadmap_size()
        report["graph"] = {"nodes": nodes, "edges": edges}
        report["refinement"] = {"rounds": len(rounds), "history": rounds}
        wp = np.zeros((0, 3)) if waypoints is None else np.asarray(waypoints, dtype=np.float64)
        length = float(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum()) if len(wp) else math.nan
        timings = dict(clock.seconds)
        timings["cspace"] = sum(timings.get(k, 0.0) for k in ("octree", "refine"))
        timings["total"] = time.perf_counter() - t_start
        outcome = PlanOutcome(
            status=status, waypoints=wp, length=length, clearance=clearance, timings=timings,
            validation=validation or {"fcl": {}, "ompl": {}}, message=message, reason=reason,
            planner="minkplan", certificate=certificate, collision=collision, report=report,
            cspace=cs)
        log.info("%s: %s (%s) in %.2f s", scenario.name, status, message, timings["total"])
        return outcome

    # ---- start and goal
    ends = {"start": start, "goal": goal}
    for which, p in list(ends.items()):
        if not cs.contains(p[None, :])[0]:
            continue
        escaped = None
        if checker.is_valid(p):  # tolerated contact, or within the margin: step out
            escaped = _escape(cs, checker, p, params.escape_rel * max(delta, margin))
        if escaped is None:
            collision = _point_report(problem, cs, checker, p, which)
            if checker.is_valid(p):
                message = (f"the {which} is within the clearance margin of "
                           f"{collision.get('obstacle')} and no short escape was found")
                return finish(NOT_FOUND, f"{which}_in_margin", message, collision=collision)
            depth = collision.get("depth_upper_bound", collision.get("depth_lower_bound"))
            message = (f"the {which} is in collision with {collision.get('obstacle')} "
                       f"(depth about {depth:.4g})")
            return finish(NO_PATH, f"{which}_in_collision", message, collision=collision)
        ends[which] = escaped
        report[f"{which}_escape"] = {"from": p.tolist(), "to": escaped.tolist()}

    bar.show("minkplan: searching")
    result = _search(problem, cs, ends["start"], ends["goal"], clock, rounds, deadline, bar)
    space = cs
    if result.status == NO_PATH and margin > 0:
        # The certificate must speak of the obstacles themselves, not of the margin.
        log.info("no path with margin %.3g; checking without the margin", margin)
        space = problem.build(0.0, clock)
        second = _search(problem, space, ends["start"], ends["goal"], clock, rounds,
                         deadline, bar)
        if second.status == FOUND:
            result = _SearchResult(
                NOT_FOUND, "clearance",
                f"no path keeps the clearance margin {margin:.4g}; paths with less exist")
        else:
            result = second

    if result.status == NO_PATH:
        certificate = _certificate(problem, space, result.certificate, ends)
        kind = ("exact" if certificate["exact"] else
                "relative to the convex hulls of the approximate decomposition")
        message = (f"no path: the {certificate['walled']} is walled off by "
                   f"{certificate['wall_cells']} FULL cells ({kind})")
        return finish(NO_PATH, "certificate", message, certificate=certificate, space=space)
    if result.status != FOUND:
        report["resolution"]["reached"] = _smallest_cell(space)
        return finish(result.status, result.reason, result.message, space=space)

    # ---- path: attach escapes, shortcut, validate
    raw = np.asarray(result.waypoints, dtype=np.float64)
    d_ends = space.signed_distance(np.stack([ends["start"], ends["goal"]]))
    shortcut_margin = 0.25 * min(result.min_leaf_size, 2.0 * float(d_ends.min()))
    with clock.stage("shortcut"):
        short = space.shortcut(raw, margin=max(shortcut_margin, 0.0),
                               passes=params.shortcut_passes) if settings.simplify else raw
    report["resolution"]["reached"] = result.min_leaf_size
    report["path"] = {"roadmap_waypoints": len(raw), "waypoints": len(short),
                      "roadmap_length": float(np.linalg.norm(np.diff(raw, axis=0), axis=1).sum()),
                      "shortcut_margin": shortcut_margin}

    def with_escapes(path: np.ndarray) -> np.ndarray:
        parts = []
        if "start_escape" in report:
            parts.append(start[None, :])
        parts.append(path)
        if "goal_escape" in report:
            parts.append(goal[None, :])
        return np.vstack(parts)

    candidates = [with_escapes(short)]
    if len(short) != len(raw) or not np.array_equal(short, raw):
        candidates.append(with_escapes(raw))
    if not validate:
        return finish(FOUND, "path", result.message, waypoints=candidates[0])
    failures = []
    for path in candidates:
        with clock.stage("validate"):
            validation = validate_path(path, checker, problem.bounds)
        if validation["fcl"]["valid"] and validation["ompl"]["valid"]:
            return finish(FOUND, "path", result.message, waypoints=path, validation=validation,
                          clearance=validation["fcl"]["min_clearance"])
        failures.append(validation)
    message = ("the path failed validation on the original meshes "
               f"(fcl: {failures[0]['fcl'].get('detail', '')}; "
               f"ompl valid: {failures[0]['ompl'].get('valid')})")
    return finish(NOT_FOUND, "validation_failed", message, validation=failures[0])


def _smallest_cell(cs: CSpace) -> float:
    counts = cs.level_counts()
    for level, c in enumerate(counts):
        if c[2] > 0:
            return cs.floor * 2**level
    return cs.floor * 2**cs.coarse_level


def _cell_report(counts: list, floor: float) -> dict[str, Any]:
    per_level = []
    totals = Counter()
    for level, c in enumerate(counts):
        if sum(c) == 0:
            continue
        entry = {"level": level, "size": floor * 2**level}
        for name, n in zip(LABELS, c):
            entry[name] = int(n)
            totals[name] += int(n)
        per_level.append(entry)
    return {"total": dict(totals), "leaves": int(sum(totals.values())), "per_level": per_level}


def _certificate(problem: _Problem, cs: CSpace, raw: dict[str, Any],
                 ends: dict[str, np.ndarray]) -> dict[str, Any]:
    """The certificate as stored in reports: summary, the walled-off component and its
    wall cells with primitives and obstacles."""
    prims = np.asarray(raw["wall_prims"], dtype=np.int64)
    boxes = np.asarray(raw["wall_boxes"], dtype=np.float64)
    leaves = np.asarray(raw["wall_leaves"], dtype=np.int64)
    obstacles = [problem.obstacle_of(int(p), cs.n_obstacle_prims) for p in prims]
    walled = "start" if raw["walls_around_start"] else "goal"
    component = [int(i) for i in raw["component_leaves"]]
    comp_boxes = np.array([cs.cell_box(i) for i in component]).reshape(-1, 2, 3)
    volume = float(np.prod(comp_boxes[:, 1] - comp_boxes[:, 0], axis=1).sum())
    exact = problem.exact
    if problem.source == "exact":
        relative_to = "the meshes as given (exact boundary-convolution source)"
    elif exact:
        relative_to = "the obstacles (exact convex decomposition)"
    else:
        relative_to = None
    return {
        "exact": exact,
        "source": problem.source,
        "relative_to": (relative_to if relative_to else
                        f"the convex hulls of CoACD's decomposition (excess about "
                        f"{problem.excess:.3g})"),
        "walled": walled,
        "walled_point": ends[walled].tolist(),
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
            {"leaf": int(leaf), "box": box.tolist(), "primitive": int(p), "obstacle": name}
            for leaf, box, p, name in zip(leaves, boxes, prims, obstacles)
        ],
        "component": {"leaves": component, "boxes": comp_boxes.tolist()},
    }
