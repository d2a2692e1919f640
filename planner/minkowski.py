"""Minkowski sums and translational C-obstacles of closed meshes, with a stated error bound.

``minkowski_sum(a, b)`` approximates ``A ⊕ B = {a + b}``; ``c_obstacle(obstacle, robot)``
approximates ``O ⊕ (−R)``, the set of translations ``t`` at which ``R + t`` meets ``O``.
Both take the pair's C-obstacle from a :mod:`planner.sources` source (the exact
boundary convolution of the meshes, or pairwise sums of convex pieces: exact for convex
bodies, CoACD's otherwise, cached on disk) and extract a closed surface of it on an
adaptive octree (Varadhan & Manocha 2006).

The error bound is the two-sided Hausdorff distance between the result's surface and the
true boundary: the grid's part ``sqrt(3) h (1 + 2e-4)``, widened where the lattice may have
missed boundary (unresolved cells, and silent ones the source cannot prove clear; counted in
``stats["unresolved_cells"]``, ``stats["silent_cells"]``, ``stats["complex_cells"]``) to
those cells' reach: half a cell's diagonal plus the distance from its centre to the surface.
The decomposition's part is CoACD's measured excess of hulls over the solid (0 for convex
bodies), an estimate by sampling.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh

from . import _minkowski_core as core
from . import budget
from .blas import single_blas_thread
from .decompose import check_threshold
from .errors import GeometryError, InvalidMeshError, InvalidParameterError, ResourceLimitError
from .operands import solid_part
from .problem import Part
from .progress import StatusLine
from .sources import PairCObstacle, Source, SourceSettings, choose, parse_exact
from .tolerances import tol

log = logging.getLogger(__name__)

# the grid bound in terms of the finest cell size h (keep in step with union.rs)
_GRID_BOUND_PER_H = math.sqrt(3.0) * (1.0 + 2e-4)
# estimated octree leaves per finest cell of band area (band ~2 cells thick, plus the
# coarser cells around it); used only to refuse hopeless grids before building them
_CELLS_PER_AREA = 3.0


@dataclass
class MinkowskiResult:
    """A Minkowski sum (or C-obstacle) surface and what is known about it.

    Attributes:
        mesh: watertight, outward-oriented ``trimesh.Trimesh``.
        error_bound: absolute two-sided Hausdorff bound between ``mesh`` and the true
            boundary of the sum of the input solids: the grid's proved bound plus the
            decompositions' measured excess. Cells where the lattice may have missed
            boundary (a feature thinner than the cell) widen it to their reach: a smaller
            eps then tightens it.
        eps: the grid resolution asked for (the grid's share of the bound).
        bound_kind: ``"two-sided"`` when both decompositions are exact: ``error_bound`` is
            then a proved two-sided Hausdorff bound between ``mesh`` and the true boundary.
            ``"outer"`` with CoACD pieces: their hulls over-approximate, so the result
            contains the true sum (up to the grid part) and sticks out of it by at most
            ``error_bound``, but a passage of the true sum narrower than the excess (a
            bore, a slot) can be filled, where the true boundary lies farther inside.
        bound_guaranteed: True when the bound is proved as a two-sided bound: both
            decompositions are exact (the grid's part is proved, complex cells or not).
        exact: True when both operands were decomposed exactly (convex bodies).
        stats: pieces, primitives, cells per label and level, triangles, seconds per
            stage, decomposition details.
        primitives: the native object (the pairwise sums, or the exact sum), for point,
            distance and segment queries.
        pair: the same as a :class:`~planner.sources.PairCObstacle`.
    """

    mesh: trimesh.Trimesh
    error_bound: float
    eps: float
    bound_kind: str
    bound_guaranteed: bool
    exact: bool
    stats: dict = field(repr=False)
    primitives: object = field(repr=False)
    pair: PairCObstacle | None = field(default=None, repr=False)


def _check_eps(eps) -> float:
    try:
        value = float(eps)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"eps = {eps!r}: must be a positive number") from None
    if not (math.isfinite(value) and value > 0.0):
        raise InvalidParameterError(f"eps = {eps!r}: must be a positive finite number")
    return value


def _result_box(a: trimesh.Trimesh, b: trimesh.Trimesh, mirror_b: bool) -> np.ndarray:
    lo_a, hi_a = np.asarray(a.bounds, dtype=float)
    lo_b, hi_b = np.asarray(b.bounds, dtype=float)
    if mirror_b:
        lo_b, hi_b = -hi_b, -lo_b
    return np.array([lo_a + lo_b, hi_a + hi_b])


def _estimate_cells(box: np.ndarray, eps: float) -> float:
    ext = np.maximum(box[1] - box[0], 0.0)
    area = 2.0 * (ext[0] * ext[1] + ext[1] * ext[2] + ext[0] * ext[2])
    h = eps / _GRID_BOUND_PER_H
    if h * h == 0.0:  # an eps so small its square underflows: no grid fits
        return math.inf
    return float(_CELLS_PER_AREA * area / (h * h))


MAX_EPS_REL = 0.25
"""The coarsest ``eps`` taken, relative to the result's diagonal: a grid coarser than
that may miss the whole surface."""


def checked_eps(eps, diag: float) -> float:
    """``eps`` checked (positive, finite, at most :data:`MAX_EPS_REL` of the result's
    diagonal ``diag``), or by default ``tol.eps_rel`` of it."""
    return tol.eps_rel * diag if eps is None else _at_most(_check_eps(eps), diag)


def _at_most(eps: float, diag: float) -> float:
    """``eps``, refused when more than :data:`MAX_EPS_REL` of the result's diagonal."""
    if eps > MAX_EPS_REL * diag:
        raise InvalidParameterError(
            f"eps = {eps:g}: more than {MAX_EPS_REL:g} of the result's size ({diag:.3g}), "
            f"where the grid may miss the whole surface; use eps <= {MAX_EPS_REL * diag:.3g}")
    return eps


def _grid_eps(box: np.ndarray, diag: float, eps, max_cells: int, *, from_memory: bool = False,
              names: tuple[str, str] = ("a", "b")) -> float:
    """``eps`` (default ``tol.eps_rel`` of the diagonal), refused before any work when the
    grid would not fit the cell budget (``from_memory``: the memory limit's)."""
    eps_value = checked_eps(eps, diag)
    estimate = _estimate_cells(box, eps_value)
    if estimate > max_cells:
        floor = eps_value * math.sqrt(estimate / max_cells)
        raise budget.refuse_cells(f"{names[0]} ⊕ {names[1]} at eps = {eps_value:.3g}",
                                  estimate, max_cells, from_memory, f"use eps >= {floor:.3g}")
    return eps_value


def bound_by_region(surf: dict) -> dict[str, float]:
    """The native surface ``surf``'s two-sided bound by the kind of region it holds for
    (``error_bound`` is the largest, and never below the grid's): ``planes``, cells
    resolved by facet planes (0: exact; the gap of planes taken as one, or a small hole
    closed, otherwise, and how far vertices moved apart where sheets touched);
    ``sampled``, the band sampled at eps (the grid's bound; 0 without one); ``missed``,
    cells where the lattice may have missed boundary (their reach; 0 without any)."""
    return {key: float(surf[f"bound_{key}"]) for key in ("planes", "sampled", "missed")}


SURFACE_STATS = ("band_cells", "h", "refinements", "planar_cells", "planar_pieces",
                 "planar_regions", "planar_fanned", "planar_straight_dropped", "planar_unfolded",
                 "planes_fallback_edges", "slivers_apart",
                 "bound_by_region", "holes_closed", "sheets_unzipped", "sheets_apart")
"""The statistics every extracted surface reports (sums, C-obstacles, offsets)."""

_FLOAT_STATS = ("h", "sheets_apart")


def surface_stats(surf: dict) -> dict[str, Any]:
    """:data:`SURFACE_STATS` of the native surface ``surf``."""
    stats: dict[str, Any] = {key: int(surf[key]) for key in SURFACE_STATS
                             if key not in (*_FLOAT_STATS, "bound_by_region")}
    return {**stats, **{key: float(surf[key]) for key in _FLOAT_STATS},
            "bound_by_region": bound_by_region(surf)}


def _cell_totals(per_level) -> dict[str, int]:
    """Leaves per label over all levels."""
    return {name: int(sum(c[i] for c in per_level))
            for i, name in enumerate(("empty", "full", "mixed"))}


def _sum(a, b, *, mirror_b: bool, eps, threshold: float, seed: int, cache_dir, progress,
         max_cells, max_refinements: int, simplify: bool, names: tuple[str, str],
         exact="auto", source: Source | None = None,
         warn_complex: bool = True) -> MinkowskiResult:
    t_start = time.perf_counter()
    exact = parse_exact(exact, "exact")
    check_threshold(threshold)
    parts = (solid_part(a, names[0]), solid_part(b, names[1]))
    names = (parts[0].name, parts[1].name)
    max_cells, from_memory = budget.surface_cells(max_cells)
    if max_refinements < 0:
        raise InvalidParameterError(f"max_refinements = {max_refinements}: must be >= 0")
    if source is None:
        source = choose(parts, SourceSettings(exact=exact, threshold=threshold, seed=seed,
                                              cache_dir=cache_dir, progress=progress))
    grid = dict(eps=eps, max_cells=max_cells, from_memory=from_memory,
                max_refinements=max_refinements,
                simplify=simplify, names=names, t_start=t_start, warn_complex=warn_complex)
    if source.kind == "exact":
        chosen = "asked" if exact is True else "auto"
        return _exact_sum(source, parts, mirror_b=mirror_b, chosen=chosen, progress=progress,
                          **grid)
    return _decomposition_sum(source, parts, mirror_b=mirror_b, progress=progress, **grid)


def _decomposition_sum(source: Source, parts: tuple[Part, Part], *, mirror_b: bool, eps,
                       max_cells: int, from_memory: bool, max_refinements: int, simplify: bool,
                       names: tuple[str, str], t_start: float, progress,
                       warn_complex: bool) -> MinkowskiResult:
    what = f"minkplan: {names[0]} ⊕ {names[1]}"
    with StatusLine(progress) as line:
        # validate and decompose both before the slow work: bad input fails fast
        line.show(f"{what}: decomposing {names[0]}")
        dec_a = source.decomposition(parts[0])  # type: ignore[attr-defined]
        line.show(f"{what}: decomposing {names[1]}")
        dec_b = source.decomposition(parts[1])  # type: ignore[attr-defined]
        box = _result_box(parts[0].mesh, parts[1].mesh, mirror_b)
        diag = float(np.linalg.norm(box[1] - box[0]))
        if len(dec_a.pieces) == 1 and len(dec_b.pieces) == 1:
            # one convex sum: the core gives its hull, exact, with no grid to budget
            eps_value = checked_eps(eps, diag)
        else:
            eps_value = _grid_eps(box, diag, eps, max_cells, from_memory=from_memory,
                                  names=names)
        line.show(f"{what}: pairwise sums of the pieces")
        t0 = time.perf_counter()
        pair = source.pair(*parts, mirror_b=mirror_b)
        t_pairs = time.perf_counter() - t0
        line.show(f"{what}: surface at eps {eps_value:.3g}")
        try:
            surf = core.union_surface(pair.native, eps_value, max_cells=max_cells,
                                      max_refinements=max_refinements, simplify=simplify)
        except ResourceLimitError as exc:
            raise budget.explain(exc, f"{names[0]} ⊕ {names[1]}",
                                 cells_given=budget.cells_setting(from_memory)) from exc
    mesh, surface_stats, surface_seconds = _surface_mesh(surf, names, warn_complex)
    error_bound = float(surf["error_bound"]) + pair.excess
    stats = {
        "source": "decomposition",
        **pair.stats,
        **surface_stats,
        "eps": eps_value,
        "decomposition_excess": pair.excess,
        "exact": pair.exact,
        "decomposition": {"a": _dec_stats(dec_a), "b": _dec_stats(dec_b)},
        "seconds": {"decompose_a": dec_a.seconds, "decompose_b": dec_b.seconds,
                    "pairwise": t_pairs, **surface_seconds,
                    "total": time.perf_counter() - t_start},
    }
    log.info("%s ⊕ %s: %d primitives, %d triangles, bound %.4g (grid %.4g + decomposition "
             "%.4g), %.3fs", names[0], names[1], stats["primitives"], len(mesh.faces),
             error_bound, surf["error_bound"], pair.excess, stats["seconds"]["total"])
    return MinkowskiResult(
        mesh=mesh, error_bound=error_bound, eps=eps_value,
        bound_kind="two-sided" if pair.exact else "outer",
        bound_guaranteed=pair.exact,
        exact=pair.exact, stats=stats, primitives=pair.native, pair=pair)


def _dec_stats(d) -> dict:
    return {"exact": d.exact, "method": d.method, "pieces": len(d.pieces), "bodies": d.bodies,
            "excess": d.excess, "deficit": d.deficit, "cache_hit": d.cache_hit,
            "threshold": d.threshold, "seconds": d.seconds}


def convex_bodies(mesh: trimesh.Trimesh) -> bool:
    """Whether every body of ``mesh`` is convex (its decomposition is then exact and
    cheap, no CoACD), by the same test :func:`planner.decompose.decompose` uses; ``False``
    for a mesh that is no solid."""
    from .sources import CheckedParts

    try:
        return CheckedParts().convex(Part("mesh", mesh, "mesh"))
    except InvalidMeshError:
        return False


def mesh_arrays(mesh: trimesh.Trimesh, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (float64) and faces (int64) of a closed, outward solid for the exact
    source (checked and cleaned by :func:`planner.meshes.validate_solid`)."""
    from .sources import CheckedParts

    return CheckedParts().arrays(Part(name, mesh, "mesh"))


def _widened_by(surf: dict) -> str:
    """Why the core's bound is above twice the grid's: cells where the lattice may have
    missed boundary, else plane-resolved cells' deviation or vertices parted where sheets
    touched (the larger)."""
    missed = int(surf["complex_cells"]) + int(surf["silent_cells"])
    slivers = int(surf["slivers_apart"])
    if slivers and not missed:
        return (f"{slivers} slivers of a sheet thinner than the weld ({float(surf['h']):.3g} "
                f"cells) came apart from the rest and were dropped after "
                f"{surf['refinements']} refinements: the bound reaches over them")
    if missed:
        return (f"the lattice may miss boundary in {missed} cells after {surf['refinements']} "
                f"refinements (a feature thinner than {float(surf['h']):.3g}: "
                f"{int(surf['complex_cells'])} complex, {int(surf['silent_cells'])} silent ones "
                f"no piece covers)")
    deviation, apart = float(surf["planar_deviation"]), float(surf["sheets_apart"])
    if deviation >= apart:
        return f"the cells resolved by planes deviate from them by up to {deviation:.3g}"
    return f"vertices parted where sheets touch moved by up to {apart:.3g}"


def _surface_mesh(surf: dict, names: tuple[str, str],
                  warn_complex: bool) -> tuple[trimesh.Trimesh, dict, dict]:
    """The core's surface as a mesh, with the stats and stage seconds both sources report;
    an empty surface is an error, a bound widened past twice the grid's by cells the lattice
    may have missed boundary in a warning (with ``warn_complex``)."""
    mesh = trimesh.Trimesh(vertices=surf["vertices"], faces=surf["faces"], process=False)
    # closed, manifold and outward by construction (integer-determinant orientation over
    # a crack-free tetrahedral split); the tests check it, so it is not re-checked here
    if len(mesh.faces) == 0:
        raise GeometryError(
            f"{names[0]} ⊕ {names[1]}: the extracted surface is empty; please report this input"
        )
    complex_cells = int(surf["complex_cells"])
    grid_bound = _GRID_BOUND_PER_H * float(surf["h"])
    # no grid (h 0: apart hulls, exact to their plane tolerance) misses nothing
    if warn_complex and grid_bound > 0 and float(surf["error_bound"]) > 2.0 * grid_bound * (
            1 + 1e-9):
        log.warning("%s ⊕ %s: %s, so the bound is %.4g, not %.4g; use a smaller eps",
                    names[0], names[1], _widened_by(surf), surf["error_bound"], grid_bound)
    per_level = surf["cells_per_level"]
    stats = {
        "cells": _cell_totals(per_level),
        "cells_per_level": [list(map(int, c)) for c in per_level],
        "triangles": int(len(mesh.faces)),
        "triangles_extracted": int(surf["triangles_extracted"]),
        "vertices": int(len(mesh.vertices)),
        "grid_error_bound": float(surf["error_bound"]),
        "complex_cells": complex_cells,
        "unresolved_cells": int(surf["unresolved_cells"]),
        "silent_cells": int(surf["silent_cells"]),
        "complex_edges": int(surf["complex_edges"]),
        **surface_stats(surf),
        "threads": core.num_threads(),
    }
    if stats["planes_fallback_edges"]:
        log.info("%s ⊕ %s: the exact polygons of plane-resolved cells left %d edges open "
                 "against the sampled band; sampled everywhere instead",
                 names[0], names[1], stats["planes_fallback_edges"])
    seconds = {key: float(surf[f"seconds_{key}"]) for key in ("octree", "surface", "simplify")}
    return mesh, stats, seconds


def _exact_sum(source: Source, parts: tuple[Part, Part], *, mirror_b: bool, eps,
               max_cells: int, from_memory: bool, max_refinements: int, simplify: bool,
               names: tuple[str, str], t_start: float, chosen: str, warn_complex: bool,
               progress: bool | None) -> MinkowskiResult:
    t0 = time.perf_counter()
    what = f"{names[0]} ⊕ {names[1]}"
    with StatusLine(progress) as line:
        line.show(f"minkplan: {what}: convolution facets")
        try:
            pair = source.pair(*parts, mirror_b=mirror_b)
        except ResourceLimitError as exc:
            raise budget.explain(exc, what) from exc
        t_source = time.perf_counter() - t0
        box = np.asarray(pair.native.bounds)
        diag = float(np.linalg.norm(box[1] - box[0]))
        # no estimate from the box's area: cells resolved by the facets' planes end above
        # eps (a polyhedral sum needs about as many cells at any eps), so the core's own
        # leaf budget, counted before each allocation, is the one that refuses
        eps_value = checked_eps(eps, diag)
        line.show(f"minkplan: {what}: surface at eps {eps_value:.3g}")
        try:
            surf = pair.native.surface(eps_value, max_cells=max_cells,
                                       max_refinements=max_refinements, simplify=simplify)
        except ResourceLimitError as exc:
            raise budget.explain(exc, what,
                                 cells_given=budget.cells_setting(from_memory)) from exc
    mesh, surface_stats, surface_seconds = _surface_mesh(surf, names, warn_complex)
    stats = {
        "source": "exact",
        "exact_chosen": chosen,
        **pair.stats,
        **surface_stats,
        "eps": eps_value,
        "decomposition_excess": 0.0,
        "exact": True,
        "seconds": {"source": t_source, **surface_seconds,
                    "total": time.perf_counter() - t_start},
    }
    log.info("%s ⊕ %s (exact source): %d triangles, bound %.4g, %.3fs", names[0], names[1],
             len(mesh.faces), surf["error_bound"], stats["seconds"]["total"])
    return MinkowskiResult(
        mesh=mesh, error_bound=float(surf["error_bound"]), eps=eps_value,
        bound_kind="two-sided", bound_guaranteed=True,
        exact=True, stats=stats, primitives=pair.native, pair=pair)


@single_blas_thread
def minkowski_sum(
    a,
    b,
    *,
    eps: float | None = None,
    threshold: float = tol.coacd_threshold,
    seed: int = 0,
    cache_dir=None,
    progress: bool | None = None,
    max_cells: int | None = None,
    max_refinements: int = 2,
    simplify: bool = True,
    exact: bool | str = "auto",
    source: Source | None = None,
) -> MinkowskiResult:
    r"""Approximate ``A ⊕ B = {a + b : a ∈ A, b ∈ B}`` of two closed meshes.

    Args:
        a, b: ``trimesh.Trimesh`` solids (watertight), mesh file paths, or
            :class:`~planner.problem.Part`\ s (solids or surfaces).
        eps: the grid's share of the error bound (absolute); default
            ``tol.eps_rel`` (0.5%) of the result's bounding-box diagonal.
        threshold: CoACD concavity threshold for non-convex bodies.
        seed: CoACD seed (results are deterministic for a seed).
        cache_dir: decomposition cache; default ``$MINKPLAN_CACHE_DIR`` or
            the user cache folder, see :func:`planner.decompose.default_cache_dir`.
        progress: a status line on stderr naming the stage (:mod:`planner.progress`;
            default: when stderr is a terminal).
        max_cells: octree leaf budget (default ``tol.max_cells``, else derived from the
            memory limit: :mod:`planner.budget`).
        max_refinements: how often the grid may be halved while complex cells lie farther
            from the surface than the grid's bound (their reach widens the bound).
        simplify: collapse the interiors of flat patches (the same surface with far fewer
            triangles; the bound is unchanged).
        exact: ``True``: the exact source (boundary convolution of the two meshes, no
            decomposition; the bound is two-sided and proved for the meshes as given);
            ``False``: convex decomposition (CoACD for non-convex bodies, whose hulls make
            the bound one-sided); ``"auto"`` (default): the decomposition when every body
            is convex (exact and fastest), else the exact source. ``stats["source"]``
            says which was used.
        source: a :class:`~planner.sources.Source` to take the pair from (then ``exact``,
            ``threshold``, ``seed`` and ``cache_dir`` are its own); a plan's
            ``outcome.source`` gives the C-obstacles it planned on.

    Returns:
        :class:`MinkowskiResult` with ``.mesh``, ``.error_bound`` and ``.stats``.

    Raises:
        InvalidMeshError: an operand is not a closed solid (open, NaN/inf, empty,
            degenerate) or a file cannot be read.
        InvalidParameterError: ``eps`` or another parameter is out of range.
        ResourceLimitError: ``eps`` is so small that the grid would not fit.
    """
    return _sum(
        a,
        b,
        mirror_b=False,
        eps=eps,
        threshold=threshold,
        seed=seed,
        cache_dir=cache_dir,
        progress=progress,
        max_cells=max_cells,
        max_refinements=max_refinements,
        simplify=simplify,
        names=("a", "b"),
        exact=exact,
        source=source,
    )


@single_blas_thread
def c_obstacle(
    obstacle,
    robot,
    *,
    eps: float | None = None,
    threshold: float = tol.coacd_threshold,
    seed: int = 0,
    cache_dir=None,
    progress: bool | None = None,
    max_cells: int | None = None,
    max_refinements: int = 2,
    simplify: bool = True,
    exact: bool | str = "auto",
    source: Source | None = None,
    warn_complex: bool = True,
) -> MinkowskiResult:
    """The translational C-obstacle ``O ⊕ (−R) = {t : (R + t) ∩ O ≠ ∅}``.

    ``robot`` is given in its own frame (at translation ``t`` it occupies ``R + t``), with
    the orientation it keeps for the whole motion. Arguments, result and errors as in
    :func:`minkowski_sum`; ``warn_complex=False`` logs no warning for complex cells left
    (a picture's coarse surface; the stats still count them).
    """
    return _sum(
        obstacle,
        robot,
        mirror_b=True,
        eps=eps,
        threshold=threshold,
        seed=seed,
        cache_dir=cache_dir,
        progress=progress,
        max_cells=max_cells,
        max_refinements=max_refinements,
        simplify=simplify,
        names=("obstacle", "robot"),
        exact=exact,
        source=source,
        warn_complex=warn_complex,
    )
