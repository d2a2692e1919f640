"""The memory budget: one limit, from which every size budget of the work is derived.

Everything that grows with the input is counted before (or while) it is allocated against
a budget derived from one number, the *memory limit* (``minkplan … --memory-limit GB``;
:func:`set_memory_limit` or :func:`memory_limit` from Python). Beyond a budget the work
stops with a :class:`~planner.errors.ResourceLimitError` that names the input, the limit
and what would bring the work within it, never with an out-of-memory crash.

The default limit is half of this machine's memory (``MemTotal`` in ``/proc/meminfo``, or
a container's ``memory.max`` when lower), but no more than the memory available when the
process starts; the environment variable ``MINKPLAN_MEMORY_LIMIT`` (GiB) overrides it (a
batch worker sets it for its task process from ``minkplan batch --memory-limit``).

How the limit is shared (each figure is peak resident bytes, measured on this code with
``ru_maxrss`` in fresh processes; see :data:`LEAF_BYTES` etc.):

- the exact source's boundary-convolution facets: a quarter (:meth:`MemoryBudget.facets`);
- the octree's candidate records: a quarter (:meth:`MemoryBudget.record_bytes`; at most
  4 GiB, the core's addressing limit);
- the octree's leaves (planner) or a surface's cells (sums, offsets, drawings): half
  (:meth:`MemoryBudget.leaves`, :meth:`MemoryBudget.surface_cells`).

A gigabyte here is a GiB (2**30 bytes).
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass

from .errors import InvalidParameterError, ResourceLimitError

log = logging.getLogger(__name__)

__all__ = ["GIB", "MemoryBudget", "current", "default_memory_limit", "explain",
           "memory_limit", "parse_memory_limit", "set_memory_limit"]

GIB = 1 << 30
"""Bytes in a GiB, the unit of ``--memory-limit``."""

LEAF_BYTES = 128
"""Peak bytes per leaf of the planner's C-space octree, candidate records apart (measured
91–105 B per leaf over 1.4M and 5.6M leaves, exact and decomposition sources: the leaf,
its index entry and the build's transient lists)."""

SURFACE_CELL_BYTES = 1024
"""Peak bytes per octree leaf of a sum's or an offset's surface, with its records, lattice
signs, edges and triangles, as the cells' share of the limit: measured 591–611 B per leaf
over 1.5M–6.7M leaves of curved surfaces, but 905 B (the whole peak over 4.4M leaves) to
about 1,700 B (over some 8M) on an L of two 2 x 0.5 bars grown by 1 mm, whose cells its
faces' planes resolve (their polygons kept per cell): at 640 B that run, allowed under a
10 GiB limit, peaked at 13.9 GB. The cells take half the limit, so this keeps it whole."""

DEPTH_CELL_BYTES = 256
"""Bytes per cell of a penetration-depth search (a box, its bounds and a queue entry)."""

DEPTH_CELLS = 1_000_000
"""Most cells one penetration-depth search classifies (it is a search: more cells buy
precision, not correctness); fewer when the memory limit is small."""

MAX_RECORD_BYTES = 4 * GIB
"""The core addresses at most 2**30 record words of 4 bytes."""

MINIMUM_BYTES = 1 << 20
"""The smallest memory limit accepted (1 MiB: smaller refuses every input)."""

FACET_SHARE = 0.25
"""The share of the limit the exact source's facets may use."""

RECORD_SHARE = 0.25
"""The share of the limit the octree's candidate records may use."""

CELL_SHARE = 0.5
"""The share of the limit the octree's leaves (or a surface's cells) may use."""

ENVIRONMENT = "MINKPLAN_MEMORY_LIMIT"
"""The environment variable (GiB) that sets the default memory limit."""


def gib(n_bytes: float) -> str:
    """``n_bytes`` as GiB for a message (``"4 GiB"``, ``"0.0153 GiB"``)."""
    return f"{n_bytes / GIB:.3g} GiB"


def _meminfo() -> dict[str, int]:
    """``/proc/meminfo`` in bytes (empty where there is none)."""
    found: dict[str, int] = {}
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                name, _, rest = line.partition(":")
                fields = rest.split()
                if fields and fields[0].isdigit():
                    found[name] = int(fields[0]) * (1024 if fields[1:2] == ["kB"] else 1)
    except OSError:
        pass
    return found


def _cgroup_limit() -> int | None:
    """The container's memory limit in bytes (cgroup v2, then v1), or ``None``."""
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path, encoding="ascii") as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 1 << 60:
            return int(text)
    return None


def machine_memory() -> tuple[int, int]:
    """``(total, available)`` bytes of memory this process may use: ``MemTotal`` (or the
    container's limit when lower) and ``MemAvailable``; ``os.sysconf`` where there is no
    ``/proc``; 8 GiB when nothing can be read."""
    info = _meminfo()
    total = info.get("MemTotal")
    if total is None:
        try:
            total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        except (ValueError, OSError, AttributeError):
            total = 8 * GIB
    limit = _cgroup_limit()
    if limit is not None:
        total = min(total, limit)
    available = min(info.get("MemAvailable", total), total)
    return int(total), int(available)


def default_memory_limit() -> tuple[int, str]:
    """The default limit in bytes and where it comes from (for messages)."""
    value = os.environ.get(ENVIRONMENT)
    if value:
        return parse_memory_limit(value, ENVIRONMENT), f"{ENVIRONMENT}={value}"
    total, available = machine_memory()
    limit = max(min(total // 2, available), MINIMUM_BYTES)
    return limit, f"the default: half of this machine's {gib(total)}"


def parse_memory_limit(value: object, name: str = "--memory-limit") -> int:
    """A memory limit in GiB (a number or a numeric string) as bytes; refuses what is not a
    finite number of at least :data:`MINIMUM_BYTES`."""
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} {value!r}: not a number of GiB") from None
    if not math.isfinite(number) or number * GIB < MINIMUM_BYTES:
        raise InvalidParameterError(
            f"{name} {value!r}: must be a finite number of GiB, at least "
            f"{MINIMUM_BYTES / GIB:.3g} (1 MiB)")
    if number * GIB > 1 << 62:
        raise InvalidParameterError(f"{name} {value!r}: more memory than any machine has")
    _warn_over_machine(int(number * GIB), name, value)
    return int(number * GIB)


def _warn_over_machine(limit: int, name: str, value: object) -> None:
    """Warn when the limit is more than this machine's memory (:func:`machine_memory`'s
    total): the work may then run out of memory before the limit refuses it."""
    total = machine_memory()[0]
    if limit > total:
        log.warning("%s %s GiB is more than this machine's memory (%s%s): work up to the "
                    "limit may run out of memory before the limit refuses it", name, value,
                    gib(total), ", its container's limit" if _cgroup_limit() == total else "")


@dataclass(frozen=True)
class MemoryBudget:
    """A memory limit and the size budgets derived from it.

    Attributes:
        limit: bytes.
        origin: where the limit comes from (``"--memory-limit"``, the default, ...).
    """

    limit: int
    origin: str = "--memory-limit"

    def facets(self, bytes_per_facet: int) -> int:
        """Boundary-convolution facets the exact source may hold."""
        return max(1, int(self.limit * FACET_SHARE) // bytes_per_facet)

    def record_bytes(self) -> int:
        """Bytes of octree candidate records."""
        return max(4, min(int(self.limit * RECORD_SHARE), MAX_RECORD_BYTES))

    def leaves(self) -> int:
        """Leaves of the planner's C-space octree."""
        return max(1, int(self.limit * CELL_SHARE) // LEAF_BYTES)

    def surface_cells(self) -> int:
        """Octree leaves of one surface (a sum, a C-obstacle, an offset)."""
        return max(1, int(self.limit * CELL_SHARE) // SURFACE_CELL_BYTES)

    def depth_cells(self) -> int:
        """Cells of one penetration-depth search."""
        return max(1, min(DEPTH_CELLS, self.limit // 8 // DEPTH_CELL_BYTES))

    def now(self) -> str:
        """``"now 4 GiB"`` (with where a default comes from)."""
        where = "" if self.origin == "--memory-limit" else f"; {self.origin}"
        return f"now {gib(self.limit)}{where}"

    def describe(self) -> str:
        """``"--memory-limit is 4 GiB"`` (with where a default comes from)."""
        where = "" if self.origin == "--memory-limit" else f" ({self.origin})"
        return f"--memory-limit is {gib(self.limit)}{where}"

    def refuse(self, what: str, needs: float, fraction: float, fix: str = ""
               ) -> ResourceLimitError:
        """The error for ``what``, which would need ``needs`` bytes where it may use
        ``fraction`` of the limit: it names the limit, the limit that would do and ``fix``
        (another way in)."""
        also = f", or {fix}" if fix else ""
        return ResourceLimitError(
            f"{what} needs about {gib(needs)}, more than the {gib(self.limit * fraction)} "
            f"it may use; {self.describe()}: raise it to {gib(needs / fraction)} or "
            f"more{also}")


_lock = threading.Lock()
_current: MemoryBudget | None = None


def _apply(budget: MemoryBudget) -> None:
    """Pass the budgets the core keeps process-wide (the candidate records) to it."""
    from ._minkowski_core import set_record_budget  # noqa: PLC0415 (errors.py must not)

    set_record_budget(budget.record_bytes())


def current() -> MemoryBudget:
    """The memory budget in force (the default until one is set)."""
    global _current
    with _lock:
        if _current is None:
            limit, origin = default_memory_limit()
            _current = MemoryBudget(limit, origin)
            _apply(_current)
        return _current


def set_memory_limit(limit_gib: float | None, *, origin: str = "--memory-limit"
                     ) -> MemoryBudget:
    """Set the memory limit of this process to ``limit_gib`` GiB (``None``: the default)
    and return the budget; every computation that follows keeps within it.

    Raises:
        InvalidParameterError: not a finite number of GiB of at least 1 MiB.
    """
    global _current
    if limit_gib is None:
        limit, origin = default_memory_limit()
    else:
        limit = parse_memory_limit(limit_gib, "memory limit" if origin != "--memory-limit"
                                   else origin)
    budget = MemoryBudget(limit, origin)
    with _lock:
        _current = budget
        _apply(budget)
    return budget


@contextlib.contextmanager
def memory_limit(limit_gib: float | None) -> Iterator[MemoryBudget]:
    """``with planner.memory_limit(2): ...``: the work inside keeps within 2 GiB; the
    previous limit is back afterwards."""
    before = current()
    try:
        yield set_memory_limit(limit_gib, origin="planner.memory_limit")
    finally:
        global _current
        with _lock:
            _current = before
            _apply(before)


def explain(error: ResourceLimitError, what: str | None = None,
            obstacles: list[str] | None = None, *, cell_bytes: int = SURFACE_CELL_BYTES,
            knob: str = "eps", cells_given: str | None = None,
            decomposition: bool = True) -> ResourceLimitError:
    """The core's refusal ``error`` as a user reads it: prefixed by the input ``what``,
    the core's ``obstacle K`` named (``obstacles``; dropped without them), cells weighed
    at ``cell_bytes``, the cell size called ``knob``, naming the memory limit in force
    and the setting that raises it — ``cells_given``, the setting that gave the budget
    the leaves ran out of, when the caller gave one (the candidate records stay the
    memory limit's);
    without ``decomposition`` the decomposition source is not offered (a command that
    has none)."""
    import re  # noqa: PLC0415

    budget = current()
    message = str(error)
    numbered = re.match(r"obstacle (\d+): ", message)
    if numbered:
        k = int(numbered.group(1))
        name = (f"{obstacles[k]}: " if obstacles is not None and k < len(obstacles) else "")
        message = name + message[numbered.end():]
    facets = re.search(r"the boundary convolution needs more than [\d.]+ [MG]iB", message)
    if facets:  # which part of the limit that is (it reads as the whole limit otherwise)
        end = facets.end()
        message = (f"{message[:end]}, the {FACET_SHARE:.0%} of the memory limit it may use"
                   f"{message[end:]}")
    cells = re.search(r"needs more than (\d+) cells", message)
    if cells:  # what those cells weigh
        end = cells.end()
        share = "" if cells_given else ", the cells' share of the memory limit"
        message = (f"{message[:end]} (more than {gib(int(cells.group(1)) * cell_bytes)}"
                   f"{share}){message[end:]}")
    if not decomposition:
        message = message.replace(", or use the decomposition source (exact: false) or "
                                  "simpler meshes", ", or use simpler meshes")
    lattice = "the lattice addresses at most" in message  # too fine: no memory helps
    if lattice:
        message = message.replace("use a larger eps or raise the memory limit",
                                  "use a larger eps (no memory limit makes this grid fit)")
    message = message.replace("use a larger eps", f"use a larger {knob}")
    setting = f"raise --memory-limit ({budget.now()})"
    if cells_given and message.startswith("the octree needs more than"):
        setting = f"raise {cells_given}"
    if "raise the memory limit" in message:
        message = message.replace("raise the memory limit", setting, 1)
    elif "--memory-limit" not in message and not lattice and not cells_given:
        message = f"{message}; {budget.describe()}"
    if what and not message.startswith(what):
        message = f"{what}: {message}"
    refused = ResourceLimitError(message)
    refused.__cause__ = error
    return refused


def facet_bytes() -> int:
    """Bytes per boundary-convolution facet (the core's ``FACET_BYTES``)."""
    from ._minkowski_core import budget_units  # noqa: PLC0415

    return int(budget_units()["facet"])


def facets() -> int:
    """The facet budget of the exact source under the memory limit in force."""
    return current().facets(facet_bytes())


def leaves() -> int:
    """The leaf budget of the planner's octree under the memory limit in force."""
    return current().leaves()


def surface_cells(max_cells: int | None = None) -> tuple[int, bool]:
    """The cell budget of one surface: ``max_cells`` when given, else ``tol.max_cells``
    when set, else :meth:`MemoryBudget.surface_cells`; and whether it is the latter (so a
    refusal names ``--memory-limit`` rather than ``max_cells``)."""
    from .tolerances import tol  # noqa: PLC0415

    if max_cells is not None:
        return int(max_cells), False
    if tol.max_cells is not None:
        return int(tol.max_cells), False
    return current().surface_cells(), True


def cells_setting(from_memory: bool) -> str | None:
    """The setting a refusal of :func:`surface_cells`' budget names for :func:`explain`
    (``None``: the memory limit's)."""
    return None if from_memory else "max_cells"


def refuse_cells(what: str, cells: float, max_cells: int, from_memory: bool, fix: str
                 ) -> ResourceLimitError:
    """The refusal of a surface that would need about ``cells`` cells, over ``max_cells``."""
    if from_memory:
        return current().refuse(f"{what}: the grid ({cells:.2g} cells)",
                                cells * SURFACE_CELL_BYTES, CELL_SHARE, fix)
    return ResourceLimitError(f"{what}: the grid would need about {cells:.2g} cells, over "
                              f"the budget of {max_cells:.2g}; {fix} or raise max_cells")
