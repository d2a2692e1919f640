"""What an assembly search returns: the removal steps and the result, and their JSON
forms (``sequence.json``, ``report.json``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.output import jsonable, schema_id
from planner.problem import Assembly

__all__ = ["INTERLOCKED", "SEQUENCE", "AssemblyResult", "AssemblyStep", "group_label",
           "inner_order"]


SEQUENCE = "sequence"


INTERLOCKED = "interlocked"


@dataclass
class AssemblyStep:
    """One part's (or one group's) removal, in removal order, and hence insertion
    (reversed).

    Attributes:
        part: the part's name; for a group, its label (:func:`group_label`).
        method: ``"straight"`` (one segment along ``direction``), ``"planned"``, or
            ``"group"`` (a subassembly leaving as one rigid body, straight).
        direction: ``"+z"`` etc. for straight removals, the goal's side when planned.
        removal: ``(n, 3)`` translations from ``0`` (assembled) to outside.
        obstacles: the parts present while it moves.
        seconds: time spent finding it.
        validation: FCL's check of the removal path at the contact tolerance (for a
            group: of every member against the parts outside it).
        members: a group's parts (empty for one part).
        inner: a group's own removal steps with only its members present (how the
            subassembly comes apart once out; fewer than ``len(members) - 1`` when it
            cannot be taken apart by translations).
    """

    part: str
    method: str
    direction: str
    removal: np.ndarray
    obstacles: list[str]
    seconds: float
    validation: dict[str, Any]
    members: tuple[str, ...] = ()
    inner: list[AssemblyStep] = field(default_factory=list)

    @property
    def insertion(self) -> np.ndarray:
        """Translations from outside to ``0`` (the removal reversed)."""
        return self.removal[::-1].copy()

    @property
    def parts(self) -> tuple[str, ...]:
        """The parts that move in this step."""
        return self.members or (self.part,)


def group_label(members: tuple[str, ...]) -> str:
    """A group's name in orders and messages: ``[a + b]``."""
    return "[" + " + ".join(members) + "]"


def inner_order(step: AssemblyStep) -> list[str]:
    """A group's own assembly order: its part left last, then its removals reversed."""
    removed = [name for s in step.inner for name in s.parts]
    return [n for n in step.members if n not in removed] + [s.part for s in step.inner[::-1]]


def _inner_json(step: AssemblyStep) -> list[dict[str, Any]]:
    """A group's own assembly, in order: its first part fixed, then each insertion (in
    the group's assembled frame, before the group moves in)."""
    inner = {s.part: s for s in step.inner}
    return [{"part": n, "fixed": True, "insertion": [[0.0, 0.0, 0.0]]} if n not in inner
            else {"part": n, "fixed": False, "method": inner[n].method,
                  "direction": inner[n].direction, "insertion": inner[n].insertion}
            for n in inner_order(step)]


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
        reuse: what the search computed and reused (see
            :class:`~planner.assembly.pairs.PairCache`).
        source: the C-obstacle source every pair and planned removal used (``used``,
            ``why``).
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
    source: dict[str, Any] = field(default_factory=dict)

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
        removed = {name for s in self.removal for name in s.parts}
        first = [p.name for p in self.assembly.parts if p.name not in removed]
        return first + [s.part for s in self.removal[::-1]]

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
            groups = "".join(f"; {s.part} is put together first: {' -> '.join(inner_order(s))}"
                             for s in self.removal if s.members)
            return f"assembly order: {' -> '.join(self.order)}{groups}"
        how = self._how_proved()
        text = f"no sequence: interlocked parts {', '.join(self.interlocked)} ({how})"
        together = [s for s in self.removal if set(self.interlocked) <= set(s.members)]
        if together:
            text += f"; they leave the rest together, as {together[0].part}"
        others = [n for n in self.stuck if n not in self.interlocked]
        if others:
            text += f"; also stuck: {', '.join(others)}"
        return text

    def _how_proved(self) -> str:
        """Whether, and for which motions, the interlocked set was proved: the proofs
        speak of motions that meet no other part, which is all a user asked when no
        interference was allowed, and not all when one was."""
        if not self.proved:
            tries = [*self.core_attempts.values(), *self.attempts.values()]
            if any(t.get("reason") == "plan_parts" for t in tries):
                return "not proved: no straight removal, and planning was not asked for"
            return "not proved: some planner gave up"
        if self.assembly.interference > 0:
            return (f"proved for motions that meet no other part; motions that penetrate "
                    f"by up to the interference {self.assembly.interference:.3g} are not "
                    "covered")
        return "proved"

    def interference_json(self) -> dict[str, Any]:
        """The interference tolerance the user gave (``0``: none), the penetration every
        check allowed (``tolerance``: contact plus interference) and the overlaps of the
        assembled pose it accepted."""
        a = self.assembly
        return {"interference": a.interference, "tolerance": a.tolerance,
                "overlaps": list(a.overlaps)}

    def sequence_json(self) -> dict[str, Any]:
        """``sequence.json``: parts in assembly order, each with its insertion path."""
        steps = {s.part: s for s in self.removal}
        parts = []
        for name in self.order:
            step = steps.get(name)
            if step is None:
                parts.append({"part": name, "fixed": True, "insertion": [[0.0, 0.0, 0.0]]})
                continue
            entry = {"part": name, "fixed": False, "method": step.method,
                     "direction": step.direction, "insertion": step.insertion,
                     "validation": step.validation}
            if step.members:
                entry.update(group=list(step.members), subassembly=_inner_json(step))
            parts.append(entry)
        return jsonable({
            "schema": schema_id("sequence"),
            "name": self.assembly.name, "units": self.assembly.units, "status": self.status,
            "contact_tolerance": self.contact_tolerance, **self.interference_json(),
            "base": self.base, "parts": parts, "interlocked": self.interlocked, "stuck": self.stuck,
            "proved": self.proved, "message": self.message,
        })

    def report_json(self) -> dict[str, Any]:
        """``report.json``: removal steps with timings, obstacles and attempts."""
        return jsonable({
            "schema": schema_id("assembly_report"),
            "name": self.assembly.name, "status": self.status, "message": self.message,
            "contact_tolerance": self.contact_tolerance, **self.interference_json(),
            "seconds": self.seconds,
            "removal": [{"part": s.part, "method": s.method, "direction": s.direction,
                         "waypoints": s.removal, "obstacles": s.obstacles,
                         "seconds": s.seconds, "validation": s.validation,
                         **({"group": list(s.members),
                             "inner": [{"part": i.part, "method": i.method,
                                        "direction": i.direction, "waypoints": i.removal}
                                       for i in s.inner]} if s.members else {})}
                        for s in self.removal],
            "interlocked": self.interlocked, "stuck": self.stuck,
            "attempts": self.attempts, "interlocked_attempts": self.core_attempts,
            "reuse": self.reuse, "source": self.source,
            "parts": [p.describe() for p in self.assembly.parts],
            "settings": dataclasses.asdict(self.assembly.settings),
        })
