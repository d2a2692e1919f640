"""The assembly YAML reader (the format is in ``docs/assembly.md``).

Entry points: :func:`read_assembly` (a file) and :func:`parse_assembly` (text or a
mapping), both to a validated :class:`~planner.problem.Assembly`: parts read like a
scenario's obstacles (:mod:`planner.io.parts`), posed at their assembled pose, the
contact tolerance given or defaulted, and the assembled pose checked for overlaps beyond
it plus the ``interference`` tolerance the user may state (FCL; an overlap is reported
with its penetration depth, also in the error's ``details`` for ``report.json``; the
overlaps an interference tolerance accepts are listed in ``Assembly.overlaps``). Errors
as for scenarios: ``"<file>:<line>: <field>: <problem>"``.
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

from planner.errors import ScenarioError
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

# how many times, at most, an overlap's depth is found again finer while the tolerance
# lies inside its interval (each halves the gap below the tolerance: about twice the cells)
_FINER_DEPTHS = 3


TOP_LEVEL_KEYS = ("name", "units", "parts", "base", "contact_tolerance", "interference",
                  "planner")


def read_assembly(path: str | os.PathLike[str], *,
                  interference: float | None = None) -> Assembly:
    """Read and validate an assembly YAML file (mesh paths relative to its folder).
    ``interference`` (units, ``>= 0``) replaces the file's ``interference``.

    Raises:
        ScenarioError: one line, ``"<file>:<line>: <field>: <problem>"``.
    """
    path = Path(path)
    return parse_document(read_text(path, "assembly"), Document(str(path)),
                          lambda data: _build(data, path.parent, path.resolve(), path.stem,
                                              interference))


def parse_assembly(source: str | Mapping[str, Any], base_dir: str | os.PathLike[str] | None = None,
                   *, filename: str | None = None,
                   interference: float | None = None) -> Assembly:
    """An :class:`Assembly` from YAML text or a mapping (see :func:`read_assembly`)."""
    base = Path(base_dir) if base_dir is not None else Path.cwd()
    return parse_document(source, Document(filename or "<assembly>"),
                          lambda data: _build(data, base, None, "assembly", interference))


def _interference(top: Mapping[str, Any], given: float | None) -> tuple[float, str]:
    """The interference tolerance and where it is set: ``given`` (the command line's,
    ``"--interference"``), else the file's (``"interference"``), else ``0`` (the file's
    field, where it would be set)."""
    if given is not None:
        value, where = float(given), "--interference"
    elif top.get("interference") is not None:
        value, where = real(top["interference"], "interference"), "interference"
    else:
        return 0.0, "interference"
    if not (math.isfinite(value) and value >= 0):
        raise field_error(where, f"must be a finite number >= 0, got {value:g}")
    return value, where


def _build(data: Any, base_dir: Path, path: Path | None, default_name: str,
           given_interference: float | None = None) -> Assembly:
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
    interference, interference_field = _interference(top, given_interference)
    cache: dict = {}
    parts = [build_part(spec, part_name, cache, spec.pose.matrix)
             for spec, part_name in zip(specs, names, strict=True)]
    if delta is None:
        bounds = np.array([p.mesh.bounds for p in parts])
        delta = DEFAULT_CONTACT_REL * float(np.linalg.norm(bounds[:, 1].max(axis=0)
                                                           - bounds[:, 0].min(axis=0)))
    settings = dataclasses.replace(settings, contact_tolerance=delta + interference)
    overlaps = _accepted_overlaps(parts, delta, interference, base) if interference > 0 else ()
    parts = _with_escape_hints(parts, overlaps)
    parts = _check_assembled_pose(parts, delta, interference, overlaps, base=base,
                                  interference_field=interference_field)
    return Assembly(name=name, units=units, parts=parts, base=base, contact_tolerance=delta,
                    settings=settings, path=path, interference=interference,
                    overlaps=overlaps)


# the largest tolerance, as a fraction of the scene, searched for a suggested interference
_SUGGEST_UPTO = 0.1


def _check_assembled_pose(parts: list[Part], delta: float, interference: float = 0.0,
                          overlaps: tuple[dict, ...] = (), base: str | None = None,
                          interference_field: str = "interference") -> list[Part]:
    """The assembled pose must be valid: no part overlaps another beyond the contact
    tolerance plus the interference tolerance, pair by pair (one part checked against
    all later ones at once first: a witness that frees it from all frees it from each).
    A pair FCL's check refuses is tried again along its penetration depth's direction;
    when that frees it (a depth within the tolerance, whose way out is along no contact
    normal or axis), the parts keep that direction as an escape hint. Else the overlap is
    reported for the part to move (:func:`_moving`), with its penetration depth (from
    ``overlaps`` when it is there, else computed for that pair only), its advice naming
    ``interference_field`` (where the interference tolerance is set, see
    :func:`_interference`). Returns the parts with those hints."""
    allowed = delta + interference
    hints: dict[str, list[tuple[float, float, float]]] = {}
    origin = np.zeros(3)
    for i, part in enumerate(parts):
        others = parts[i + 1:]
        if not others or FclChecker.for_parts(part, others,
                                              contact_tolerance=allowed).is_valid(origin):
            continue
        for other in others:
            checker = FclChecker.for_parts(part, [other], contact_tolerance=allowed)
            if checker.is_valid(origin):
                continue
            mover, fixed = _moving(part, other, base)
            depth = _known_depth(overlaps, mover, fixed, allowed)
            way_out = _hint(depth if mover is part else _reversed(depth))  # part's way
            if way_out is not None and way_out not in part.escape_hints:  # tried first
                hinted = dataclasses.replace(part, escape_hints=part.escape_hints + (way_out,))
                checker = FclChecker.for_parts(hinted, [other], contact_tolerance=allowed)
                if checker.is_valid(origin):
                    hints.setdefault(part.name, []).append(way_out)
                    hints.setdefault(other.name, []).append((-way_out[0], -way_out[1],
                                                             -way_out[2]))
                    continue
            raise _overlap_error(parts, (mover, fixed), checker, (delta, interference),
                                 depth, interference_field)
    return [dataclasses.replace(p, escape_hints=p.escape_hints + tuple(hints[p.name]))
            if p.name in hints else p for p in parts]


def _known_depth(overlaps: tuple[dict, ...], mover: Part, fixed: Part,
                 allowed: float) -> dict | None:
    """The penetration depth of ``mover`` into ``fixed`` (JSON values): from the accepted
    ``overlaps`` when it is there, else computed (:func:`_overlap_depth`)."""
    known = {(o["part"], o["other"]): o["penetration_depth"] for o in overlaps}
    key = (mover.name, fixed.name)
    return known[key] if key in known else _overlap_depth(mover, fixed, allowed)


def _overlap_error(parts: list[Part], moving: tuple[Part, Part], checker: FclChecker,
                   tolerances: tuple[float, float], depth: dict | None,
                   interference_field: str = "interference") -> ScenarioError:
    """The error for ``moving`` (the part to move, and the one it overlaps; ``depth``:
    the first's penetration depth into the second) overlapping beyond the ``(contact,
    interference)`` tolerances, as FCL's ``checker`` of the pair (its depth's direction
    tried) refused it: the moving part's entry, its depth and the interference
    tolerance that accepts the pose, to be set as ``interference_field`` says
    (:func:`_interference_advice`)."""
    delta, interference = tolerances
    mover, fixed = moving
    suggested = _interference_accepting(checker, delta, depth)
    said = "" if depth is None else (
        f"; penetration depth in [{depth['lower']:.6g}, {depth['upper']:.6g}] "
        f"(tolerance {depth['tolerance']:.2g}) along ({_direction_text(depth['direction'])})")
    if depth is None and not (mover.solid and fixed.solid):
        said = "; no penetration depth (a surface has no inside)"
    beyond = (f"contact tolerance {delta:g}" if interference == 0 else
              f"contact tolerance {delta:g} + interference {interference:g}")
    hint = "" if suggested is None else (
        f"; to accept it as an interference fit, "
        f"{_interference_advice(suggested, interference_field, depth is not None)}")
    error = field_error(f"parts[{parts.index(mover)}]",
                        f"part '{mover.name}' collides with '{fixed.name}' in the assembled "
                        f"pose (overlap beyond {beyond}, or clamped between faces on "
                        f"opposite sides){said}{hint}")
    error.details = {"overlap": {"part": mover.name, "other": fixed.name,
                                 "contact_tolerance": delta,
                                 "interference": interference,
                                 "penetration_depth": depth,
                                 "suggested_interference":
                                     None if suggested is None else float(suggested)}}
    return error


def _interference_advice(suggested: str, field: str, at_least: bool) -> str:
    """``"give interference: 0.021 or more in the assembly file"``: the ``suggested``
    tolerance set where the one in force was (``field``): with the option
    ``--interference`` when the command line gave it (it replaces the file's), else in
    the file, which every command reads (``minkplan batch`` has no such option).
    ``at_least``: any larger tolerance accepts the pose too (a known depth); else it is
    the one FCL's check was found to accept."""
    given = (f"give --interference {suggested}" if field.startswith("--")
             else f"give interference: {suggested}")
    more = " or more" if at_least else ""
    where = "" if field.startswith("--") else " in the assembly file"
    accepted = "" if at_least else " (FCL's check accepts the pose with it)"
    return f"{given}{more}{where}{accepted}"


def _direction_text(direction) -> str:
    """A unit direction as a message gives it: components within rounding of zero (below
    1e-12) as 0, not as ``1.7e-16``."""
    return ", ".join(f"{0.0 if abs(x) < 1e-12 else x:.4g}" for x in direction)


def _moving(part: Part, other: Part, base: str | None) -> tuple[Part, Part]:
    """``(the part to move, the one it overlaps)`` of two overlapping parts, ``other``
    listed after ``part``: the later one, unless it is the base (parts are listed in
    assembly order, the base or the fixed part first)."""
    return (part, other) if other.name == base else (other, part)


def _reversed(depth: dict | None) -> dict | None:
    """A penetration depth of one part into another (JSON values) as the other's: the
    same interval, the direction and translation reversed."""
    if depth is None:
        return None
    flip = {key: [-float(x) for x in depth[key]] for key in ("direction", "translation")}
    return {**depth, **flip}


def _interference_accepting(checker: FclChecker, delta: float, depth: dict | None) -> str | None:
    """The interference tolerance to suggest for a rejected assembled pose, as written
    in the message: the penetration depth's upper bound less the contact tolerance (then
    all of it) rounded up when it is known (solids), else the smallest tolerance found
    under which FCL's check accepts the pose (:meth:`FclChecker.tolerance_accepting`, a
    surface). Only a value the check accepts
    (contact tolerance plus it) is suggested; ``None`` when none was found."""
    origin = np.zeros(3)
    if depth is not None:  # what the contact tolerance leaves to cover, then all of it
        candidates = [max(depth["upper"] - delta, 0.0), depth["upper"]]
    else:
        needed = checker.tolerance_accepting(origin, upto=_SUGGEST_UPTO * checker.scale)
        candidates = [] if needed is None else [needed - delta]
    for extra in candidates:
        for text in (_round_up(extra), repr(float(extra))):
            if checker.accepts_with(origin, delta + float(text)):
                return text
    return None


def _round_up(x: float) -> str:
    """``x`` rounded up to two significant digits (a tolerance to suggest)."""
    if x <= 0:
        return "0"
    step = 10.0 ** (math.floor(math.log10(x)) - 1)
    return f"{math.ceil(x / step * (1 - 1e-12)) * step:.2g}"


def _accepted_overlaps(parts: list[Part], delta: float, interference: float,
                       base: str | None) -> tuple[dict, ...]:
    """The pairs that overlap beyond the contact tolerance (the interference tolerance
    accepted them), each for the part to move (:func:`_moving`) with its penetration
    depth."""
    allowed = delta + interference
    found = []
    for i, part in enumerate(parts):
        for other in parts[i + 1:]:
            checker = FclChecker.for_parts(part, [other], contact_tolerance=delta)
            if checker.is_valid(np.zeros(3)):
                continue
            mover, fixed = _moving(part, other, base)
            found.append({"part": mover.name, "other": fixed.name,
                          "penetration_depth": _overlap_depth(mover, fixed, allowed)})
    return tuple(found)


def _with_escape_hints(parts: list[Part], overlaps: tuple[dict, ...]) -> list[Part]:
    """The parts, each overlapping one given the directions its penetration depths free
    it along (the other part of a pair the reverse): FCL's tolerance checks try them, as
    no contact normal or axis frees a peg pushed sideways into its bore with its shoulder
    flush on the block."""
    hints: dict[str, list[tuple[float, float, float]]] = {}
    for overlap in overlaps:
        hint = _hint(overlap["penetration_depth"])
        if hint is None:
            continue
        hints.setdefault(overlap["part"], []).append(hint)
        hints.setdefault(overlap["other"], []).append((-hint[0], -hint[1], -hint[2]))
    return [dataclasses.replace(p, escape_hints=p.escape_hints + tuple(hints[p.name]))
            if p.name in hints else p for p in parts]


def _hint(depth: dict | None) -> tuple[float, float, float] | None:
    """The direction a penetration depth (JSON values) frees its part along, or ``None``
    (no depth, or parts apart)."""
    if depth is None or depth["separated"] or not any(depth["direction"]):
        return None
    x, y, z = (float(c) for c in depth["direction"])
    return (x, y, z)


def _overlap_depth(part: Part, other: Part, allowed: float | None = None) -> dict | None:
    """The penetration depth of ``part`` into ``other`` (JSON values), or ``None`` when it
    is not defined (a surface) or cannot be computed. While the tolerance ``allowed``
    (contact plus interference) lies inside its interval, the depth is found again to a
    width that tells them apart where it can (:data:`_FINER_DEPTHS` times at most): its
    direction is then the hint that frees the part within ``allowed`` (the default width
    left Factory's round peg, pushed 0.3 mm aslant into its hole, refused at 0.3 mm in
    [0.284, 0.308])."""
    if not (part.solid and other.solid):
        return None
    from planner.depth import FINEST_TOLERANCE, penetration_depth  # noqa: PLC0415
    from planner.errors import MinkplanError  # noqa: PLC0415

    def depth(tolerance: float | None = None):
        return penetration_depth(part, other, validate=False, max_cells=_DEPTH_CELLS,
                                 tolerance=tolerance)

    try:
        result = depth()
    except MinkplanError as exc:
        log.warning("penetration depth of %s into %s not computed: %s", part.name,
                    other.name, exc)
        return None
    size = float(np.linalg.norm(np.ptp(np.vstack([part.mesh.bounds, other.mesh.bounds]),
                                       axis=0)))
    for _ in range(_FINER_DEPTHS):
        if allowed is None or not result.lower < allowed < result.upper:
            break
        finer = max(0.5 * (allowed - result.lower), 1.01 * FINEST_TOLERANCE * size)
        if finer >= result.upper - result.lower:
            break
        try:
            result = depth(finer)
        except MinkplanError as exc:  # the coarser interval stands
            log.warning("penetration depth of %s into %s not found finer than %.3g: %s",
                        part.name, other.name, result.upper - result.lower, exc)
            break
    out = result.describe()
    out.pop("validated")
    return out
