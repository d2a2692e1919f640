"""The input edge: problem files to typed problems (:mod:`planner.problem`).

:func:`load_problem` dispatches on the file, as ``trimesh.load`` does, to the readers
that live side by side:

- :mod:`.scenario_yaml` -- scenario YAML (``robot:``, ``start:``, ``goal:``) to a
  :class:`~planner.problem.Scenario`;
- :mod:`.assembly_yaml` -- assembly YAML (``parts:``) to an
  :class:`~planner.problem.Assembly`;
- :mod:`.omplapp` -- OMPL.app problem ``.cfg`` files (COLLADA meshes) to a
  :class:`~planner.problem.Scenario`, translation only.

:mod:`.fields` and :mod:`.parts` hold what the YAML readers share. Readers check every
mesh once (solid or surface) and say where each problem is: one-line
:class:`~planner.errors.ScenarioError` naming the file, line and field.
"""

from __future__ import annotations

import os
from pathlib import Path

from planner.errors import ScenarioError
from planner.problem import Assembly, Scenario

from .assembly_yaml import parse_assembly, read_assembly
from .omplapp import load_omplapp
from .scenario_yaml import parse_scenario, read_scenario

__all__ = [
    "PROBLEM_SUFFIXES",
    "load_assembly",
    "load_omplapp",
    "load_problem",
    "load_scenario",
    "parse_assembly",
    "parse_scenario",
]

PROBLEM_SUFFIXES = (".yaml", ".yml", ".cfg")
"""File suffixes :func:`load_problem` reads."""


def _is_assembly_yaml(path: Path) -> bool:
    """Whether a YAML file lists ``parts:`` at its top level (an assembly), judged from
    its text without parsing it (the reader reports the file's own errors)."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    return any(line.startswith("parts:") for line in text.splitlines())


def load_problem(path: str | os.PathLike[str]) -> Scenario | Assembly:
    """Read a problem file: an OMPL.app ``.cfg``, a scenario YAML or an assembly YAML
    (one with top-level ``parts:``).

    Raises:
        ScenarioError: unknown suffix, or whatever the reader finds (one line naming the
            file, line and field).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".cfg":
        return load_omplapp(path)
    if suffix in (".yaml", ".yml"):
        return read_assembly(path) if _is_assembly_yaml(path) else read_scenario(path)
    raise ScenarioError(f"{path}: unknown problem file type {suffix or '(no suffix)'!r}; "
                        f"use one of {', '.join(PROBLEM_SUFFIXES)}")


def load_scenario(path: str | os.PathLike[str]) -> Scenario:
    """A planning problem: a scenario YAML, or an OMPL.app ``.cfg`` (translation only).

    Raises:
        ScenarioError: as :func:`load_problem`, or the file is an assembly.
    """
    path = Path(path)
    if path.suffix.lower() == ".cfg":
        return load_omplapp(path)
    return read_scenario(path)


def load_assembly(path: str | os.PathLike[str]) -> Assembly:
    """An assembly YAML file (see ``docs/assembly.md``)."""
    return read_assembly(path)
