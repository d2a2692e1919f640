"""Closed triangle meshes for the scenario primitives: box, sphere and cylinder.

Entry point: :func:`make_primitive`, which turns the primitive part of a scenario object
(``{box: [sx, sy, sz]}``, ``{sphere: r}``, ``{cylinder: {radius: r, height: h}}``) into a
watertight ``trimesh.Trimesh`` with outward normals, in the primitive's own frame:

- ``box: [sx, sy, sz]``: full side lengths, centred on the origin, edges along the axes.
- ``sphere: r`` or ``sphere: {radius: r, subdivisions: n}``: an icosphere centred on the
  origin (``n`` in 0..6, default 3: 642 vertices).
- ``cylinder: {radius: r, height: h, sections: n}``: axis along z, centred on the origin
  (``z`` in ``[-h/2, h/2]``), ``n >= 3`` sides (default 32).

Spheres and cylinders are *inscribed* polyhedra: their vertices lie on the true surface,
so the mesh is inside the curved solid by at most ``r * (1 - cos(pi / n))`` for a
cylinder with ``n`` sections (about 0.5 % of ``r`` at the default 32).

Errors are :class:`~planner.errors.ScenarioError` with the message
``"<field>.<key>: <problem>"`` and ``field`` set; the scenario loader adds the file name
and line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import trimesh

from .errors import ScenarioError

__all__ = ["PRIMITIVE_KINDS", "make_primitive"]

PRIMITIVE_KINDS = ("box", "sphere", "cylinder")
"""Keys that introduce a primitive in a scenario object."""

DEFAULT_SPHERE_SUBDIVISIONS = 3
DEFAULT_CYLINDER_SECTIONS = 32
_MAX_SPHERE_SUBDIVISIONS = 6
_MAX_CYLINDER_SECTIONS = 4096


def _fail(field: str, problem: str) -> ScenarioError:
    return ScenarioError(f"{field}: {problem}", field=field)


def _positive(value: Any, field: str, what: str) -> float:
    """A finite number > 0, else ScenarioError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise _fail(field, f"{what} must be a number, got {type(value).__name__} {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise _fail(field, f"{what} must be finite, got {value!r}")
    if number <= 0:
        raise _fail(field, f"{what} must be > 0, got {value!r}")
    return number


def _integer(value: Any, field: str, what: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise _fail(field, f"{what} must be an integer, got {type(value).__name__} {value!r}")
    if not low <= int(value) <= high:
        raise _fail(field, f"{what} must be in {low}..{high}, got {value!r}")
    return int(value)


def _check_keys(spec: Mapping, allowed: tuple[str, ...], required: tuple[str, ...],
                field: str) -> None:
    import difflib

    for key in spec:
        if key not in allowed:
            close = difflib.get_close_matches(str(key), allowed, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise _fail(f"{field}.{key}", f"unknown key{hint} (allowed: {', '.join(allowed)})")
    for key in required:
        if key not in spec:
            raise _fail(field, f"missing required key '{key}'")


def _box(value: Any, field: str) -> trimesh.Trimesh:
    if not isinstance(value, (list, tuple)):
        raise _fail(field, f"expected a list of 3 side lengths [sx, sy, sz], got "
                           f"{type(value).__name__} {value!r}")
    if len(value) != 3:
        raise _fail(field, f"expected 3 side lengths [sx, sy, sz], got {len(value)}")
    extents = [_positive(v, f"{field}[{i}]", "side length") for i, v in enumerate(value)]
    return trimesh.creation.box(extents=extents)


def _sphere(value: Any, field: str) -> trimesh.Trimesh:
    subdivisions = DEFAULT_SPHERE_SUBDIVISIONS
    if isinstance(value, Mapping):
        _check_keys(value, ("radius", "subdivisions"), ("radius",), field)
        radius = _positive(value["radius"], f"{field}.radius", "radius")
        if "subdivisions" in value:
            subdivisions = _integer(value["subdivisions"], f"{field}.subdivisions",
                                    "subdivisions", 0, _MAX_SPHERE_SUBDIVISIONS)
    else:
        radius = _positive(value, field, "radius")
    return trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)


def _cylinder(value: Any, field: str) -> trimesh.Trimesh:
    if not isinstance(value, Mapping):
        raise _fail(field, f"expected a mapping {{radius: r, height: h}}, got "
                           f"{type(value).__name__} {value!r}")
    _check_keys(value, ("radius", "height", "sections"), ("radius", "height"), field)
    radius = _positive(value["radius"], f"{field}.radius", "radius")
    height = _positive(value["height"], f"{field}.height", "height")
    sections = DEFAULT_CYLINDER_SECTIONS
    if "sections" in value:
        sections = _integer(value["sections"], f"{field}.sections", "sections", 3,
                            _MAX_CYLINDER_SECTIONS)
    return trimesh.creation.cylinder(radius=radius, height=height, sections=sections)


_BUILDERS = {"box": _box, "sphere": _sphere, "cylinder": _cylinder}


def make_primitive(spec: Mapping[str, Any], *, field: str) -> trimesh.Trimesh:
    """Build the closed mesh of a primitive.

    Args:
        spec: a mapping holding exactly one of the keys ``box``, ``sphere``,
            ``cylinder`` (other keys, such as ``name`` or ``position``, are ignored),
            e.g. ``{"box": [1, 2, 3]}`` or ``{"cylinder": {"radius": 1, "height": 4}}``.
        field: dotted name of the object in the scenario (``"obstacles[2]"``), used in
            error messages (``"obstacles[2].cylinder.radius: radius must be > 0 ..."``).

    Returns:
        A watertight ``trimesh.Trimesh`` with consistent outward winding (positive
        volume), in the primitive's own frame (centred on the origin; cylinder axis z).

    Raises:
        ScenarioError: no or several primitive keys, a wrong type, a size that is not a
            finite number > 0, an unknown key, a bad ``sections``/``subdivisions``.
    """
    if not isinstance(spec, Mapping):
        raise _fail(field, f"expected a mapping, got {type(spec).__name__} {spec!r}")
    kinds = [kind for kind in PRIMITIVE_KINDS if kind in spec]
    if not kinds:
        raise _fail(field, f"no primitive given: expected one of {', '.join(PRIMITIVE_KINDS)}")
    if len(kinds) > 1:
        raise _fail(field, f"give only one of {', '.join(kinds)}")
    kind = kinds[0]
    return _BUILDERS[kind](spec[kind], f"{field}.{kind}")
