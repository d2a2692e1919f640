"""The assembly YAML reader (the format is in ``docs/assembly.md``).

Entry points: :func:`read_assembly` (a file) and :func:`parse_assembly` (text or a
mapping), both to a validated :class:`~planner.problem.Assembly`: parts read like a
scenario's obstacles (:mod:`planner.io.parts`), posed at their assembled pose, the
contact tolerance given or defaulted, and the assembled pose checked for overlaps beyond
it (FCL; an overlap is reported with its penetration depth, also in the error's
``details`` for ``report.json``). Errors as for scenarios: ``"<file>:<line>: <field>: <problem>"``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from planner.problem import DEFAULT_CONTACT_REL, Assembly, Part
from planner.validation import FclChecker

from .fields import (
    Document,
    check_mapping,
    field_error,
    name_of,
    parse_document,
    read_text,
    real,
    settings_from_mapping,
)
from .parts import OBSTACLE_KEYS, assign_names, build_part, object_spec

__all__ = ["parse_assembly", "read_assembly"]

log = logging.getLogger(__name__)

# cells the depth of an overlap may search (an error message's detail: kept cheap; a search
# cut short still gives a proved, wider interval)
_DEPTH_CELLS = 100_000


TOP_LEVEL_KEYS = ("name", "units", "parts", "base", "contact_tolerance", "planner")


def read_assembly(path: str | os.PathLike[str]) -> Assembly:
    """Read and validate an assembly YAML file (mesh paths relative to its folder).

    Raises:
        ScenarioError: one line, ``"<file>:<line>: <field>: <problem>"``.
    """
    path = Path(path)
    return parse_document(read_text(path, "assembly"), Document(str(path)),
                          lambda data: _build(data, path.parent, path.resolve(), path.stem))


def parse_assembly(source: str | Mapping[str, Any], base_dir: str | os.PathLike[str] | None = None,
                   *, filename: str | None = None) -> Assembly:
    """An :class:`Assembly` from YAML text or a mapping (see :func:`read_assembly`)."""
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    return parse_document(source, Document(filename or "<assembly>"),
                          lambda data: _build(data, base, None, "assembly"))


def _build(data: Any, base_dir: Path, path: Path | None, default_name: str) -> Assembly:
    if data is None:
        raise field_error("", "the assembly is empty; it needs a list of parts")
    if isinstance(data, Mapping) and "robot" in data and "parts" not in data:
        raise field_error("robot", "this looks like a planning scenario (minkplan plan); an "
                              "assembly lists its parts under 'parts:'")
    top = check_mapping(data, "", TOP_LEVEL_KEYS, ("parts",))
    name = default_name if top.get("name") is None else name_of(top["name"], "name")
    units = "unitless" if top.get("units") is None else name_of(top["units"], "units")
    settings = settings_from_mapping(top.get("planner"), field="planner")
    raw = top["parts"]
    if not isinstance(raw, (list, tuple)) or len(raw) < 1:
        raise field_error("parts", "expected a non-empty list of parts")
    specs = [object_spec(value, f"parts[{i}]", OBSTACLE_KEYS, base_dir)
             for i, value in enumerate(raw)]
    names = assign_names(specs)
    base = None
    if top.get("base") is not None:
        base = name_of(top["base"], "base")
        if base not in names:
            raise field_error("base", f"'{base}' is not a part (parts: {', '.join(names)})")
    delta = None
    if top.get("contact_tolerance") is not None:
        delta = real(top["contact_tolerance"], "contact_tolerance")
        if delta < 0:
            raise field_error("contact_tolerance", f"must be >= 0, got {delta:g}")
    if settings.contact_tolerance is not None:
        if delta is not None and not math.isclose(delta, settings.contact_tolerance):
            raise field_error("planner.contact_tolerance",
                         f"{settings.contact_tolerance:g} differs from contact_tolerance "
                         f"{delta:g}; give it once")
        delta = settings.contact_tolerance
    cache: dict = {}
    parts = [build_part(spec, part_name, cache, spec.pose.matrix)
             for spec, part_name in zip(specs, names, strict=True)]
    if delta is None:
        bounds = np.array([p.mesh.bounds for p in parts])
        delta = DEFAULT_CONTACT_REL * float(np.linalg.norm(bounds[:, 1].max(axis=0)
                                                           - bounds[:, 0].min(axis=0)))
    settings = dataclasses.replace(settings, contact_tolerance=delta)
    _check_assembled_pose(parts, delta)
    return Assembly(name=name, units=units, parts=parts, base=base, contact_tolerance=delta,
                    settings=settings, path=path)


def _check_assembled_pose(parts: list[Part], delta: float) -> None:
    """The assembled pose must be valid: no part overlaps another beyond the tolerance. An
    overlap is reported with its penetration depth (computed for that pair only)."""
    for i, part in enumerate(parts):
        others = parts[i + 1:]
        if not others:
            continue
        checker = FclChecker.for_parts(part, others, contact_tolerance=delta)
        if checker.is_valid(np.zeros(3)):
            continue
        hit = checker.colliding_obstacle(np.zeros(3))
        other = next((p for p in others if hit and p.name == hit[0]), None)
        name = other.name if other is not None else "another part"
        depth = _overlap_depth(part, other) if other is not None else None
        said = "" if depth is None else (
            f"; penetration depth in [{depth['lower']:.6g}, {depth['upper']:.6g}] along "
            f"({', '.join(f'{x:.4g}' for x in depth['direction'])})")
        error = field_error(f"parts[{i}]", f"part '{part.name}' collides with '{name}' in "
                                           f"the assembled pose (overlap beyond contact "
                                           f"tolerance {delta:g}, or clamped between faces "
                                           f"on opposite sides){said}")
        error.details = {"overlap": {"part": part.name, "other": name,
                                     "contact_tolerance": delta, "penetration_depth": depth}}
        raise error


def _overlap_depth(part: Part, other: Part) -> dict | None:
    """The penetration depth of ``part`` into ``other`` (JSON values), or ``None`` when it
    is not defined (a surface) or cannot be computed."""
    if not (part.solid and other.solid):
        return None
    from planner.depth import penetration_depth  # noqa: PLC0415
    from planner.errors import MinkplanError  # noqa: PLC0415

    try:
        result = penetration_depth(part, other, validate=False, max_cells=_DEPTH_CELLS)
    except MinkplanError as exc:
        log.warning("penetration depth of %s into %s not computed: %s", part.name,
                    other.name, exc)
        return None
    out = result.describe()
    out.pop("validated")
    return out
