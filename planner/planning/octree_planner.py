"""minkplan's own planner, in OMPL's roles: an octree roadmap of the Minkowski-sum C-space.

:class:`OctreePlanner` has ``setup()`` and ``solve()``, as OMPL's planners do:

1. ``setup``: the C-obstacle source (:func:`planner.sources.choose`, unless one is given),
   the FCL checker of the validation, and the native C-space: the source's C-obstacles
   grown by the requested clearance plus the decompositions' measured deficit, walls
   filling everything outside the bounds, and an octree with cells of 1/64 of the
   bounds' largest side whose lattice reaches a floor of ``floor_rel`` times the bounds'
   diagonal (or ``planner.resolution``). EMPTY leaves are exactly free, FULL leaves
   exactly blocked, MIXED leaves undecided.
   For large problems the straight motion from start to goal is tested exactly first
   (:mod:`.direct`): free, it is the answer once validated, and no C-space is built;
   an end in collision (FCL) is the answer too.
   For large triangle soups a local proof comes next (:mod:`.local_proof`): an end
   walled off in a box around it is a proved no-path, and no C-space over the bounds is
   built.
2. ``solve``: start and goal (:mod:`.endpoints`: in collision is an answer, a tolerated
   contact is stepped out of); the refinement rounds (:mod:`.search`), searched again
   without the margin when they prove no path with it; then a found path is shortcut by
   exact segment tests and validated on the original meshes by FCL and OMPL (a path that
   fails either is never reported as found), and a no-path becomes a certificate
   (:mod:`.certificates`).

Everything is deterministic: no random choice is made after the decomposition (whose
CoACD seed is ``planner.seed``). ``planner.time_limit`` bounds the refinement rounds; the
decomposition (cached on disk) is preprocessing and does not count against it.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner import budget
from planner.deadline import Deadline, native_deadline
from planner.errors import ResourceLimitError, TimeLimitError
from planner.problem import Scenario
from planner.progress import StatusLine
from planner.roles import FOUND, NO_PATH, NOT_FOUND, PlanStatus
from planner.sources import Source, choose_for
from planner.validation import FclChecker

from .certificates import certificate_document
from .direct import Direct, direct_motion, triangle_pairs
from .endpoints import Ends, attach_ends
from .local_proof import LocalProof, prove_end_enclosed, surface_pairs
from .outcome import PlanOutcome
from .report import Clock, cell_report, smallest_mixed_cell
from .search import SearchResult, SearchRun, search, search_without_margin
from .validate import validate_path

__all__ = ["WALL", "OctreeParams", "OctreePlanner", "default_contact_tolerance"]

log = logging.getLogger(__name__)

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
        max_leaves: leaf budget of the octree (``None``: from the memory limit,
            :func:`planner.budget.leaves`).
        max_rounds: refinement rounds at most.
        shortcut_passes: greedy shortcutting passes.
        escape_rel: longest escape from a tolerated contact, in contact tolerances.
        local_first_pairs: with at least this many triangle pairs involving a surface
            (:func:`.local_proof.surface_pairs`), a local no-path proof at the start, then
            at the goal, is tried before the C-space over the whole bounds is built
            (:mod:`.local_proof`).
        direct_first_pairs: with at least this many triangle pairs in all
            (:func:`.direct.triangle_pairs`), the straight motion from start to goal is
            tested exactly first (:mod:`.direct`); when it is free and validates, no
            C-space is built.
    """

    coarse_divisions: int = 64
    floor_rel: float = 1e-5
    contact_rel: float = 1e-6
    mixed_penalty: float = 2.0
    refine_levels: int = 1
    ring: bool = True
    attach_rings: int = 2
    max_leaves: int | None = None
    max_rounds: int = 400
    shortcut_passes: int = 3
    escape_rel: float = 2.0
    local_first_pairs: int = 5_000_000
    direct_first_pairs: int = 5_000_000

    @property
    def leaves_setting(self) -> str | None:
        """The setting that gave the leaf budget, for refusals (``None``: the memory
        limit did)."""
        return None if self.max_leaves is None else "OctreeParams.max_leaves"


def default_contact_tolerance(scenario: Scenario, params: OctreeParams | None = None) -> float:
    """``planner.contact_tolerance``, or ``contact_rel`` times the scene's scale (the
    diagonal of the bounds)."""
    if scenario.settings.contact_tolerance is not None:
        return float(scenario.settings.contact_tolerance)
    params = params or OctreeParams()
    lo, hi = scenario.bounds
    return params.contact_rel * float(np.linalg.norm(hi - lo))


class OctreePlanner:
    """The octree planner of one scenario (see the module documentation).

    Args:
        scenario: the problem.
        params: :class:`OctreeParams` (defaults are scale-free).
        source: the C-obstacle source; default :func:`planner.sources.choose` with the
            scenario's settings.
        cache_dir: decomposition cache directory (default: :mod:`planner.decompose`'s).
        progress: a status line on stderr (``None``: only on a TTY).
        validate: validate a found path with FCL and OMPL (a path that fails is never
            reported as found); ``False`` only for tests of the planner itself.

    Thread safety: one :meth:`solve` at a time per instance.
    """

    name = "minkplan"

    def __init__(self, scenario: Scenario, *, params: OctreeParams | None = None,
                 source: Source | None = None, cache_dir=None, progress: bool | None = None,
                 validate: bool = True) -> None:
        self.scenario = scenario
        self.params = params or OctreeParams()
        self.source = source
        self.cache_dir = cache_dir
        self.validate = validate
        self.clock = Clock()
        self.bar = StatusLine(progress)
        self.report: dict[str, Any] = {}
        self.rounds: list[dict] = []
        self.cspace: Any = None
        self.direct: Direct | None = None
        self.local: LocalProof | None = None
        self._ready = False
        self.out_of_time = ""  # where the time limit was reached ("": it was not)

    # ---------------------------------------------------------------- setup

    def setup(self) -> None:
        """Choose the source, build the FCL checker and the C-space (with the margin)."""
        try:
            self._setup()
        finally:
            self.bar.close()

    def _setup(self) -> None:
        sc, params = self.scenario, self.params
        self.t_start = time.perf_counter()
        self.delta = default_contact_tolerance(sc, params)
        self.checker = FclChecker.for_parts(sc.robot, sc.obstacles, contact_tolerance=self.delta)
        if self.source is None:
            self.source = choose_for([sc.robot, *sc.obstacles], sc.settings,
                                     cache_dir=self.cache_dir, progress=self.bar.enabled)
        if self._src.kind == "decomposition":
            self.bar.show("minkplan: decomposing")
            with self.clock.stage("decompose"):
                self.margin = sc.settings.clearance + self._src.margin_deficit(self._parts)
        else:
            self.margin = sc.settings.clearance
        # the time limit bounds the planning from here (not the decomposition)
        self.deadline = Deadline(time.perf_counter() + sc.settings.time_limit)
        lo, hi = sc.bounds
        self.bounds = np.stack([lo, hi])
        diagonal = float(np.linalg.norm(hi - lo))
        resolution = sc.settings.resolution
        self.floor_asked = float(resolution) if resolution else params.floor_rel * diagonal
        self.coarse = max(float(np.max(hi - lo)) / params.coarse_divisions, self.floor_asked)
        self.diagonal = diagonal
        self.owner = self._src.owners(sc.obstacles, sc.robot)
        self._ready = True
        self.direct = self._direct()
        if self.direct is None:  # nothing found: the C-space decides
            self._build_space()

    def _build_space(self) -> None:
        """The local proof, else the C-space over the whole bounds; the report's head."""
        self.local = self._local_proof()
        if self.local is not None:
            self.cspace = self.local.cspace
        elif self.out_of_time:
            self._direct_head()  # the time limit went on the local proofs: no C-space
            return
        else:
            self.bar.show("minkplan: building the C-space")
            try:
                with self.deadline.native():
                    self.cspace = self._build(self.margin)
            except TimeLimitError:
                self.deadline.reached = True
                self.out_of_time = "while the C-space over the whole bounds was built"
                self._direct_head()
                return
        self._report_head()

    def _direct(self) -> Direct | None:
        """What the direct test of a large problem found (:mod:`.direct`): ``None`` when
        it was not tried or found neither a free motion nor an end in collision."""
        sc = self.scenario
        if triangle_pairs(sc) < self.params.direct_first_pairs:
            return None
        self.bar.show("minkplan: testing the straight motion")
        t0 = time.perf_counter()  # not a stage of its own: timings keep their keys
        direct = direct_motion(sc, self._src, self.checker,
                               reach=self.params.escape_rel * max(self.delta, self.margin),
                               margin=sc.settings.clearance)
        self.report["direct"] = {"free": direct.motion is not None,
                                 "seconds": time.perf_counter() - t0}
        return direct if direct.motion is not None or direct.in_collision else None

    def _local_proof(self) -> LocalProof | None:
        """A proof that the start (or goal) is walled off near it, tried for large
        triangle soups on the exact source without a margin (see :mod:`.local_proof`).
        A proof that runs out of memory is the answer (a :class:`ResourceLimitError`,
        see :mod:`.local_proof` for why the whole bounds are not tried then)."""
        sc = self.scenario
        if (self._src.kind != "exact" or self.margin > 0
                or surface_pairs(sc) < self.params.local_first_pairs):
            return None
        deadline = self.deadline
        attempts: list[dict[str, Any]] = []
        self.report["local_proof"] = {"proved": False, "attempts": attempts}
        for which in ("start", "goal"):
            if deadline.would_pass():
                attempts.append({"end": which, "outcome": "not started: the time limit "
                                                          "passed", "seconds": 0.0})
                break
            self.bar.show(f"minkplan: a local proof at the {which}")
            try:
                with self.clock.stage("octree"):
                    proof = prove_end_enclosed(sc, self._src, self.checker, which,
                                               deadline=deadline, attempts=attempts)
            except ResourceLimitError as exc:
                raise self._refusal(exc, f"the local proof at the {which}") from exc
            if proof is not None:
                self.report["local_proof"] = {"proved": True, **proof.summary,
                                              "attempts": attempts}
                return proof
        if deadline.reached or deadline.would_pass():
            self.out_of_time = "in the local proofs (no C-space over the whole bounds was built)"
        return None

    @property
    def _src(self) -> Source:
        assert self.source is not None, "setup() chooses the source"
        return self.source

    @property
    def _parts(self) -> list:
        return [*self.scenario.obstacles, self.scenario.robot]

    def _build(self, margin: float):
        sc = self.scenario
        try:
            with self.clock.stage("octree"):
                return self._src.cspace(sc.obstacles, sc.robot, self.bounds, self.floor_asked,
                                        self.coarse, margin=margin,
                                        max_leaves=self.params.max_leaves)
        except ResourceLimitError as exc:
            raise self._refusal(exc, "the C-space") from exc

    def _refusal(self, exc: ResourceLimitError, what: str) -> ResourceLimitError:
        """The core's refusal of ``what`` as the user reads it (:func:`budget.explain`)."""
        sc = self.scenario
        blocked = self.report.get("direct", {}).get("free") is False
        after = ", built after the straight motion was found blocked" if blocked else ""
        where = str(sc.path) if sc.path is not None else sc.name
        names = [f"{o.name} ⊕ −{sc.robot.name}" for o in sc.obstacles]
        return budget.explain(exc, f"{where}: {what} ({self._src.kind} source){after}", names,
                              cell_bytes=budget.LEAF_BYTES, knob="planner.resolution",
                              cells_given=self.params.leaves_setting)

    def _report_head(self) -> None:
        cs, sc = self.cspace, self.scenario
        described = self._src.describe(sc.obstacles, sc.robot)
        decomposition = described.pop("decomposition")
        self.report.update({
            "scenario": sc.describe(),
            "source": described,
            "decomposition": decomposition,
            "primitives": {"obstacle": cs.n_obstacle_prims,
                           "walls": cs.n_primitives - cs.n_obstacle_prims,
                           "margin": self.margin},
            "contact_tolerance": self.delta,
            "resolution": {"coarse": cs.floor * 2**cs.coarse_level, "floor": cs.floor,
                           "floor_rel_diagonal": cs.floor / self.diagonal},
        })

    def obstacle_of(self, prim: int) -> str:
        """The obstacle (or ``"bounds"``) a primitive of the C-space belongs to."""
        if prim < 0:
            return "unknown"
        if prim >= self.cspace.n_obstacle_prims:
            return WALL
        return self.scenario.obstacles[int(self.owner[prim])].name

    # ---------------------------------------------------------------- solve

    def solve(self) -> PlanOutcome:
        """Plan from the scenario's start to its goal within ``planner.time_limit``."""
        if not self._ready:
            self.setup()
        try:
            return self._solve()
        finally:
            self.bar.close()

    def _solve(self) -> PlanOutcome:
        if self.direct is not None:
            direct, self.direct = self.direct, None
            if direct.in_collision is not None:
                return self._direct_in_collision(direct.in_collision)
            assert direct.motion is not None
            found = self._direct_found(direct.motion)
            if found is not None:
                return found
            self._build_space()
        if self.local is not None:
            return self._local_no_path(self.local)
        if self.out_of_time:
            return self._finish(NOT_FOUND, "time_limit",
                                f"time limit reached {self.out_of_time}")
        sc = self.scenario
        deadline = self.deadline.at
        start = np.asarray(sc.start, dtype=np.float64)
        goal = np.asarray(sc.goal, dtype=np.float64)
        reach = self.params.escape_rel * max(self.delta, self.margin)
        ends = attach_ends(self.cspace, self.checker, start, goal, reach, self.obstacle_of)
        if ends.blocked is not None:
            return self._blocked(ends)
        for which, escape in ends.escapes.items():
            self.report[f"{which}_escape"] = escape
        self.bar.show("minkplan: searching")
        run = SearchRun(self.params, self.clock, self.rounds, deadline, self.bar)
        try:
            with native_deadline(deadline):
                first = search(self.cspace, ends.points["start"], ends.points["goal"], run)
                result, space = search_without_margin(self._build, first, self.margin,
                                                      ends.points, run)
        except TimeLimitError as exc:
            return self._finish(NOT_FOUND, "time_limit",
                                f"{exc} after {len(self.rounds)} refinement rounds")
        space = space if space is not None else self.cspace
        if result.status == NO_PATH:
            return self._no_path(result, space, ends)
        if result.status != FOUND:
            self.report["resolution"]["reached"] = smallest_mixed_cell(space)
            return self._finish(result.status, result.reason, result.message, space=space)
        return self._found(result, space, ends)

    def _blocked(self, ends: Ends) -> PlanOutcome:
        """A start or goal in collision (no path) or within the margin (nothing found)."""
        assert ends.blocked is not None
        which, collision, in_margin = ends.blocked
        obstacle = collision.get("obstacle")
        if in_margin:
            return self._finish(NOT_FOUND, f"{which}_in_margin",
                                f"the {which} is within the clearance margin of {obstacle} "
                                f"and no short escape was found", collision=collision)
        depth = collision.get("depth_upper_bound", collision.get("depth_lower_bound"))
        return self._finish(NO_PATH, f"{which}_in_collision",
                            f"the {which} is in collision with {obstacle} (depth about "
                            f"{depth:.4g})", collision=collision)

    def _no_path(self, result: SearchResult, space, ends: Ends) -> PlanOutcome:
        assert result.certificate is not None
        source = self._src
        exact = source.exact and space.margin == 0
        certificate = certificate_document(
            space, result.certificate, ends.points, exact=exact, source_kind=source.kind,
            relative_to=source.relative_to(self._parts), obstacle_of=self.obstacle_of,
            scenario=self.scenario)
        kind = ("exact" if certificate["exact"] else
                "relative to the convex hulls of the approximate decomposition")
        message = (f"no path: the {certificate['walled']} is walled off by "
                   f"{certificate['wall_cells']} FULL cells ({kind})")
        return self._finish(NO_PATH, "certificate", message, certificate=certificate,
                            space=space)

    def _local_no_path(self, proof: LocalProof) -> PlanOutcome:
        """The no-path of a local proof: its certificate, over the box around the end."""
        raw = dict(proof.raw)
        if proof.which == "goal":
            raw.update(walls_around_start=False, start_component_size=0,
                       goal_component_size=raw["start_component_size"])
        points = {"start": np.asarray(self.scenario.start, dtype=np.float64),
                  "goal": np.asarray(self.scenario.goal, dtype=np.float64)}
        source = self._src
        certificate = certificate_document(
            proof.cspace, raw, points, exact=source.exact, source_kind=source.kind,
            relative_to=source.relative_to(self._parts), obstacle_of=self.obstacle_of,
            scenario=self.scenario)
        certificate["local"] = proof.summary
        beyond = certificate["wall_cells_by_obstacle"].get(WALL, 0)
        of_bounds = f", {beyond} of them beyond the bounds" if beyond else ""
        message = (f"no path: the {proof.which} is walled off by "
                   f"{certificate['wall_cells']} FULL cells (exact{of_bounds}) in a box "
                   "around it")
        return self._finish(NO_PATH, "certificate", message, certificate=certificate,
                            space=proof.cspace)

    def _direct_head(self) -> None:
        """The report's head when no C-space was built (direct answers, time out)."""
        described = self._src.describe(self.scenario.obstacles, self.scenario.robot)
        described.pop("decomposition")
        self.report.update({"scenario": self.scenario.describe(), "source": described,
                            "contact_tolerance": self.delta})

    def _direct_in_collision(self, which: str) -> PlanOutcome:
        """An end in collision found by the direct test: the answer, from FCL alone (the
        C-space's depth, a lower bound, is not computed)."""
        self._direct_head()
        p = np.asarray(getattr(self.scenario, which), dtype=np.float64)
        collision: dict[str, Any] = {"which": which, "position": p.tolist()}
        hit = self.checker.colliding_obstacle(p)
        if hit is not None:
            collision.update(obstacle=hit[0], depth_upper_bound=hit[1])
        depth = collision.get("depth_upper_bound", math.nan)
        return self._finish(NO_PATH, f"{which}_in_collision",
                            f"the {which} is in collision with "
                            f"{collision.get('obstacle', 'an obstacle')} (depth about "
                            f"{depth:.4g})", collision=collision)

    def _direct_found(self, motion: np.ndarray) -> PlanOutcome | None:
        """The straight motion, validated by FCL and OMPL; ``None`` when it fails (the
        C-space is built then, as without it)."""
        self._direct_head()
        message = "the straight motion is free (exact segment test, no C-space built)"
        if not self.validate:
            return self._finish(FOUND, "direct", message, waypoints=motion)
        self.bar.show("minkplan: validating the path (FCL, OMPL)")
        with self.clock.stage("validate"):
            validation = validate_path(motion, self.checker, self.bounds)
        self.report["direct"]["validation"] = {"valid": validation["valid"]}
        if not validation["valid"]:
            log.info("%s: the straight motion failed validation; building the C-space",
                     self.scenario.name)
            return None
        return self._finish(FOUND, "direct", message, waypoints=motion,
                            validation=validation,
                            clearance=validation["fcl"]["min_clearance"])

    def _found(self, result: SearchResult, space, ends: Ends) -> PlanOutcome:
        """Shortcut, put the escapes back, validate; the first candidate that passes."""
        candidates = self._candidates(result, space, ends)
        if not self.validate:
            return self._finish(FOUND, "path", result.message, waypoints=candidates[0],
                                space=space)
        failures = []
        self.bar.show("minkplan: validating the path (FCL, OMPL)")
        for path in candidates:
            with self.clock.stage("validate"):
                validation = validate_path(path, self.checker, self.bounds)
            if validation["valid"]:
                return self._finish(FOUND, "path", result.message, waypoints=path,
                                    validation=validation, space=space,
                                    clearance=validation["fcl"]["min_clearance"])
            failures.append(validation)
        message = ("the path failed validation on the original meshes "
                   f"(fcl: {failures[0]['fcl'].get('detail', '')}; "
                   f"ompl valid: {failures[0]['ompl'].get('valid')})")
        return self._finish(NOT_FOUND, "validation_failed", message, validation=failures[0],
                            space=space)

    def _candidates(self, result: SearchResult, space, ends: Ends) -> list[np.ndarray]:
        """The shortcut path, then the roadmap path, each with the escapes at its ends."""
        raw = np.asarray(result.waypoints, dtype=np.float64)
        d_ends = space.signed_distance(np.stack([ends.points["start"], ends.points["goal"]]))
        shortcut_margin = 0.25 * min(result.min_leaf_size, 2.0 * float(d_ends.min()))
        with self.clock.stage("shortcut"):
            short = (space.shortcut(raw, margin=max(shortcut_margin, 0.0),
                                    passes=self.params.shortcut_passes)
                     if self.scenario.settings.simplify else raw)
        self.report["resolution"]["reached"] = result.min_leaf_size
        self.report["path"] = {
            "roadmap_waypoints": len(raw), "waypoints": len(short),
            "roadmap_length": float(np.linalg.norm(np.diff(raw, axis=0), axis=1).sum()),
            "shortcut_margin": shortcut_margin}

        def with_escapes(path: np.ndarray) -> np.ndarray:
            start = [np.asarray(self.scenario.start)[None]] if "start" in ends.escapes else []
            goal = [np.asarray(self.scenario.goal)[None]] if "goal" in ends.escapes else []
            return np.vstack([*start, path, *goal])

        candidates = [with_escapes(short)]
        if len(short) != len(raw) or not np.array_equal(short, raw):
            candidates.append(with_escapes(raw))
        return candidates

    def _finish(self, status: PlanStatus, reason: str, message: str, *, space=None,
                waypoints=None, certificate=None, collision=None, validation=None,
                clearance: float = float("nan")) -> PlanOutcome:
        """The outcome, with the octree's cells, graph and refinement in the report."""
        self.bar.close()
        space = self.cspace if space is None else space
        if space is not None:
            self.report["cells"] = cell_report(space.level_counts(), space.floor)
            with self.clock.stage("graph"):
                nodes, edges = space.roadmap_size()
            self.report["graph"] = {"nodes": nodes, "edges": edges}
        self.report["refinement"] = {"rounds": len(self.rounds), "history": self.rounds}
        wp = np.zeros((0, 3)) if waypoints is None else np.asarray(waypoints, dtype=np.float64)
        length = float(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum()) if len(wp) else math.nan
        timings = dict(self.clock.seconds)
        timings["cspace"] = sum(timings.get(k, 0.0) for k in ("octree", "refine"))
        timings["total"] = time.perf_counter() - self.t_start
        log.info("%s: %s (%s) in %.2f s", self.scenario.name, status, message, timings["total"])
        return PlanOutcome(
            status=status, waypoints=wp, length=length, clearance=clearance, timings=timings,
            validation=validation or {"fcl": {}, "ompl": {}}, message=message, reason=reason,
            planner=self.name, certificate=certificate, collision=collision,
            report=self.report, cspace=space, source=self.source)
