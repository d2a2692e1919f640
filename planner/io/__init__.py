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


def load_problem(path: str | os.PathLike[str], *,
                 hold_orientation: str | None = None) -> Scenario | Assembly:
    """Read a problem file: an OMPL.app ``.cfg``, a scenario YAML or an assembly YAML
    (one with top-level ``parts:``). ``hold_orientation`` (``"start"`` or ``"goal"``):
    a planning problem whose start and goal orientations differ is read with that one
    throughout (see :func:`load_scenario`).

    Raises:
        ScenarioError: unknown suffix, or whatever the reader finds (one line naming the
            file, line and field).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml") and _is_assembly_yaml(path):
        return read_assembly(path)
    if suffix in (".cfg", ".yaml", ".yml"):
        return load_scenario(path, hold_orientation=hold_orientation)
    raise ScenarioError(f"{path}: unknown problem file type {suffix or '(no suffix)'!r}; "
                        f"use one of {', '.join(PROBLEM_SUFFIXES)}")


def load_scenario(path: str | os.PathLike[str], *,
                  hold_orientation: str | None = None) -> Scenario:
    """A planning problem: a scenario YAML, or an OMPL.app ``.cfg`` (translation only).

    Args:
        path: the file.
        hold_orientation: ``"start"`` or ``"goal"``: when the start and goal orientations
            differ (a 6-DOF problem), read it translation-only with that orientation
            throughout (noted in ``Scenario.notes``); ``None``: that is an error.

    Raises:
        ScenarioError: as :func:`load_problem`, or the file is an assembly.
    """
    path = Path(path)
    if path.suffix.lower() == ".cfg":
        return load_omplapp(path, hold_orientation=hold_orientation)
    if path.suffix.lower() in (".yaml", ".yml") and _is_assembly_yaml(path):
        raise ScenarioError(f"{path}: an assembly (it lists parts:), not a planning problem: "
                            f"use minkplan assemble (planner.load_assembly, "
                            f"planner.plan_assembly)")
    return read_scenario(path, hold_orientation=hold_orientation)


def load_assembly(path: str | os.PathLike[str], *,
                  interference: float | None = None) -> Assembly:
    """An assembly YAML file (see ``docs/assembly.md``); ``interference`` replaces the
    file's interference tolerance."""
    return read_assembly(path, interference=interference)
