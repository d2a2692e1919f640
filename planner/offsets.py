"""Offsets and morphology of closed solids: grow (dilate) and shrink (erode) by a radius,
and the opening and closing that compose them (Varadhan and Manocha, section 5.2).

The offset of a solid ``P`` by ``r > 0`` is ``{x : dist(x, P) <= r}``; by ``r < 0`` it is
the erosion ``{x in P : dist(x, boundary of P) >= |r|}``. Both are computed as cell
sources of the native octree (:mod:`minkowski_core::offset`): cells classified by exact
distances to ``P``'s triangles (never a sum with a polyhedral ball), the surface extracted
with the grid's two-sided error bound. Flat parts (the prisms over faces; all of an
eroded box) are exact: cells in the column over one face are cut by its offset plane at
their size (``stats["planar_pieces"]``), only the round parts are sampled. One convex
body needs no grid (:mod:`.offsets_convex`): grown, the hull of its vertices' balls
tessellated within ``eps`` (its flat faces exact); eroded, its face planes moved inward
(exact); ``stats["convex"]`` says so.
``opening(P, r)`` erodes then grows (removing features thinner than ``2 r``),
``closing(P, r)`` grows then erodes (filling gaps narrower than ``2 r``). Their
``error_bound`` is ``inf``: an erosion is not continuous in its input (a neck a hair
thicker than ``2 r`` survives, a hair thinner vanishes), so the first stage's error has no
bound through the second in general. ``stats["stage_bounds"]`` gives each stage's own
bound; their sum bounds the result where no feature's thickness (opening) or gap
(closing) lies within that sum of ``2 r``.

Entry points: :func:`offset`, :func:`opening`, :func:`closing` -> :class:`OffsetResult`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh

from planner.errors import GeometryError, InvalidParameterError, ResourceLimitError

from .meshes import load_mesh
from .meshes.kinds import classify
from .minkowski import bound_by_region
from .offsets_convex import convex_offset
from .progress import StatusLine
from .tolerances import tol

__all__ = ["OffsetResult", "closing", "offset", "opening"]


@dataclass(frozen=True)
class OffsetResult:
    """An offset's surface and what it is worth.

    Attributes:
        mesh: the closed, outward surface.
        radius: the offset radius (negative: an erosion); for an opening or closing, the
            radius of its two stages.
        error_bound: every point of ``mesh`` lies within this distance of the true
            offset's boundary, and every point of that boundary within it of ``mesh``
            (``inf`` for an opening or closing: see the module documentation).
        eps: the resolution asked for.
        stats: triangles, cells, seconds (per stage for an opening or closing).
    """

    mesh: trimesh.Trimesh
    radius: float
    error_bound: float
    eps: float
    stats: dict[str, Any] = field(default_factory=dict)


def _solid(obj, name: str) -> trimesh.Trimesh:
    """The operand as a checked solid, made one as a part's mesh is (T-junctions split:
    :func:`planner.meshes.kinds.classify`), else the reason it is none."""
    if isinstance(obj, trimesh.Trimesh):
        mesh = obj
    elif isinstance(obj, tuple) and len(obj) == 2:
        mesh = trimesh.Trimesh(np.asarray(obj[0], dtype=np.float64),
                               np.asarray(obj[1], dtype=np.int64), process=False)
    else:
        mesh = load_mesh(obj, name=name)
    return classify(mesh, name=name, kind="solid").mesh


def _radius(r: float) -> float:
    value = float(r)
    if not (math.isfinite(value) and value != 0.0):
        raise InvalidParameterError(f"radius = {r!r}: must be a non-zero finite number")
    return value


def offset(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
           name: str = "mesh", progress: bool | None = None,
           convex: bool = True) -> OffsetResult:
    """The offset of the closed solid ``mesh`` (a trimesh, ``(V, F)`` or a mesh file) by
    ``r``: grown for ``r > 0``, eroded for ``r < 0``.

    Args:
        eps: resolution (default ``tol.eps_rel`` of the result's diagonal); the error bound
            is of this order.
        max_cells: octree cell budget (default ``tol.max_cells``, else from the memory
            limit: :mod:`planner.budget`).
        progress: a status line on stderr while the surface is built
            (:mod:`planner.progress`; ``None``: only when stderr is a terminal).
        convex: offset one convex body without a grid (:mod:`planner.offsets_convex`);
            ``False``: the cell source for every solid.

    Raises:
        InvalidMeshError: ``mesh`` is not a closed solid.
        InvalidParameterError: ``r`` zero or not finite, ``eps`` not positive.
        ResourceLimitError: the grid for ``eps`` would not fit the cell budget.
        GeometryError: an erosion that leaves nothing (``|r|`` past the solid's
            thickness).
    """
    from ._minkowski_core import CheckedMesh, offset_surface

    t0 = time.perf_counter()
    radius = _radius(r)
    solid = _solid(mesh, name)
    extent = np.ptp(np.asarray(solid.bounds), axis=0)
    diagonal = float(np.linalg.norm(extent + 2.0 * max(radius, 0.0)))
    step = tol.eps_rel * diagonal if eps is None else float(eps)
    if not (math.isfinite(step) and step > 0):
        raise InvalidParameterError(f"eps = {eps!r}: must be a positive finite number")
    from . import budget  # noqa: PLC0415

    cells, _ = budget.surface_cells(max_cells)
    verb = "growing" if radius > 0 else "eroding"
    with StatusLine(progress) as line:
        line.show(f"minkplan: {verb} {name} by {abs(radius):g} at eps {step:.3g}")
        hull = convex_offset(solid, radius, step) if convex else None
        if hull is None:
            checked = CheckedMesh(np.asarray(solid.vertices, dtype=np.float64),
                                  np.asarray(solid.faces, dtype=np.int64), name=name)
            try:
                raw = offset_surface(checked, radius, step, max_cells=cells)
            except ResourceLimitError as exc:
                raise budget.explain(exc, f"{name} offset by {radius:g}") from exc
    if hull is not None:
        grown_or_eroded, bound, stats = hull
        if len(grown_or_eroded.faces) == 0:
            raise GeometryError(f"{name}: nothing is left of it eroded by {-radius:g} (its "
                                f"thickest part is thinner than {2 * -radius:g})")
        stats["seconds"] = time.perf_counter() - t0
        return OffsetResult(grown_or_eroded, radius, bound, step, stats)
    if len(raw["faces"]) == 0:
        if not math.isfinite(raw["error_bound"]):
            raise GeometryError(f"{name}: nothing was resolved of it offset by {radius:g} at "
                                f"eps {step:g}; try a smaller eps")
        raise GeometryError(f"{name}: nothing is left of it eroded by {-radius:g} (its "
                            f"thickest part is thinner than {2 * -radius:g})")
    surface = trimesh.Trimesh(raw["vertices"], raw["faces"], process=False)
    stats = {"triangles": len(surface.faces), "band_cells": int(raw["band_cells"]),
             "h": float(raw["h"]), "refinements": int(raw["refinements"]),
             "planar_cells": int(raw["planar_cells"]), "planar_pieces": int(raw["planar_pieces"]),
             "planes_fallback_edges": int(raw["planes_fallback_edges"]),
             "bound_by_region": bound_by_region(raw),
             "holes_closed": int(raw["holes_closed"]),
             "sheets_unzipped": int(raw["sheets_unzipped"]),
             "seconds": time.perf_counter() - t0}
    return OffsetResult(surface, radius, float(raw["error_bound"]), step, stats)


def _composed(mesh, first: float, second: float, eps, max_cells, name: str,
              kind: str, progress: bool | None) -> OffsetResult:
    one = offset(mesh, first, eps=eps, max_cells=max_cells, name=name, progress=progress)
    two = offset(one.mesh, second, eps=eps, max_cells=max_cells, name=f"{name} ({kind})",
                 progress=progress)
    stats = {"triangles": two.stats["triangles"], "stages": [one.stats, two.stats],
             "stage_bounds": [one.error_bound, two.error_bound],
             "seconds": one.stats["seconds"] + two.stats["seconds"]}
    return OffsetResult(two.mesh, abs(first), math.inf, two.eps, stats)


def opening(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
            name: str = "mesh", progress: bool | None = None) -> OffsetResult:
    """Erode by ``r`` then grow by ``r`` (``r > 0``): features thinner than ``2 r`` go."""
    radius = abs(_radius(r))
    return _composed(mesh, -radius, radius, eps, max_cells, name, "eroded", progress)


def closing(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
            name: str = "mesh", progress: bool | None = None) -> OffsetResult:
    """Grow by ``r`` then erode by ``r`` (``r > 0``): gaps narrower than ``2 r`` close."""
    radius = abs(_radius(r))
    return _composed(mesh, radius, -radius, eps, max_cells, name, "grown", progress)
