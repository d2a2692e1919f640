"""Bookkeeping of a planning run: seconds per stage and the parts of
``report.json`` that describe the octree (cells per label and level)."""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["LABELS", "STAGES", "Clock", "cell_report", "smallest_mixed_cell", "stage_seconds"]

LABELS = ("empty", "full", "mixed")
"""Octree labels in the core's order (``level_counts`` columns)."""


STAGES = ("decompose", "octree", "refine", "cspace", "graph", "search", "certificate",
          "shortcut", "validate", "total")
"""The keys of ``timings`` (``path.json``) and ``seconds`` (``report.json``), the same in
every run and for every planner: ``cspace`` is ``octree`` + ``refine``, ``total`` the
whole run, and a stage that did not run (no decomposition, no certificate, an OMPL
baseline's octree) is 0.0."""


def stage_seconds(seconds: dict[str, float]) -> dict[str, float]:
    """``seconds`` with every key of :data:`STAGES`, in that order (0.0 for a stage that
    did not run); a key outside it is kept after them."""
    stable = {key: float(seconds.get(key, 0.0)) for key in STAGES}
    return stable | {k: v for k, v in seconds.items() if k not in stable}


class Clock:
    """Seconds per stage, added up over the run (``clock.seconds``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def add(self, key: str, seconds: float) -> None:
        self.seconds[key] = self.seconds.get(key, 0.0) + seconds

    @contextmanager
    def stage(self, key: str) -> Iterator[None]:
        """Time the ``with`` block as stage ``key``."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.add(key, time.perf_counter() - t0)


def smallest_mixed_cell(cs) -> float:
    """Size of the smallest MIXED leaf of a native C-space (the coarse size if none)."""
    for level, counts in enumerate(cs.level_counts()):
        if counts[2] > 0:
            return cs.floor * 2**level
    return cs.floor * 2**cs.coarse_level


def cell_report(counts: list, floor: float) -> dict[str, Any]:
    """``report.json``'s ``cells``: leaves per label in total and per level (with its
    cell size), from the core's ``level_counts``."""
    per_level = []
    totals: Counter[str] = Counter()
    for level, c in enumerate(counts):
        if sum(c) == 0:
            continue
        entry: dict[str, Any] = {"level": level, "size": floor * 2**level}
        for name, n in zip(LABELS, c, strict=True):
            entry[name] = int(n)
            totals[name] += int(n)
        per_level.append(entry)
    return {"total": dict(totals), "leaves": int(sum(totals.values())), "per_level": per_level}
