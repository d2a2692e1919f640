"""Translational penetration depth of two closed solids, as a proved interval.

``penetration_depth(a, b)``: the length of the shortest translation ``t`` of ``A`` after
which ``A + t`` and ``B`` no longer overlap, which is the distance from the origin to the
boundary of the C-obstacle ``CO = B ⊕ (−A) = {t : (A + t) ∩ B ≠ ∅}`` (the origin lies in
it when they overlap). For disjoint parts, the separation distance instead, as a negative
depth.

It is computed on the exact source (the reduced boundary convolution of the two meshes,
no mesh extraction, no decomposition) by the native core's
:meth:`~planner._minkowski_core.ExactSum.depth`, which rests on two facts:

- every boundary point of ``CO`` lies on a reduced-convolution facet (a boundary point is
  a contact of ``A + t`` and ``B`` with disjoint interiors, where both are locally
  extreme in a common direction; the facets are exactly the feature pairs that can be,
  tested conservatively, so the set can only be too large, never too small);
- every facet lies in ``CO`` (its points are contacts).

So the **lower bound** is proved: no boundary point is nearer to the origin than the
nearest facet, nor nearer than any octree cell around the origin that is not shown FULL
by the core's exact tests (one triangle-pair piece containing the cell, a vertex of one
part inside the other for every translation of the cell, or no facet in the cell and its
centre inside); the search goes best first over those cells, nearest first, until the
gap closes. The **upper bound** is the length of a translation proved free: outside
``CO`` by the exact point query (or in a cell no facet meets, its centre outside), and
checked with FCL here (``A`` moved by it overlaps ``B`` by no more than the tolerance).
Outside ``CO`` the nearest point of ``CO`` lies on a facet and every facet is in ``CO``,
so the separation distance is the smallest point–facet distance, exact up to rounding.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from .blas import single_blas_thread
from .errors import InvalidMeshError, InvalidParameterError, ResourceLimitError
from .operands import solid_part
from .problem import Part
from .progress import StatusLine
from .sources import ExactSource, Source, SourceSettings
from .tolerances import tol

__all__ = ["PenetrationDepth", "penetration_depth"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PenetrationDepth:
    """The penetration depth of ``A`` into ``B`` (or their separation), proved bounds.

    Attributes:
        lower, upper: the depth lies in ``[lower, upper]``, ``upper - lower <= tolerance``
            when ``converged``; both ``-distance`` when the parts are separated.
        direction: ``(3,)`` unit vector: the direction to move ``A`` (out of ``B`` when
            they overlap, towards ``B`` when separated).
        translation: ``(3,)`` the translation of ``A``: overlapping, a separating one of
            length ``upper``; separated, the shortest one that brings them into contact.
        separated: the parts do not touch (then ``distance > 0``); touching parts are in
            contact (depth ``0``: ``lower == 0``, ``upper <= tolerance``).
        distance: the separation distance (``0`` when they touch or overlap).
        tolerance: the interval width asked for (absolute).
        converged: ``upper - lower <= tolerance`` was reached within the cell budget.
        validated: FCL agrees: ``A`` moved by ``translation`` overlaps ``B`` by at most
            ``tolerance`` (overlapping), or FCL's distance matches and ``A`` moved by
            ``translation`` touches ``B`` within ``tolerance`` (separated).
        stats: cells classified, facets (of the reduced convolution, those the search
            could reach when the parts overlap), ``smallest_cells`` (cells of the smallest size
            the search could not resolve: when not converged, what held the lower bound
            down), seconds, FCL's own distance at the origin (``None`` without
            ``validate``), ``changes`` (per operand, ``"a"`` and ``"b"``: what was changed
            to make it a solid, ``{"t_junctions_split": 28}``; empty when nothing was).
    """

    lower: float
    upper: float
    direction: np.ndarray = field(repr=False)
    translation: np.ndarray = field(repr=False)
    separated: bool
    distance: float
    tolerance: float
    converged: bool
    validated: bool
    stats: dict = field(repr=False, compare=False)

    @property
    def depth(self) -> float:
        """The midpoint of ``[lower, upper]`` (negative: the separation distance)."""
        return 0.5 * (self.lower + self.upper)

    def describe(self) -> dict:
        """The result as plain JSON values (reports, the CLI)."""
        return {"lower": self.lower, "upper": self.upper,
                "direction": [float(x) for x in self.direction],
                "translation": [float(x) for x in self.translation],
                "separated": self.separated, "distance": self.distance,
                "tolerance": self.tolerance, "converged": self.converged,
                "validated": self.validated, "stats": self.stats}


def _tolerance(tolerance, size: float) -> float:
    if tolerance is None:
        return tol.depth_rel * max(size, 1e-300)
    try:
        value = float(tolerance)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"tolerance = {tolerance!r}: must be a positive number") \
            from None
    if not (math.isfinite(value) and value > 0.0):
        raise InvalidParameterError(f"tolerance = {tolerance!r}: must be a positive finite "
                                    "number")
    floor = FINEST_TOLERANCE * size
    if value < floor:
        raise InvalidParameterError(
            f"tolerance = {tolerance!r}: below {FINEST_TOLERANCE:g} of the pair's size "
            f"({size:.4g}); each tenfold finer costs about ten times the cells (1e-8 of it "
            f"took minutes); use at least {floor:.3g}")
    ceiling = COARSEST_TOLERANCE * size
    if value > ceiling:
        raise InvalidParameterError(
            f"tolerance = {tolerance!r}: more than {COARSEST_TOLERANCE:g} of the pair's size "
            f"({size:.4g}), so the interval would say next to nothing about the depth; use "
            f"at most {ceiling:.3g}")
    return value


FINEST_TOLERANCE = 1e-6
"""The finest interval width :func:`penetration_depth` takes, as a fraction of the pair's
size: the search's cells grow about tenfold per decade of it."""

COARSEST_TOLERANCE = 0.1
"""The widest interval :func:`penetration_depth` takes, as a fraction of the pair's size
(the diagonal of the box around both): a depth is at most about that size, so an interval
wider than a tenth of it says next to nothing (``1e3`` on 6 cm parts gave [0.0003, 250])."""


def _fcl_check(a: Part, b: Part, translation: np.ndarray, separated: bool, distance: float,
               tolerance: float) -> tuple[bool, float | None]:
    """Whether FCL agrees, and FCL's distance at the origin (overlapping: ``A`` moved by
    ``translation`` is valid under the contact tolerance ``tolerance``; separated: the
    distances match and ``A`` moved by it touches ``B`` within ``tolerance``)."""
    from .validation import FclChecker  # noqa: PLC0415

    checker = FclChecker(a.mesh, [b.mesh], contact_tolerance=tolerance)
    fcl_distance = checker.distance(np.zeros(3))
    if separated:
        # its distance, and A moved by the translation touching B within the tolerance
        agrees = abs(fcl_distance - distance) <= 1e-9 * max(distance, 1e-300) + 1e-12
        touches = checker.distance(translation) <= tolerance and checker.is_valid(translation)
        return agrees and touches, fcl_distance
    return checker.is_valid(translation), fcl_distance


@single_blas_thread
def penetration_depth(a, b, *, tolerance: float | None = None,
                      max_cells: int | None = None, validate: bool = True,
                      source: Source | None = None,
                      progress: bool | None = None, repair: bool = False) -> PenetrationDepth:
    """The translational penetration depth of solid ``a`` into solid ``b``.

    The length of the shortest translation ``t`` with ``(A + t) ∩ B = ∅`` (interiors), as
    a proved interval ``[lower, upper]`` (see the module documentation); for disjoint
    parts, the separation distance as a negative depth (``separated=True``).

    Args:
        a, b: closed solids: ``trimesh.Trimesh``, ``(vertices, faces)``, a mesh file path,
            or a :class:`~planner.problem.Part`; posed in one frame.
        tolerance: the widest interval wanted (absolute); default ``tol.depth_rel`` (1e-3)
            of the pair's size (the diagonal of the box around both); from
            :data:`FINEST_TOLERANCE` to :data:`COARSEST_TOLERANCE` of it.
        max_cells: cells the search may classify (default ``tol.depth_max_cells``, else
            from the memory limit: :meth:`planner.budget.MemoryBudget.depth_cells`); a
            search stopped by it returns a wider, still proved, interval
            (``converged=False``, with a warning).
        validate: check the answer with FCL (see :attr:`PenetrationDepth.validated`).
        source: an exact :class:`~planner.sources.Source` whose checked meshes to reuse
            (another kind is refused).
        progress: a status line on stderr naming the stage (:mod:`planner.progress`;
            ``None``: only when stderr is a terminal).
        repair: an operand that is no closed solid may have its holes filled
            (:func:`planner.meshes.repair_mesh`; a :class:`~planner.problem.Part` is
            taken as it is); ``stats["changes"]`` says what was changed to make each
            operand a solid (split T-junctions too, which need no ``repair``).

    Returns:
        :class:`PenetrationDepth`.

    Raises:
        InvalidMeshError: an operand is not a closed solid (even repaired, with
            ``repair``) or cannot be read.
        InvalidParameterError: ``tolerance`` or ``max_cells`` is out of range.
    """
    t0 = time.perf_counter()
    part_a, part_b = solid_part(a, "a", repair=repair), solid_part(b, "b", repair=repair)
    if not (part_a.solid and part_b.solid):
        raise InvalidMeshError("penetration depth: both parts must be solids (a surface has "
                               "no inside to penetrate)")
    bounds = np.vstack([part_a.mesh.bounds, part_b.mesh.bounds])
    width = _tolerance(tolerance, float(np.linalg.norm(bounds.max(axis=0) - bounds.min(axis=0))))
    if max_cells is not None:
        cells = int(max_cells)
    elif tol.depth_max_cells is not None:
        cells = int(tol.depth_max_cells)
    else:
        from . import budget  # noqa: PLC0415

        cells = budget.current().depth_cells()
    if cells < 1:
        raise InvalidParameterError(f"max_cells = {max_cells!r}: must be >= 1")
    if source is not None and source.kind != "exact":
        raise InvalidParameterError(f"source: the depth is computed on the exact source, got "
                                    f"the {source.kind} source")
    source = source or ExactSource(SourceSettings(exact=True), "penetration depth")
    what = f"minkplan: depth of {part_a.name} into {part_b.name}"
    with StatusLine(progress) as line:
        try:
            found, facets = _search(source, (part_a, part_b), width, cells,
                                    lambda stage: line.show(f"{what}: {stage}"))
        except ResourceLimitError as exc:
            from . import budget  # noqa: PLC0415

            raise budget.explain(exc, f"penetration depth of {part_a.name} into "
                                      f"{part_b.name}", decomposition=False) from exc
        if validate:
            line.show(f"{what}: checking the answer with FCL")
        result = _result(found, (part_a, part_b), facets, width, validate, t0)
    _log(result, part_a.name, part_b.name, validate)
    return result


def _search(source: Source, parts: tuple[Part, Part], width: float, cells: int,
            show) -> tuple[dict, int]:
    """The core's answer at the origin of ``B ⊕ (−A)`` and the facets it searched: those
    of the cube the search can reach first (:meth:`ExactSource.depth_pair`: two parts
    that overlap a little have few there), the whole reduced convolution when the
    question reaches beyond them (parts apart, the separation farther than that cube); no
    convolution when the parts' boxes lie apart (:func:`_separation`)."""
    part_a, part_b = parts
    origin = np.zeros(3)
    (a_lo, a_hi), (b_lo, b_hi) = part_a.mesh.bounds, part_b.mesh.bounds
    gap = np.maximum(b_lo - a_hi, a_lo - b_hi)  # per axis: > 0 apart, < 0 overlapping
    if np.any(gap > 0.0):  # apart, not touching
        show("the least distance between the parts' triangles")
        return _separation(part_a, part_b), 0
    if isinstance(source, ExactSource) and np.all(gap < 0.0):
        show("convolution facets near the origin")
        near = source.depth_pair(part_b, part_a, origin, width)
        show(f"searching cells down to a {width:.3g} wide interval")
        try:
            return near.native.depth(origin, width, max_cells=cells), int(near.stats["facets"])
        except InvalidParameterError as exc:
            if not str(exc).startswith("depth region"):
                raise
            log.debug("%s into %s: the separation reaches beyond the facets near the origin; "
                      "the whole convolution instead", part_a.name, part_b.name)
        del near  # (its memory back before the whole convolution's)
    show("convolution facets")
    pair = source.pair(part_b, part_a, mirror_b=True)  # B ⊕ (−A)
    show(f"searching cells down to a {width:.3g} wide interval")
    return pair.native.depth(origin, width, max_cells=cells), int(pair.stats["facets"])


def _separation(a: Part, b: Part) -> dict:
    """The core's answer for two parts whose boxes lie apart, without the convolution
    (parts far apart made one of several GiB): they are disjoint, so their separation is
    the least distance between their triangles, FCL's (exact up to rounding over every
    pair its BVHs do not rule out), and the translation that makes them touch takes
    ``A``'s nearest point to ``B``'s."""
    import fcl  # noqa: PLC0415

    from .validation.fcl_checker import bvh_model  # noqa: PLC0415

    t0 = time.perf_counter()
    obj_a, obj_b = (fcl.CollisionObject(bvh_model(p.mesh.vertices, p.mesh.faces), fcl.Transform())
                    for p in (a, b))
    result = fcl.DistanceResult()
    distance = float(fcl.distance(obj_a, obj_b, fcl.DistanceRequest(enable_nearest_points=True),
                                  result))
    on_a, on_b = (np.asarray(p, dtype=np.float64) for p in result.nearest_points)
    return {"point": on_b - on_a, "inside": False, "lower": distance, "upper": distance,
            "cells": 0, "facets_tried": 0, "smallest_cells": 0, "converged": True,
            "seconds": time.perf_counter() - t0, "method": SEPARATION_BY_TRIANGLES}


SEPARATION_BY_TRIANGLES = "the least distance between the triangles (their boxes lie apart)"
"""``stats["method"]`` of a depth whose parts' boxes lie apart (:func:`_separation`); else
:data:`BY_CONVOLUTION`."""

BY_CONVOLUTION = "the exact convolution's facets and cells"
"""``stats["method"]`` of a depth searched on the exact source."""


def _result(found: dict, parts: tuple[Part, Part], facets: int, width: float, validate: bool,
            t0: float) -> PenetrationDepth:
    """The core's answer as a :class:`PenetrationDepth`, checked with FCL (``validate``)."""
    point = np.asarray(found["point"], dtype=np.float64)
    length = float(np.linalg.norm(point))
    direction = point / length if length > 0.0 else np.zeros(3)
    separated = not found["inside"]
    distance = float(found["upper"]) if separated else 0.0
    lower, upper = ((-distance, -distance) if separated
                    else (float(found["lower"]), float(found["upper"])))
    validated, fcl_distance = (_fcl_check(*parts, point, separated, distance, width)
                               if validate else (False, None))
    stats = {"cells": int(found["cells"]), "facets": facets,
             "facets_tried": int(found["facets_tried"]),
             "smallest_cells": int(found["smallest_cells"]), "fcl_distance": fcl_distance,
             "method": found.get("method", BY_CONVOLUTION),
             "changes": {"a": dict(parts[0].repairs), "b": dict(parts[1].repairs)},
             "seconds": {"search": float(found["seconds"]),
                         "total": time.perf_counter() - t0}}
    return PenetrationDepth(lower=lower, upper=upper, direction=direction, translation=point,
                            separated=separated, distance=distance, tolerance=width,
                            converged=bool(found["converged"]), validated=validated,
                            stats=stats)


def _log(result: PenetrationDepth, a: str, b: str, validate: bool) -> None:
    if not result.converged:
        stuck = result.stats["smallest_cells"]
        why = (f"{stuck} cells of the smallest size (tolerance / 8) could not be shown inside "
               "the C-obstacle; a larger tolerance may help" if stuck else
               "the cell budget ran out; raise max_cells or the tolerance")
        log.warning("%s into %s: the depth search stopped after %d cells with [%.6g, %.6g], "
                    "wider than %.3g: %s", a, b, result.stats["cells"], result.lower,
                    result.upper, result.tolerance, why)
    if validate and not result.validated:
        log.warning("%s into %s: FCL disagrees with the depth result (FCL distance %.6g); "
                    "please report this input", a, b, result.stats["fcl_distance"])
    log.info("%s into %s: depth [%.6g, %.6g], %d cells, %.3fs", a, b, result.lower,
             result.upper, result.stats["cells"], result.stats["seconds"]["total"])
