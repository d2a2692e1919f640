"""Exceptions raised by minkplan.

Every error minkplan raises on bad input or exhausted limits derives from
:class:`MinkplanError`, and also from the matching built-in exception (``ValueError``,
``MemoryError``, ``TimeoutError``, ``RuntimeError``), so callers that already catch the
built-in keep working::

    MinkplanError(Exception)
    ├── InvalidMeshError(MinkplanError, ValueError)       bad solid or unreadable mesh file
    ├── InvalidParameterError(MinkplanError, ValueError)  bad argument value (eps <= 0, ...)
    ├── ResourceLimitError(MinkplanError, MemoryError)    work would not fit in memory/time
    ├── TimeLimitError(MinkplanError, TimeoutError)       time limit passed in native work
    ├── GeometryError(MinkplanError, RuntimeError)        core failed on valid-looking input
    │   └── EmptyResultError(GeometryError)               the result is empty (all eroded)
    └── ScenarioError(MinkplanError, ValueError)          scenario YAML problem (field, line)

Messages are a single line that names the input (mesh name, file path or field), states
the problem and, where possible, how to fix it, e.g.
``mesh 'robot': not watertight (4 boundary edges, 0 non-manifold edges); close the holes
or try planner.meshes.repair_mesh``.

The native extension ``planner._minkowski_core`` raises these same classes (it imports
them from this module), so this module imports nothing beyond the standard library and
must never import the extension.
"""

from __future__ import annotations

__all__ = [
    "EmptyResultError",
    "GeometryError",
    "InvalidMeshError",
    "InvalidParameterError",
    "MinkplanError",
    "ResourceLimitError",
    "ScenarioError",
    "TimeLimitError",
]


def _one_line(message: object) -> object:
    """Collapse a multi-line string message to one line; leave other objects alone."""
    if isinstance(message, str) and ("\n" in message or "\r" in message):
        return " ".join(part.strip() for part in message.splitlines() if part.strip())
    return message


class MinkplanError(Exception):
    """Base class of every error minkplan raises on bad input or exhausted limits.

    The first argument is the message. A multi-line message is collapsed into one line,
    so that logs and command-line error output stay one line per error.
    """

    def __init__(self, *args: object) -> None:
        if args:
            args = (_one_line(args[0]), *args[1:])
        super().__init__(*args)


class InvalidMeshError(MinkplanError, ValueError):
    """A mesh is not a usable solid, or a mesh file cannot be read.

    Raised for: a missing or unreadable file, no triangles, NaN or infinite
    coordinates, an open (not watertight) or non-manifold surface, inconsistent winding
    that cannot be repaired, zero volume. The message names the mesh or file.
    """


class InvalidParameterError(MinkplanError, ValueError):
    """An argument has an invalid value, e.g. ``eps <= 0`` or a CoACD threshold outside
    ``(0, 1]``. The message names the parameter, the value and the accepted range."""


class ResourceLimitError(MinkplanError, MemoryError):
    """The requested work would not fit in the memory or time budget (e.g. an ``eps``
    so small that the grid exceeds the memory limit's share, see :mod:`planner.budget`).
    The message names the input, the limit and how to stay within it (``--memory-limit``,
    a larger eps, the decomposition source)."""


class TimeLimitError(MinkplanError, TimeoutError):
    """The time limit passed during a long native step (an octree build or refinement,
    see :mod:`planner.deadline`); the step changed nothing. The planner reports it as
    ``not_found`` (``time_limit``)."""


class GeometryError(MinkplanError, RuntimeError):
    """The native core (or a geometry library such as CoACD) could not process input that
    passed validation. This is a bug or a numerical limit, not a user error; the message
    names the input so it can be reproduced."""


class EmptyResultError(GeometryError):
    """The answer is the empty set: an erosion (or an opening's) that leaves nothing of
    the solid, its every part thinner than twice the radius. Not a failure of the input
    or the core: ``minkplan offset`` exits 1 (no result) and writes nothing. A
    :class:`GeometryError` as before, for callers that catch that."""


class ScenarioError(MinkplanError, ValueError):
    """A scenario YAML file is invalid.

    Attributes:
        field: dotted name of the offending field (``"robot.mesh"``), or ``None`` when the
            problem is not tied to one field (e.g. a YAML syntax error).
        line: 1-based line number in the YAML file, or ``None`` when unknown.
        details: what a report should say about it beyond the message (JSON values), e.g.
            the penetration depth of parts that overlap in an assembled pose; or ``None``.
    """

    def __init__(
        self, message: object = "", *, field: str | None = None, line: int | None = None,
        details: dict | None = None,
    ) -> None:
        super().__init__(message)
        self.field = field
        self.line = line
        self.details = details

    def __reduce__(self):  # keep field, line and details through pickling (multiprocessing)
        return (_rebuild_scenario_error,
                (type(self), self.args, self.field, self.line, self.details))


def _rebuild_scenario_error(cls, args, field, line, details=None):
    error = cls(*args, field=field, line=line, details=details)
    return error
