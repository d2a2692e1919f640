"""OMPL's benchmark log format, so runs of minkplan and of OMPL's planners can be read by
the tools OMPL users have: ``ompl_benchmark_statistics.py`` (shipped with the ``ompl``
wheel) turns the ``.log`` files into the SQLite database that Planner Arena plots.

One log is one experiment (one problem): a header (library and version, experiment name,
host, date, the problem's setup, seed, time and memory limits, run count, total time),
an enum declaration for ``status``, then for each planner its name, its common
properties, the typed property names of a run and one line of ``;``-separated values
per run.

Entry points: :class:`Run` (what one run reports), :func:`write_log`.
"""

from __future__ import annotations

import datetime
import math
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from .output import atomic_write

__all__ = ["RUN_PROPERTIES", "STATUSES", "Run", "write_log"]

STATUSES = ("found", "no_path", "not_found")
"""The values of the ``status`` enum, in its order (the roles' vocabulary)."""

RUN_PROPERTIES = (
    ("time", "REAL"),
    ("solved", "BOOLEAN"),
    ("status", "ENUM"),
    ("solution length", "REAL"),
    ("solution clearance", "REAL"),
    ("valid", "BOOLEAN"),
    ("proved no path", "BOOLEAN"),
    ("reason", "VARCHAR(128)"),
)
"""The properties every run reports, with their SQL types (the last word of each line)."""


@dataclass(frozen=True)
class Run:
    """One run of one planner on the problem.

    Attributes:
        seconds: wall-clock time of the run.
        status: ``"found"``, ``"no_path"`` or ``"not_found"``.
        length: path length (``nan`` without one).
        clearance: smallest distance to the obstacles along it (``nan`` without one).
        valid: the path passed the independent validation (``False`` without one).
        reason: the status's reason (``"path"``, ``"certificate"``, ``"time_limit"``...).
    """

    seconds: float
    status: str
    length: float = math.nan
    clearance: float = math.nan
    valid: bool = False
    reason: str = ""

    def values(self) -> list[str]:
        """The run's line of values, in :data:`RUN_PROPERTIES` order."""
        def real(x: float) -> str:
            return "nan" if not math.isfinite(x) else repr(float(x))

        return [real(self.seconds), str(int(self.status == "found")),
                str(STATUSES.index(self.status)), real(self.length), real(self.clearance),
                str(int(self.valid)), str(int(self.status == "no_path")),
                self.reason.replace(";", ",").replace(" ", "_") or "none"]


def write_log(path: Path, *, experiment: str, setup: str, runs: Mapping[str, Sequence[Run]],
              time_limit: float, total_seconds: float, seed: int = 0,
              version: str = "0.0.0", memory_limit_mb: float = 0.0) -> None:
    """Write one experiment's log (atomically).

    Args:
        path: the ``.log`` file.
        experiment: its name (no spaces: OMPL's reader takes the last word).
        setup: a description of the problem (kept as the experiment's setup text).
        runs: per planner name, its runs.
        time_limit: seconds per run.
        total_seconds: time spent on the whole experiment.
        seed: the random seed of the first run.
        version: minkplan's version.
        memory_limit_mb: memory limit per run (0: none).
    """
    counts = {len(r) for r in runs.values()}
    lines = [
        f"minkplan version {version}",
        f"Experiment {experiment.replace(' ', '_')}",
        f"Running on {platform.node() or 'localhost'}",
        f"Starting at {datetime.datetime.now().strftime('%Y-%m-%d %H:%M:%S')}",
        "<<<|", *setup.splitlines(), "|>>>",
        f"{seed} is the random seed",
        f"{time_limit!r} seconds per run",
        f"{memory_limit_mb!r} MB per run",
    ]
    if len(counts) == 1:
        lines.append(f"{counts.pop()} runs per planner")
    lines += [f"{total_seconds!r} seconds spent to collect the data",
              "1 enum types", "status|" + "|".join(STATUSES),
              f"{len(runs)} planners"]
    for name, planner_runs in runs.items():
        lines += [name.replace(" ", "_"), "0 common properties",
                  f"{len(RUN_PROPERTIES)} properties for each run",
                  *[f"{prop} {kind}" for prop, kind in RUN_PROPERTIES],
                  f"{len(planner_runs)} runs",
                  *["; ".join(r.values()) + "; " for r in planner_runs], "."]
    text = "\n".join(lines) + "\n"
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))
