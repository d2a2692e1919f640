"""The time limit of one plan: a ``time.perf_counter()`` value the planner's steps
are measured against, and the native core's copy of it.

A step in Python asks :meth:`Deadline.would_pass` before it starts; the native core's
octree builds and refinements, which can run for minutes on large triangle soups, are
stopped from inside by :meth:`Deadline.native` (they raise
:class:`~planner.errors.TimeLimitError` and change nothing), so a plan ends near its
limit instead of after the step that was running.

The native deadline is one value per process (like the candidate records' memory
budget): while a block sets it, it bounds every build in the process, so one plan at a
time may use it — as the planner does (batch runs give each task its own process).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from planner._minkowski_core import set_time_limit

__all__ = ["Deadline", "native_deadline"]


@dataclass
class Deadline:
    """A ``time.perf_counter()`` value ``at``, whether some step was stopped or not
    started because it would have ended after it (``reached``), and the seconds per robot
    triangle the last local C-space took to build (``cspace_pace``, 0 before the first:
    the start's and the goal's local proofs share it)."""

    at: float
    reached: bool = False
    cspace_pace: float = 0.0

    def would_pass(self, seconds: float = 0.0) -> bool:
        """Whether a step of ``seconds`` started now would end after the deadline (then
        ``reached`` is set)."""
        passes = time.perf_counter() + seconds > self.at
        self.reached |= passes
        return passes

    @contextmanager
    def native(self) -> Iterator[None]:
        """The native core's builds and refinements inside stop at the deadline."""
        with native_deadline(self.at):
            yield


_active: list[float] = []
"""The deadlines of the :func:`native_deadline` blocks the process is in, outermost first."""


@contextmanager
def native_deadline(at: float) -> Iterator[None]:
    """Inside, the native core's octree builds and refinements stop at ``at`` (a
    ``time.perf_counter()`` value), or at an enclosing block's earlier deadline, with
    :class:`~planner.errors.TimeLimitError`; after, the enclosing block's deadline holds
    again (none outside every block)."""
    effective = min([at, *_active])
    _set(effective)
    _active.append(effective)
    try:
        yield
    finally:
        _active.pop()
        _set(_active[-1] if _active else None)


def _set(at: float | None) -> None:
    set_time_limit(None if at is None else max(at - time.perf_counter(), 0.0))
