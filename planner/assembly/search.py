"""The disassembly search: which part (or which group) can leave, along which path, one
step at a time; the reverse is an assembly order.

Search: while movable parts remain, find one that can translate from its assembled pose
to outside the remaining parts' bounding box (its own included) grown by a margin, with
the other remaining parts as obstacles. Cheap first: straight removals along ``±x, ±y,
±z`` (shortest exit first), then along the escape directions of FCL's contact normals at
the assembled pose. Whether part ``j`` alone blocks such a line for part ``i`` depends on
the pair only, so it is decided once per (part, obstacle, direction) by the
:class:`~planner.assembly.pairs.PairCache` -- from the pair's C-obstacle, built once per
pair from the assembly's source and reused in every step, or by FCL on the two parts
when the line only slides along touching faces -- and a line no present part blocks is
then checked with all of them by FCL. Then, for each part in turn, the octree planner
(:func:`planner.planning.plan`, on the same source) on a
:class:`~planner.problem.Scenario` whose robot is the part (start ``0``) and whose goal
lies outside that box on one of its six sides, the most open first (the shallowest block
of the straight line); the region outside the box is connected, so the first path found,
or a certificate walling off the start, settles it. When no part can leave alone, a group
may: along each axis, the parts that block a part, the parts that block those, and so on
(the directional blocking graph of Wilson and Latombe's non-directional blocking graph)
form a group no other part blocks; if FCL agrees, it leaves as one rigid body (a
subassembly) and is taken apart on its own afterwards. When nothing can leave, or a group
that left cannot be taken apart, the stuck parts are shrunk to an irreducible interlocked
set by greedy deletion (each part left out in turn, the search re-run on the rest), which
is what the result reports.

Contact: assembled parts touch face to face. One contact tolerance ``delta`` (the file's
``contact_tolerance``, else :data:`~planner.problem.DEFAULT_CONTACT_REL` times the
assembly's diagonal) is used by the straight-line checks, the planner
(``planner.contact_tolerance``) and the final FCL validation of every reported path. An
interference tolerance the user states (``interference``: parts that overlap a little in
the assembled pose) is added to it everywhere (:attr:`Assembly.tolerance`): a penetration
up to it counts as contact.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.blas import single_blas_thread
from planner.errors import InvalidParameterError, MinkplanError, ResourceLimitError, ScenarioError
from planner.problem import Assembly, Part, Scenario
from planner.progress import StatusLine
from planner.roles import FOUND, NO_PATH
from planner.validation import FclChecker

from .enclosure import HALF_SIZES_REL, prove_enclosed
from .geometry import (
    DIRECTIONS,
    ESCAPE_MARGIN_REL,
    direction_vector,
    exit_box,
    exit_point,
    vector_name,
)
from .model import INTERLOCKED, SEQUENCE, AssemblyResult, AssemblyStep, group_label
from .pairs import PairCache

__all__ = ["GOAL_SIDE", "plan_assembly", "removal_problems", "removal_scenario",
           "validate_removal"]

log = logging.getLogger(__name__)


def validate_removal(part: Part, others: list[Part], path: np.ndarray, delta: float) -> dict:
    """FCL's check of a removal path with ``others`` present, allowing a penetration of
    ``delta`` (the contact tolerance, plus the interference tolerance if one was given;
    reported as ``tolerance``, as ``sequence.json`` names that sum)."""
    checker = FclChecker.for_parts(part, others, contact_tolerance=delta)
    check = checker.check_path(path)
    return {"valid": bool(check.valid), "min_clearance": check.min_clearance,
            "n_checks": check.n_checks, "tolerance": delta, "obstacle": check.obstacle}


def _planner_validation(outcome, delta: float) -> dict | None:
    """The planner's own FCL check of the path it returned (the same part, obstacles and
    tolerance as :func:`validate_removal`'s), in that form; ``None`` when it has none
    that passed at ``delta`` (then the path is checked again)."""
    fcl = (outcome.validation or {}).get("fcl") or {}
    if not (fcl.get("valid") is True and fcl.get("contact_tolerance") == delta):
        return None
    return {"valid": True, "min_clearance": fcl["min_clearance"], "n_checks": fcl["checks"],
            "tolerance": delta, "obstacle": None, "by": "planner"}


GOAL_SIDE = "+z"
"""Default side of the exit box for :func:`removal_scenario`'s goal."""


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
    lo, hi = exit_box(body, others, margin)
    _, vec = direction_vector(direction)
    goal = exit_point(vec, (lo, hi), margin)
    return Scenario(name=f"{assembly.name}: remove {part}", units=assembly.units,
                    robot=body, obstacles=others,
                    start=np.zeros(3), goal=goal, orientation=np.eye(3),
                    bounds=(lo - margin, hi + margin), settings=assembly.settings)


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
                 plan_parts: bool, groups: bool = True, enclosures: bool = True) -> None:
        self.assembly = assembly
        self.parts = {p.name: p for p in assembly.parts}
        self.order = [p.name for p in assembly.parts]
        self.planner = planner
        self.cache_dir = cache_dir
        self.progress = progress
        self.plan_parts = plan_parts
        self.groups = groups
        self.delta = assembly.tolerance
        self.margin = ESCAPE_MARGIN_REL * assembly.diagonal
        self.pairs = PairCache(assembly, cache_dir)
        self.source = self.pairs.source
        self._straight: dict[tuple[str, frozenset], AssemblyStep | None] = {}
        self._planned: dict[tuple[str, frozenset], tuple[AssemblyStep | None, dict]] = {}
        self.enclosures = enclosures
        self.stats = {"planner_runs": 0, "planner_reused": 0, "runs": 0,
                      "enclosures_tried": 0, "enclosures_proved": 0}
        self.line = StatusLine(progress)

    # ---------------------------------------------------------------- one part

    def straight(self, part: str, others: list[str]) -> AssemblyStep | None:
        """A straight removal of ``part`` with ``others`` present, or ``None``."""
        key = (part, frozenset(others))
        if key in self._straight:
            return self._straight[key]
        t0 = time.perf_counter()
        body = self.parts[part]
        bodies = [self.parts[n] for n in others]
        box = exit_box(body, bodies, self.margin)
        # Shortest exits first (less sliding along touching faces, slow to certify);
        # then the escape directions of the contact normals.
        goals = sorted(((float(np.linalg.norm(exit_point(d, box, self.margin))), i, name, d)
                        for i, (name, d) in enumerate(DIRECTIONS.items())),
                       key=lambda item: item[:2])
        seen: list[np.ndarray] = []
        for other in others:
            for d in self.pairs.contact_directions(part, other):
                if not any(float(np.dot(d, u)) > 1.0 - 1e-6 for u in seen):
                    seen.append(d)
                    goals.append((0.0, 0, vector_name(d), d))
        step = None
        for _, _, dname, vec in goals:
            # cheap first: a part that blocks the line alone (its primitives decide, or
            # FCL did in an earlier step); grazing pairs not decided yet give None
            verdicts = [self.pairs.verdict(part, o, dname, vec, fcl=False) for o in others]
            if any(v is not None and v.blocked for v in verdicts):
                continue
            grazing = [o for o, v in zip(others, verdicts) if v is None]
            # then the whole motion, with every part present (FCL)
            path = np.array([np.zeros(3), exit_point(vec, box, self.margin)])
            validation = validate_removal(body, bodies, path, self.delta)
            if validation["valid"]:
                step = AssemblyStep(part, "straight", dname, path, list(others),
                                    time.perf_counter() - t0, validation)
                break
            # blocked: find out which grazing parts block it alone, once, for later steps
            if others == grazing and len(others) == 1:  # that was the pair alone
                self.pairs.record_blocked(part, others[0], dname, vec)
            else:
                for o in grazing:
                    self.pairs.verdict(part, o, dname, vec)
        self._straight[key] = step
        return step

    def goal_sides(self, part: str, others: list[str]) -> list[str]:
        """The six axis sides, most open first: by the longest sideways detour the
        straight line would need around a present part (:meth:`PairCache.detour`), then
        by the distance to the exit."""
        body = self.parts[part]
        box = exit_box(body, [self.parts[n] for n in others], self.margin)
        keys = []
        for i, (dname, vec) in enumerate(DIRECTIONS.items()):
            detour = max((self.pairs.detour(part, other, dname, vec) for other in others),
                         default=0.0)
            keys.append((round(detour, 12),
                         float(np.linalg.norm(exit_point(vec, box, self.margin))), i, dname))
        return [k[-1] for k in sorted(keys)]

    def planned(self, part: str, others: list[str]) -> tuple[AssemblyStep | None, dict]:
        """Plan the removal of ``part`` with ``others`` present: goals on the most open
        sides first (see :meth:`goal_sides`), stopping at the first path, at a proof that
        the part cannot leave (the region outside the exit box is connected, so a
        certificate walling off the start answers for every side), or after a side used
        up the time limit (so a stuck part costs one time limit, not six)."""
        from planner.planning import plan  # noqa: PLC0415 (lazy: native planner)

        key = (part, frozenset(others))
        if key in self._planned:
            self.stats["planner_reused"] += 1
            return self._planned[key]
        t0 = time.perf_counter()
        body = self.parts[part]
        bodies = [self.parts[n] for n in others]
        enclosed = self.enclosed(part, others)
        if enclosed is not None:
            self._planned[key] = (None, enclosed)
            return None, enclosed
        sides: list[dict[str, Any]] = []
        step, attempt = None, None
        for dname in self.goal_sides(part, others):
            t_side = time.perf_counter()
            scenario = removal_scenario(self.assembly, part, list(others), dname)
            self.stats["planner_runs"] += 1
            try:
                outcome = plan(scenario, planner=self.planner, cache_dir=self.cache_dir,
                               progress=self.progress, source=self.source)
            except (InvalidParameterError, ScenarioError, ResourceLimitError):
                raise  # bad settings, or over the memory limit: the user's to fix
            except MinkplanError as error:  # e.g. geometry the native core rejects
                sides.append({"direction": dname, "status": "error", "reason": "error",
                              "message": str(error),
                              "seconds": time.perf_counter() - t_side})
                continue
            side: dict[str, Any] = {
                "direction": dname, "status": outcome.status, "reason": outcome.reason,
                "message": outcome.message, "seconds": time.perf_counter() - t_side}
            sides.append(side)
            if outcome.status == FOUND:
                path = np.asarray(outcome.waypoints, dtype=np.float64)
                validation = (_planner_validation(outcome, self.delta)
                              or validate_removal(body, bodies, path, self.delta))
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

    def free_reach(self, part: str, others: list[str]) -> float:
        """How far the part moves along the freest axis before it meets a present part
        (cheap: the pair cache's rays; ``inf`` when some axis is clear): a box of
        enclosure no larger than that cannot wall it in."""
        return max(min(self.pairs.free_run(part, o, dname, vec) for o in others)
                   for dname, vec in DIRECTIONS.items())

    def enclosed(self, part: str, others: list[str]) -> dict[str, Any] | None:
        """The attempt of a part proved unable to leave by a local enclosure
        (:func:`~planner.assembly.enclosure.prove_enclosed`: its start's free component
        walled off inside a small box), or ``None`` (then the planner decides)."""
        if not self.enclosures:
            return None
        reach = self.free_reach(part, others)
        if reach >= max(HALF_SIZES_REL) * self.assembly.diagonal:
            return None
        t0 = time.perf_counter()
        log.info("is %s enclosed? (a local proof before planning)", part)
        proof = prove_enclosed(self.source, self.parts[part], [self.parts[n] for n in others],
                               delta=self.delta, diagonal=self.assembly.diagonal,
                               deadline=t0 + self.assembly.settings.time_limit,
                               min_half=reach)
        self.stats["enclosures_tried"] += 1
        if proof is None:
            return None
        self.stats["enclosures_proved"] += 1
        message = (f"no path: {part} is walled off within {proof['half_size']:.3g} of "
                   f"{'its start' if not any(proof['start']) else 'a free pose next to its start'}"
                   f" by {proof['wall_cells']} FULL cells")
        log.info("%s", message)
        return {"status": NO_PATH, "reason": "enclosure", "message": message,
                "direction": None, "proved": True, "enclosure": proof,
                "obstacles": list(others), "sides": [],
                "seconds": time.perf_counter() - t0}

    # ---------------------------------------------------------------- a group of parts

    def blockers(self, seed: str, remaining: list[str], dname: str, vec: np.ndarray,
                 base: str | None) -> tuple[str, ...] | None:
        """The smallest group holding ``seed`` that no other remaining part blocks along
        ``vec``: ``seed`` and, again and again, every part that blocks a member (the
        parts reachable from ``seed`` in the directional blocking graph); ``None`` when
        it takes in the base or every remaining part."""
        members, frontier = [seed], [seed]
        while frontier:
            moving = frontier.pop()
            for other in remaining:
                if other in members:
                    continue
                verdict = self.pairs.verdict(moving, other, dname, vec)
                if verdict is None or not verdict.blocked:  # free, or FCL checks it later
                    continue
                if other == base:
                    return None
                members.append(other)
                frontier.append(other)
        if len(members) == len(remaining):
            return None
        return tuple(n for n in remaining if n in members)

    def group(self, remaining: list[str], base: str | None) -> AssemblyStep | None:
        """A straight removal of a group of parts moving as one rigid body, when no part
        can leave alone (Wilson and Latombe's non-directional blocking graph, along the
        six axes: a group closed under "is blocked by" leaves along that axis). FCL
        checks every member against the parts outside it; the group's own removal steps
        (with only its members present) are found at once, by the same search."""
        t0 = time.perf_counter()
        tried: set[tuple[tuple[str, ...], str]] = set()
        for dname, vec in DIRECTIONS.items():
            for seed in [n for n in reversed(remaining) if n != base]:
                members = self.blockers(seed, remaining, dname, vec, base)
                if members is None or (members, dname) in tried:
                    continue
                tried.add((members, dname))
                outside = [n for n in remaining if n not in members]
                path = np.array([np.zeros(3), self._group_exit(members, remaining, vec)])
                checks = {n: validate_removal(self.parts[n], [self.parts[o] for o in outside],
                                              path, self.delta) for n in members}
                if not all(c["valid"] for c in checks.values()):
                    continue
                inner = self.disassemble(list(members), None)
                validation = {"valid": True, "members": checks}
                return AssemblyStep(group_label(members), "group", dname, path, outside,
                                    time.perf_counter() - t0, validation, members,
                                    inner.steps)
        return None

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
            what = f"minkplan: {self.assembly.name}: step {self.pairs.step}"
            for part in movable():
                self.line.show(f"{what}: straight removals of {part}")
                step = self.straight(part, [n for n in remaining if n != part])
                if step is not None:
                    break
            if step is None and self.plan_parts:
                for part in movable():
                    self.line.show(f"{what}: planning the removal of {part}")
                    step, attempt = self.planned(part, [n for n in remaining if n != part])
                    if step is not None:
                        break
                    attempts[part] = attempt
            if step is None and self.groups:
                self.line.show(f"{what}: a group of parts that leaves as one")
                step = self.group(remaining, base)
                if step is not None:
                    inner = self._inner_stuck(step)
                    if inner is not None:  # out as one, but it does not come apart
                        return _Run([*steps, step], *inner)
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
            remaining = [n for n in remaining if n not in step.parts]
        return _Run(steps, list(remaining), [], {})

    def _group_exit(self, members: tuple[str, ...], remaining: list[str],
                    vec: np.ndarray) -> np.ndarray:
        """The translation along ``vec`` that takes every member out of the remaining
        parts' box: the longest of the members' own exits."""
        exits = [exit_point(vec, exit_box(self.parts[m], [self.parts[n] for n in remaining
                                                          if n != m], self.margin),
                            self.margin) for m in members]
        return max(exits, key=lambda e: float(np.linalg.norm(e)))

    def _inner_stuck(self, step: AssemblyStep) -> tuple[list[str], list[str], dict] | None:
        """For a group that leaves but cannot be taken apart: its remaining parts, its
        stuck parts and their attempts (as a stuck run reports them); else ``None``."""
        run = self.disassemble(list(step.members), None)  # cached: the same answers
        if not run.stuck:
            return None
        return list(run.remaining), list(run.stuck), dict(run.attempts)

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
                "pairs_reused_across_steps": several, "steps": self.pairs.step,
                # reduced convolutions the planned removals' C-spaces took from the pairs
                "cspace_pairs_reused": int(getattr(self.source, "pairs_reused", 0)),
                **self.stats}


@single_blas_thread
def plan_assembly(assembly: Assembly, *, planner: str = "minkplan", cache_dir=None,
                  progress: bool | None = False, plan_parts: bool = True,
                  minimize: bool = True, groups: bool = True,
                  enclosures: bool = True) -> AssemblyResult:
    """Find an assembly sequence by disassembly (see the module docstring).

    Args:
        assembly: from :func:`load_assembly`.
        planner: for the full planning steps: ``"minkplan"`` or ``"ompl:NAME"``.
        cache_dir: decomposition cache (the planner's and the pair cache's).
        progress: a status line on stderr naming the step (and the planner's, nested).
        plan_parts: run the planner when no straight removal exists (else give up there).
        minimize: when stuck, shrink the stuck parts to an irreducible interlocked set
            (more searches on subsets, sharing every cache).
        groups: when no part can leave alone, look for a group that leaves as one
            (a subassembly), then take it apart on its own.
        enclosures: before planning the removal of a part that meets a present part
            within a short way along every axis, try to prove it cannot leave by a local
            enclosure (:mod:`.enclosure`).
    """
    if not isinstance(assembly, Assembly):
        hint = "; a scenario goes to planner.plan" if isinstance(assembly, Scenario) else ""
        raise InvalidParameterError(f"plan_assembly takes an Assembly (planner.load_assembly), "
                                    f"not {type(assembly).__name__}{hint}")
    t_start = time.perf_counter()
    search = _Search(assembly, planner=planner, cache_dir=cache_dir, progress=progress,
                     plan_parts=plan_parts, groups=groups, enclosures=enclosures)
    with search.line:
        return _result(search, assembly, t_start, minimize=minimize, plan_parts=plan_parts)


def _result(search: _Search, assembly: Assembly, t_start: float, *, minimize: bool,
            plan_parts: bool) -> AssemblyResult:
    """Run the search of :func:`plan_assembly` and build its result."""
    base = assembly.base
    run = search.disassemble([p.name for p in assembly.parts], base)
    source = {"used": search.source.kind, "why": search.source.why}
    if not run.stuck:
        return AssemblyResult(assembly, SEQUENCE, run.steps, [], base,
                              assembly.contact_tolerance, time.perf_counter() - t_start,
                              reuse=search.reuse(), source=source)
    if minimize and plan_parts:
        core = search.irreducible(run, base)
        interlocked = sorted(core.remaining)
    else:  # the stuck movable parts, as found
        core, interlocked = run, list(run.stuck)
    return AssemblyResult(assembly, INTERLOCKED, run.steps, interlocked, base,
                          assembly.contact_tolerance, time.perf_counter() - t_start,
                          dict(run.attempts), stuck=list(run.stuck),
                          core_attempts=dict(core.attempts),
                          reuse=search.reuse(), source=source)


def removal_problems(result: AssemblyResult) -> list[dict[str, Any]]:
    """The removal problems a result was decided on: every removal step (expected
    ``found``; the goal on the side it left by, or along its straight direction; a
    group's step, then its own steps among its members) and,
    for an interlocked result, each movable part of the interlocked set with the rest of
    the set present (expected ``no_path`` when that was proved; ``proof``: how, e.g.
    ``"enclosure"`` or ``"certificate"``)."""
    problems: list[dict[str, Any]] = []

    def add(steps: list[AssemblyStep]) -> None:
        for step in steps:
            end = np.asarray(step.removal[-1], dtype=np.float64)
            direction = step.direction if step.direction in DIRECTIONS else end
            problems.append({"part": step.part, "obstacles": list(step.obstacles),
                             "direction": direction, "expected": FOUND,
                             "method": step.method})
            add(step.inner)  # a group's own steps, among its members

    add(result.removal)
    for name in result.interlocked:
        attempt = result.core_attempts.get(name)
        if name == result.base or not attempt:
            continue
        problems.append({"part": name, "obstacles": list(attempt["obstacles"]),
                         "direction": attempt.get("direction") or GOAL_SIDE,
                         "expected": NO_PATH if attempt.get("proved") else "unknown",
                         "method": "interlocked", "proof": attempt.get("reason")})
    return problems
