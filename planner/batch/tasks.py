"""What a batch runs: the problems found in files, folders and list files, and the tasks
(problem, planner, run) made of them.

A *problem* is a file :func:`planner.io.load_problem` reads: a scenario YAML (top-level
``robot:``), an assembly YAML (top-level ``parts:``) or an OMPL.app ``.cfg``. Inputs are
problem files, folders (searched recursively; YAML files that are neither scenarios nor
assemblies are passed over, with a log line) and list files (``.txt``: one path per line,
relative to the list file, ``#`` starts a comment). Every planning problem runs once per
planner and run; an assembly runs once, with minkplan's assembly planner (OMPL's planners
do not plan assemblies; it is deterministic and has no time limit).

A task's :attr:`Task.key` names it in ``results.jsonl``: ``--resume`` skips the keys
already there.

Entry points: :func:`find_problems`, :func:`make_tasks`, :class:`Task`.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from planner.errors import ScenarioError

__all__ = ["ASSEMBLY", "PLAN", "Problem", "Task", "find_problems", "make_tasks"]

log = logging.getLogger(__name__)

PLAN = "plan"
"""A planning problem (scenario YAML or OMPL.app ``.cfg``)."""
ASSEMBLY = "assembly"
"""An assembly YAML."""

_YAML = (".yaml", ".yml")
_LIST = ".txt"


@dataclass(frozen=True)
class Problem:
    """One problem file and what kind of problem it holds."""

    path: Path
    kind: str

    @property
    def name(self) -> str:
        return self.path.stem


@dataclass(frozen=True)
class Task:
    """One run of one planner on one problem (a Ray task).

    Attributes:
        problem: the problem file (absolute).
        kind: :data:`PLAN` or :data:`ASSEMBLY`.
        planner: ``"minkplan"`` or ``"ompl:NAME"``.
        run: the run's index; its seed is the problem's seed plus ``run``.
        time_limit: the planner's time limit in seconds (``None``: the problem's own).
        hold_orientation: ``"start"``/``"goal"`` for a problem whose orientations differ
            (``None``: refuse such a problem, as ``minkplan plan`` does).
        cache_dir: the decomposition cache (``None``: the default).
    """

    problem: str
    kind: str
    planner: str
    run: int
    time_limit: float | None = None
    hold_orientation: str | None = None
    cache_dir: str | None = None

    @property
    def key(self) -> str:
        """The task's name in ``results.jsonl``: problem, planner and run."""
        return f"{self.problem}|{self.planner}|{self.run}"

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, document: dict[str, Any]) -> Task:
        return cls(**document)


def _yaml_kind(path: Path) -> str | None:
    """:data:`PLAN` or :data:`ASSEMBLY` by the YAML's top-level keys, ``None`` for neither
    (judged from the text; the reader reports the file's own errors)."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return None
    if any(line.startswith("parts:") for line in lines):
        return ASSEMBLY
    if any(line.startswith("robot:") for line in lines):
        return PLAN
    return None


def _yaml_problem(path: Path) -> str | None:
    """What keeps a YAML file from being read at all (syntax, encoding), or ``None``."""
    import yaml

    try:
        yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        return f"cannot read it ({exc})"
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        return f"YAML syntax error{where}: {getattr(exc, 'problem', None) or exc}"
    return None


def _problem_at(path: Path, *, strict: bool) -> Problem | None:
    suffix = path.suffix.lower()
    if suffix == ".cfg":
        return Problem(path, PLAN)
    if suffix in _YAML:
        kind = _yaml_kind(path)
        if kind is not None:
            return Problem(path, kind)
        if strict:
            why = _yaml_problem(path) or "neither a scenario (robot:) nor an assembly (parts:)"
            raise ScenarioError(f"{path}: {why}")
        log.info("%s: not a scenario or an assembly; passed over", path)
        return None
    if strict:
        raise ScenarioError(f"{path}: not a problem file (.yaml, .yml, .cfg) or a list "
                            f"of them (.txt)")
    return None


def _list_file(path: Path) -> list[Path]:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: cannot read the list: {exc}") from None
    entries = []
    for number, line in enumerate(lines, 1):
        entry = line.split("#", 1)[0].strip()
        if not entry:
            continue
        target = (path.parent / entry).resolve()
        if not target.exists():
            raise ScenarioError(f"{path}:{number}: {entry!r} not found")
        entries.append(target)
    return entries


def _expand(path: Path, seen: set[Path]) -> Iterable[Problem]:
    if path.is_dir():
        for child in sorted(p for p in path.rglob("*") if p.is_file()):
            found = _problem_at(child, strict=False)
            if found is not None:
                yield found
        return
    if path.suffix.lower() == _LIST:
        if path in seen:
            raise ScenarioError(f"{path}: the list includes itself")
        seen.add(path)
        for entry in _list_file(path):
            yield from _expand(entry, seen)
        return
    found = _problem_at(path, strict=True)
    if found is not None:
        yield found


def find_problems(inputs: Sequence[str | Path]) -> list[Problem]:
    """The problems named by ``inputs`` (files, folders, list files), each once, in the
    order given (a folder's in path order).

    Raises:
        ScenarioError: an input that does not exist or is not a problem or a list, or a
            list entry that does not exist (one line naming it).
    """
    problems: dict[Path, Problem] = {}
    for item in inputs:
        path = Path(item).resolve()
        if not path.exists():
            raise ScenarioError(f"{item}: not found")
        for problem in _expand(path, set()):
            problems.setdefault(problem.path, problem)
    return list(problems.values())


def make_tasks(problems: Sequence[Problem], planners: Sequence[str], runs: int, *,
               time_limit: float | None = None, hold_orientation: str | None = None,
               cache_dir: str | None = None) -> list[Task]:
    """Every (problem, planner, run): planning problems with each planner, assemblies
    once with minkplan (the assembly planner is deterministic and has no time limit)."""
    tasks = []
    for problem in problems:
        names = planners if problem.kind == PLAN else ["minkplan"]
        for name in names:
            for run in range(runs if problem.kind == PLAN else 1):
                tasks.append(Task(str(problem.path), problem.kind, name, run, time_limit,
                                  hold_orientation, cache_dir))
    return tasks
