"""Offsets and morphology of closed solids: grow (dilate) and shrink (erode) by a radius,
and the opening and closing that compose them (Varadhan and Manocha, section 5.2).

The offset of a solid ``P`` by ``r > 0`` is ``{x : dist(x, P) <= r}``; by ``r < 0`` it is
the erosion ``{x in P : dist(x, boundary of P) >= |r|}``. Three ways, each with a proved
two-sided bound (``method``; ``"auto"`` takes the first that applies, the cells before the
ball when ``P`` has many triangles, small for ``eps``: :data:`FINE_FACETS`):

* ``"hull"`` (:mod:`.offsets_convex`): one body convex up to its file's rounding, without
  a grid — grown, the hull of its vertices' balls tessellated within ``eps`` (its flat
  faces exact); eroded, its face planes moved inward (exact);
* ``"ball"`` (:mod:`.offsets_ball`): the exact Minkowski sum (boundary convolution) of
  ``P`` with a polytope inscribed in the ball, or of ``P``'s complement in a box for an
  erosion; the bound is the polytope's gap to the sphere plus the sum's own. Cells the
  facets' planes resolve end above ``eps``, so a non-convex solid with round parts costs
  about what its sum with the polytope does, not a grid at ``eps``;
* ``"cells"``: a cell source of the native octree (:mod:`minkowski_core::offset`): cells
  classified by exact distances to ``P``'s triangles, the surface extracted with the
  grid's bound. Flat parts (the prisms over faces; all of an eroded box) are exact: cells
  in the column over one face are cut by its offset plane at their size
  (``stats["planar_pieces"]``), only the round parts are sampled, at ``eps``. Where the
  offsets of two features meet in a crease (between a gear's teeth), the sampled chords
  cut the valley off; triangles that sag there by more than a sixteenth of the grid's
  bound are split on the crease, or flipped along it, a few rounds (:data:`SAG_STATS`).

An open mesh (a triangle soup) is offset as its triangles when asked (``kind``): grown,
``{x : dist(x, triangles) <= r}`` by the cells; it has no erosion, opening or closing.

``opening(P, r)`` erodes then grows (removing features thinner than ``2 r``),
``closing(P, r)`` grows then erodes (filling gaps narrower than ``2 r``). Their
``error_bound`` is ``inf``: an erosion is not continuous in its input (a neck a hair
thicker than ``2 r`` survives, a hair thinner vanishes), so the first stage's error has no
bound through the second in general. ``stats["stage_bounds"]`` gives each stage's own
bound; their sum bounds the result where no feature's thickness (opening) or gap
(closing) lies within that sum of ``2 r``. A solid convex up to its file's rounding is its
own closing (it lies in every half-space holding it): the closing returns it, its
``error_bound`` the distance between it and its hull (:func:`.offsets_convex.convex_closing`).
Its opening takes the hull path both ways, and its ``error_bound`` is the stages' sum (the
erosion is convex, and growing is 1-Lipschitz).

Entry points: :func:`offset`, :func:`opening`, :func:`closing` -> :class:`OffsetResult`.
"""

from __future__ import annotations

import functools
import logging
import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import trimesh

from planner.errors import (
    EmptyResultError,
    GeometryError,
    InvalidMeshError,
    InvalidParameterError,
    ResourceLimitError,
)

from .blas import single_blas_thread
from .meshes.kinds import KINDS, Classified, classify
from .meshes.solids import FACE_CROSSINGS, FACES_INSIDE, without_advice
from .meshes.topology import checked_arrays
from .minkowski import checked_eps, surface_stats
from .offsets_ball import ball_offset
from .offsets_convex import convex_closing, convex_offset, rounding_allowance
from .operands import REPAIR_OFFER, as_mesh
from .progress import StatusLine

log = logging.getLogger(__name__)

__all__ = ["METHODS", "OffsetResult", "closing", "offset", "opening"]


@dataclass(frozen=True)
class OffsetResult:
    """An offset's surface and what it is worth.

    Attributes:
        mesh: the closed, outward surface.
        radius: the offset radius (negative: an erosion); for an opening or closing, the
            radius of its two stages.
        error_bound: every point ``x`` of ``mesh`` has ``|dist(x, P) - |r||`` within it
            (``dist`` to the boundary of ``P`` for an erosion), and every point of the
            true offset's boundary lies within it of ``mesh``; for ``"hull"`` (convex:
            the distance between the two surfaces) and elsewhere except near a gap or
            neck whose width is within twice it of ``2 |r|``, where one may be bridged
            and the other not (:mod:`.offsets_ball`). ``inf`` for an opening or closing
            (see the module documentation), but a convex solid's closing (the solid: its
            Hausdorff distance to the true closing) and opening (the stages' sum).
        eps: the resolution asked for.
        stats: triangles, cells, seconds (per stage for an opening or closing).
    """

    mesh: trimesh.Trimesh
    radius: float
    error_bound: float
    eps: float
    stats: dict[str, Any] = field(default_factory=dict)


def _operand(obj, name: str, kind: str, repair: bool, radius: float) -> Classified:
    """The operand as the ``kind`` it is asked to be (:func:`planner.meshes.kinds.classify`:
    a solid made one as a part's mesh is, T-junctions split, with ``repair`` holes filled;
    a surface its triangles as they are). A solid that is none says what would take it:
    ``repair``, and for a growth (``radius > 0``) its triangles as a surface."""
    if kind not in KINDS:
        raise InvalidParameterError(f"kind = {kind!r}: must be one of {', '.join(KINDS)}")
    if repair and kind == "surface":
        raise InvalidParameterError("repair = True: a surface is taken as its triangles are; "
                                    "repair makes a solid (kind 'solid' or 'auto')")
    mesh = as_mesh(obj, name)
    checked_arrays(mesh, f"mesh {name!r}")  # what neither offer below would mend
    try:
        return classify(mesh, name=name, kind=kind, repair=repair)
    except InvalidMeshError as error:
        if kind != "solid":
            raise
        ways = [] if repair else [REPAIR_OFFER]
        if radius > 0 and _usable_as_surface(mesh, name):
            ways.append("kind='surface' (--kind surface) grows its triangles as they are (as "
                        "FCL sees them)")
        if not ways:
            raise
        raise InvalidMeshError(f"{error}; or: {'; or '.join(ways)}") from None


def _usable_as_surface(mesh: trimesh.Trimesh, name: str) -> bool:
    """Whether the mesh's triangles can be taken as a surface (finite, in range)."""
    try:
        classify(mesh, name=name, kind="surface")
    except InvalidMeshError:
        return False
    return True


def _name_of(mesh, name: str) -> str:
    """The name errors give: a mesh file's path unless named otherwise."""
    if name == "mesh" and isinstance(mesh, (str, os.PathLike)):
        return os.fspath(mesh)
    return name


def _radius(r: float) -> float:
    if isinstance(r, (str, bytes, bool)):  # float() would take "0.1" and True
        raise InvalidParameterError(f"radius = {r!r}: must be a non-zero finite number")
    try:
        value = float(r)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"radius = {r!r}: must be a non-zero finite number") \
            from None
    if not (math.isfinite(value) and value != 0.0):
        raise InvalidParameterError(f"radius = {r!r}: must be a non-zero finite number")
    return value


RADIUS_RANGE = (1e-9, 1e6)
"""The radii an offset takes, as fractions of the solid's diagonal: below, the offset is
the solid to the rounding of its coordinates; above, a ball about it to the rounding of
the radius (and its hull's arithmetic overflows)."""


def _check_radius_scale(radius: float, diagonal: float, name: str) -> None:
    """Refuse a radius outside :data:`RADIUS_RANGE` of the solid's ``diagonal``."""
    low, high = (f * diagonal for f in RADIUS_RANGE)
    if abs(radius) < low:
        raise InvalidParameterError(
            f"radius = {radius:g}: below {RADIUS_RANGE[0]:g} of {name}'s size "
            f"({diagonal:.4g}), where its coordinates' rounding decides; use at least "
            f"{low:.3g}")
    if abs(radius) > high:
        raise InvalidParameterError(
            f"radius = {radius:g}: more than {RADIUS_RANGE[1]:g} times {name}'s size "
            f"({diagonal:.4g}); the offset is a ball about it to rounding; use at most "
            f"{high:.3g}")


def _check_boundary_is_every_triangle(solid: trimesh.Trimesh, name: str) -> None:
    """Refuse to erode a solid some of whose triangles lie inside it, wholly or in part
    (shells that touch or overlap, as a part modelled as several bodies is): the erosion
    keeps away from its boundary, which those triangles are not all part of, and they are
    all it is given. The counts come with the checked solid
    (:data:`~planner.meshes.solids.FACES_INSIDE`, :data:`~planner.meshes.solids.FACE_CROSSINGS`)."""
    inner, crossings = solid.metadata.get(FACES_INSIDE), solid.metadata.get(FACE_CROSSINGS)
    if inner is None or crossings is None:  # checked elsewhere: count them here
        from ._minkowski_core import solid_windings  # noqa: PLC0415

        fronts, _, crossings, _ = solid_windings(np.asarray(solid.vertices, dtype=np.float64),
                                                 np.asarray(solid.faces, dtype=np.int64), name)
        inner = int((fronts != 0).sum())
    if inner or crossings:
        where = (f"{inner} of its {len(solid.faces)} triangles face into the solid"
                 if inner else f"its triangles cross each other inside it along {crossings} "
                 f"segments")
        raise InvalidParameterError(
            f"{name}: {where} (shells that touch or overlap), so they are not all its "
            f"boundary; an erosion needs its boundary alone: merge the shells into one first "
            f"(a mesh union, e.g. manifold3d's)")


METHODS = ("auto", "hull", "ball", "cells")
"""How :func:`offset` computes: ``"hull"``, a body convex up to its file's rounding by its
hull (:mod:`.offsets_convex`); ``"ball"``, the exact sum with a polytope inscribed in the
ball (:mod:`.offsets_ball`); ``"cells"``, exact distances cell by cell (the native cell
source); ``"auto"``, the first of those that applies (the cells before the ball for a
solid of small triangles, :data:`FINE_FACETS`)."""


@single_blas_thread
def offset(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
           name: str = "mesh", progress: bool | None = None,
           method: str = "auto", kind: str = "solid", repair: bool = False) -> OffsetResult:
    """The offset of the closed solid ``mesh`` (a trimesh, ``(V, F)`` or a mesh file) by
    ``r``: grown for ``r > 0``, eroded for ``r < 0``.

    Args:
        eps: resolution (default ``tol.eps_rel`` of the result's diagonal, at most
            :data:`OFFSET_EPS_SHARE` of ``|r|``, and finer once more if the bound still
            reaches ``|r|``); the error bound is of this order. One given whose bound is
            not below ``|r|`` is warned of (the result need not even lie on the right side
            of ``mesh``).
        max_cells: octree cell budget (default ``tol.max_cells``, else from the memory
            limit: :mod:`planner.budget`).
        progress: a status line on stderr while the surface is built
            (:mod:`planner.progress`; ``None``: only when stderr is a terminal).
        method: one of :data:`METHODS`; ``stats["method"]`` says which was used.
        kind: what ``mesh`` is taken for (:data:`planner.meshes.kinds.KINDS`): ``"solid"``
            (the default: a closed solid, else an error); ``"surface"``, its triangles as
            they are (an open triangle soup, as FCL sees it), grown as ``{x : dist(x,
            triangles) <= r}`` by the cells (no erosion: it has no inside; where the part
            is thicker than ``2 r`` the result is hollow); ``"auto"``, a solid when it is
            one, else a surface. ``stats["kind"]`` says which it was.
        repair: a solid may have holes filled (:func:`planner.meshes.repair_mesh`);
            ``stats["changes"]`` says what was changed to make it one.

    Raises:
        InvalidMeshError: ``mesh`` is not a closed solid (``kind="solid"``), or has no
            usable triangles at all (non-finite coordinates, none).
        InvalidParameterError: ``r`` zero or not finite, ``eps`` not positive, an unknown
            ``method`` or ``kind``, ``"hull"`` for a solid that is not convex within
            ``eps``, an erosion, ``"hull"`` or ``"ball"`` of a surface, or ``repair``
            with ``kind="surface"``.
        ResourceLimitError: the grid for ``eps`` would not fit the cell budget.
        GeometryError: an erosion that leaves nothing (``|r|`` past the solid's
            thickness).
    """
    done = _offset_unwarned(mesh, r, eps=eps, max_cells=max_cells, name=name,
                            progress=progress, method=method, kind=kind, repair=repair)
    if done.error_bound >= abs(done.radius):
        log.warning("%s offset by %g: the error bound %.3g is not below the radius, so the "
                    "result need not even lie %s it; use eps below %.3g", name, done.radius,
                    done.error_bound, "around" if done.radius > 0 else "inside",
                    _eps_below(done, done.radius))
    return done


def _offset_unwarned(mesh, r: float, *, eps: float | None, max_cells: int | None, name: str,
                     progress: bool | None, method: str, kind: str, repair: bool,
                     refuse_faulty_ball: bool = False) -> OffsetResult:
    """:func:`offset` without its warning of a bound not below the radius (an opening's
    or closing's stage, which refuses that instead); by default at an ``eps`` whose
    bound is below it when one retry finds one. ``refuse_faulty_ball``: a ball asked for
    whose surface is no clean solid raises :class:`_BallFault` (else it is returned, with
    a warning)."""
    t0 = time.perf_counter()
    radius, name, part = _prepared(mesh, r, method, name, kind, repair)

    def run(step: float | None) -> OffsetResult:
        return _offset_part(part, radius, step, max_cells, name, progress, method, t0,
                            refuse_faulty_ball=refuse_faulty_ball)

    if eps is None:
        return _within_radius(run, part.mesh, radius, None, f"{name} {_verb(radius)}",
                              refuse=False)
    return run(eps)


def _prepared(mesh, r: float, method: str, name: str, kind: str, repair: bool
              ) -> tuple[float, str, Classified]:
    """The checked radius, the mesh's name and the part it is taken for
    (:func:`_operand`), the radius and ``method`` checked before the mesh is read."""
    radius = _radius(r)
    _check_method(method)
    name = _name_of(mesh, name)
    return radius, name, _operand(mesh, name, kind, repair, radius)


def _check_method(method: str) -> None:
    if method not in METHODS:
        raise InvalidParameterError(f"method = {method!r}: must be one of {', '.join(METHODS)}")


def _offset_part(part: Classified, radius: float, eps: float | None, max_cells: int | None,
                 name: str, progress: bool | None, method: str, t0: float, *,
                 refuse_faulty_ball: bool = False) -> OffsetResult:
    """:func:`offset` of the classified ``part`` (``t0``: when the work began;
    ``refuse_faulty_ball`` as :func:`_offset_unwarned`'s)."""
    solid = part.mesh
    extent = np.ptp(np.asarray(solid.bounds), axis=0)
    _check_radius_scale(radius, float(np.linalg.norm(extent)), name)
    if not part.solid:
        _check_surface_offset(radius, method, name, part.reason)
    elif radius < 0:
        _check_boundary_is_every_triangle(solid, name)
    step = _offset_eps(eps, solid, extent, radius, name)
    verb = "growing" if radius > 0 else "eroding"
    with StatusLine(progress) as line:
        line.show(f"minkplan: {verb} {name} by {abs(radius):g} at eps {step:.3g}")
        if part.solid:
            done, used = _by_method(solid, radius, step, method, max_cells, name, progress,
                                    refuse_faulty_ball)
        else:
            done, used = _cell_offset(solid, radius, step, max_cells, name, solid=False), "cells"
    surface, bound, stats = done
    if len(surface.faces) == 0:
        if not math.isfinite(bound):
            raise GeometryError(f"{name}: nothing was resolved of it offset by {radius:g} at "
                                f"eps {step:g}; try a smaller eps")
        raise EmptyResultError(_nothing_left(name, -radius, stats.get("sheet_left", 0.0)))
    stats["method"] = used
    stats["kind"] = "solid" if part.solid else "surface"
    if not part.solid:
        _say_if_hollow(surface, stats, name, radius, part.reason)
    stats["changes"] = dict(part.changes)
    stats["seconds"] = time.perf_counter() - t0
    if part.changes:
        log.info("%s: made a solid by %s", name, changes_text(part.changes))
    return OffsetResult(surface, radius, bound, step, stats)


def _say_if_hollow(surface: trimesh.Trimesh, stats: dict[str, Any], name: str,
                   radius: float, reason: str) -> None:
    """Count the inner shells (cavities) of a surface's grown triangles in
    ``stats["inner_shells"]`` and warn when there are any: a part taken as its triangles
    (``reason``: why it was taken so) grows into a hollow shell where it is thicker than
    ``2 r``."""
    from .meshes.topology import components, face_graph, signed_volumes  # noqa: PLC0415

    faces = np.asarray(surface.faces)
    count, labels = components(len(faces), face_graph(faces)[0])
    inner = int((signed_volumes(np.asarray(surface.vertices), faces, labels, count) < 0).sum())
    stats["inner_shells"] = inner
    if inner:
        log.warning("%s grown by %g as a surface (its triangles): the result has %d inner "
                    "shell(s), hollow where the part is thicker than %g. It was taken as a "
                    "surface, being %s; a solid is filled (--repair closes holes where it "
                    "can)", name, radius, inner, 2 * radius, reason)


def _nothing_left(name: str, depth: float, sheet: float) -> str:
    """What an erosion by ``depth`` that leaves nothing says (``sheet``: the thickness of a
    flat sheet left too thin to mesh, else 0)."""
    if sheet > 0:
        return (f"{name}: nothing is left of it eroded by {depth:g} but a flat sheet at most "
                f"{sheet:.3g} thick, too thin to mesh (its thickest part is {2 * depth:g} "
                f"within that)")
    return (f"{name}: nothing is left of it eroded by {depth:g} (its thickest part is no "
            f"thicker than {2 * depth:g})")


def changes_text(changes: dict[str, Any]) -> str:
    """``"filled_holes 2, merged_vertices 80"``: what was changed to make a solid."""
    return ", ".join(f"{key} {value}" for key, value in changes.items())


def _check_surface_offset(radius: float, method: str, name: str, reason: str) -> None:
    """Refuse what a surface's offset cannot be: an erosion (it has no inside), or by the
    hull or the ball (they take a solid)."""
    if radius < 0:
        raise InvalidParameterError(f"{name}: an erosion needs a closed solid, and it is a "
                                    f"surface ({reason})")
    if method in ("hull", "ball"):
        raise InvalidParameterError(f"method = {method!r}: needs a closed solid, and {name} "
                                    f"is a surface ({reason}); use 'cells' or 'auto'")
    log.info("%s is a surface (%s): growing its triangles; where it is thicker than %g the "
             "result is hollow", name, reason, 2 * radius)


def _by_method(solid: trimesh.Trimesh, radius: float, step: float, method: str,
               max_cells: int | None, name: str, progress: bool | None,
               refuse_faulty_ball: bool = False):
    """``((mesh, error_bound, stats), method used)`` of the solid's offset by ``method``
    (``"auto"``: the first that applies, :data:`METHODS`; ``refuse_faulty_ball`` as
    :func:`_offset_unwarned`'s)."""
    if method in ("auto", "hull"):
        why: list[str] = []
        done = convex_offset(solid, radius, step, why)
        if done is not None:
            return done, "hull"
        if method == "hull":
            raise InvalidParameterError(f"method = 'hull': {name} {why[0]}; use method "
                                        f"'auto', 'ball' or 'cells'")
    if method == "auto" and _fine_facets(solid, step):
        return _cell_offset(solid, radius, step, max_cells, name), "cells"
    if method in ("auto", "ball"):
        done = ball_offset(solid, radius, step, name=name, max_cells=max_cells,
                           progress=progress)
        if done is not None:
            # (nothing left of an erosion is an answer, said as one by the caller)
            fault = _solid_fault(done[0], name) if len(done[0].faces) else None
            if fault is None:
                return done, "ball"
            what = f"{name} offset by {radius:g}: the ball's surface is no clean solid ({fault})"
            if method == "ball":
                if refuse_faulty_ball:
                    raise _BallFault(f"{what}, a fault of minkplan's")
                log.warning("%s, a fault of minkplan's (method 'cells' gives one)", what)
                return done, "ball"
            log.warning("%s, a fault of minkplan's; by the cells instead", what)
        if method == "ball":
            raise InvalidParameterError(f"method = 'ball': eps {step:.3g} is finer than the "
                                        f"finest icosphere of radius {abs(radius):g}")
    return _cell_offset(solid, radius, step, max_cells, name), "cells"


def _checked_solid(mesh: trimesh.Trimesh, name: str) -> tuple[trimesh.Trimesh | None, str | None]:
    """The offset's surface ``mesh`` validated as a solid, or ``None`` and why the winding
    check refuses it."""
    from .meshes.solids import validate_solid  # noqa: PLC0415

    try:
        return validate_solid(mesh, name=f"{name} (offset)"), None
    except InvalidMeshError as error:
        return None, without_advice(str(error))


def _solid_fault(mesh: trimesh.Trimesh, name: str) -> str | None:
    """What keeps the ball's output from being a clean solid, or ``None``: the winding
    check refusing it, or triangles with the solid in front of them too (two sheets that
    meet; an erosion of it would refuse them)."""
    checked, refused = _checked_solid(mesh, name)
    if checked is None:
        return refused
    inner = int(checked.metadata.get(FACES_INSIDE) or 0)
    return f"{inner} of its triangles face into it" if inner else None


FINE_FACETS = 0.05
"""Triangles per ``eps²`` of surface above which ``auto`` takes the cells before the ball:
the sum with the ball then holds many small facets in each cell, which it samples at eps
with costly point queries, while the cells' cost follows the area alone. Measured (solids
of at least :data:`FINE_FACETS_MIN` triangles): the IndustReal gears and the Factory M12
bolt at the default eps (0.3–1.0) 3.5–5 times faster by the cells for as many triangles;
the small gear grown by 0.5 mm at eps 2e-4 (0.29) 19 s by the cells, 96 s by the ball, and
at eps 1e-4 (0.073) 284 s and 759 s (a try-out; 0.2 sent that one to the ball). Fewer
triangles per ``eps²`` (a finely triangulated part with large flat faces) keep the ball,
whose cells the facets' planes resolve above eps."""


FINE_FACETS_MIN = 5000
"""Fewer triangles than this always go to the ball first (at a coarse eps every triangle
is small, but a sum with few of them is cheap)."""


def _fine_facets(solid: trimesh.Trimesh, eps: float) -> bool:
    """Whether the solid has many triangles, small for ``eps`` (:data:`FINE_FACETS`)."""
    count = len(solid.faces)
    return count >= FINE_FACETS_MIN and count * eps * eps > FINE_FACETS * float(solid.area)


def _cell_offset(mesh: trimesh.Trimesh, radius: float, step: float, max_cells: int | None,
                 name: str, *, solid: bool = True) -> tuple[trimesh.Trimesh, float, dict[str, Any]]:
    """``(mesh, error_bound, stats)`` of the native cell source's offset (of a surface's
    triangles when not ``solid``). The refinement at the creases gives up the splits that
    fold the surface or pass it through itself; behind that, a solid's surface it changed
    is checked, and one still no clean solid is made again without the refinement
    (``stats["creases_unrefined"]`` says why; the extraction's own surface is within the
    same bound)."""
    from .meshes.checked import core_mesh  # noqa: PLC0415

    checked = core_mesh(mesh, solid=solid, name=name)
    raw = _native_offset(checked, radius, step, max_cells, name, refine_creases=True)
    surface = trimesh.Trimesh(raw["vertices"], raw["faces"], process=False)
    fault = None
    if solid and raw["sag_splits"] + raw["sag_flips"] > 0:
        fault = _checked_solid(surface, name)[1]
        if fault is not None:
            log.info("%s offset by %g: the refinement at the creases made the cells' surface "
                     "no clean solid (%s); made again without it", name, radius, fault)
            raw = _native_offset(checked, radius, step, max_cells, name, refine_creases=False)
            surface = trimesh.Trimesh(raw["vertices"], raw["faces"], process=False)
    return surface, float(raw["error_bound"]), {"triangles": len(surface.faces),
                                                **surface_stats(raw),
                                                **{key: raw[key] for key in SAG_STATS},
                                                "creases_unrefined": fault}


def _native_offset(checked, radius: float, step: float, max_cells: int | None, name: str, *,
                   refine_creases: bool) -> dict[str, Any]:
    """The native cell source's offset of the core's ``checked`` mesh (its surface and
    statistics), within the memory's or ``max_cells``'s budget."""
    from . import budget  # noqa: PLC0415
    from ._minkowski_core import offset_surface  # noqa: PLC0415

    cells, from_memory = budget.surface_cells(max_cells)
    try:
        return offset_surface(checked, radius, step, max_cells=cells,
                              refine_creases=refine_creases)
    except ResourceLimitError as exc:
        # how much larger eps may be: below the radius, else the bound says nothing
        knob = (f"eps (now {step:.3g}; below the radius {abs(radius):g}, or the result need "
                f"not lie around the offset)")
        raise budget.explain(exc, f"{name} offset by {radius:g}", knob=knob,
                             cells_given=budget.cells_setting(from_memory)) from exc


SAG_STATS = ("sag_rounds", "sag_tested", "sag_splits", "sag_flips", "sag_folds_refused",
             "sag_left", "seconds_sag")
"""What the cells' refinement where the surface sags from the offset did (its creases,
:mod:`minkowski_core::surface::sag`): rounds, points tested, edges split, edges flipped,
triangles left as they were because a split or flip there folded the surface or passed it
through itself, the largest sag seen in its last round, seconds."""


def _composed(mesh, first: float, second: float, eps, max_cells, name: str,
              stage_name: str, progress: bool | None, method: str, kind: str,
              repair: bool) -> OffsetResult:
    t0 = time.perf_counter()
    radius, name, part = _prepared(mesh, first, method, name, kind, repair)
    if not part.solid:
        _refuse_surface_closing(name, kind)
    what = "an opening" if first < 0 else "a closing"
    if first > 0 and method in ("auto", "hull"):
        itself = _convex_closing(part, radius, eps, name, t0)
        if itself is not None:
            return itself
    stages = functools.partial(_stages, part, radius, second, eps, max_cells,
                               (name, stage_name, what), progress, t0=t0)
    try:
        one, two = stages(method)
    except _StageOutputRefused as refused:
        if method != "auto" or refused.first_method == "cells":
            raise GeometryError(str(refused)) from refused  # (the public class)
        # auto's first choice made a surface its second stage cannot take: the cells
        log.warning("%s; %s again by the cells", refused, what)
        one, two = stages("cells")
    stats = {"triangles": two.stats["triangles"], "stages": [one.stats, two.stats],
             "method": f"{one.stats['method']} then {two.stats['method']}",
             "stage_bounds": [one.error_bound, two.error_bound],
             "kind": "solid", "changes": one.stats["changes"],
             "seconds": one.stats["seconds"] + two.stats["seconds"]}
    return OffsetResult(two.mesh, abs(first), _composed_bound(first, one, two), two.eps, stats)


def _composed_bound(first: float, one: OffsetResult, two: OffsetResult) -> float:
    """An opening's bound when both stages took a convex solid's hull: the eroded hull is
    within the first stage's bound of the true erosion (both convex), and growing is
    1-Lipschitz in the Hausdorff distance, so the second stage's result is within the sum
    of the true opening. ``inf`` otherwise (see the module documentation)."""
    if first < 0 and one.stats["method"] == two.stats["method"] == "hull":
        return one.error_bound + two.error_bound
    return math.inf


def _offset_eps(eps: float | None, solid: trimesh.Trimesh, extent: np.ndarray, radius: float,
                name: str) -> float:
    """``eps`` as :func:`.minkowski.checked_eps` checks it, also refused below the rounding
    allowance every hull offset's bound carries (1e-9 of the part's size grown by the
    radius, :func:`.offsets_convex.rounding_allowance`): finer than the part's coordinates
    are trusted, and than any other method's grid reaches (its lattice is at most 2^20
    cells wide)."""
    step = checked_eps(eps, _result_diagonal(extent, radius))
    floor = rounding_allowance(solid, radius)
    if step < floor:
        raise InvalidParameterError(
            f"eps = {step:g}: below {floor:.3g}, 1e-9 of {name}'s size grown by the radius, "
            f"finer than its coordinates are trusted and than any offset method resolves; "
            f"use eps >= {floor:.3g}")
    return step


def _convex_closing(part: Classified, radius: float, eps: float | None, name: str, t0: float
                    ) -> OffsetResult | None:
    """The closing of a solid convex up to ``eps`` (its default, an offset's by
    ``radius``): the solid itself, with the Hausdorff distance to the true closing as its
    bound (:func:`.offsets_convex.convex_closing`); ``None`` for any other solid."""
    extent = np.ptp(np.asarray(part.mesh.bounds), axis=0)
    _check_radius_scale(radius, float(np.linalg.norm(extent)), name)
    step = _stage_eps(part.mesh, radius) if eps is None else \
        _offset_eps(eps, part.mesh, extent, radius, name)
    found = convex_closing(part.mesh, step)
    if found is None:
        return None
    bound, stats = found
    log.info("%s is convex within %.3g: it is its own closing", name, bound)
    stats = {**stats, "method": "hull", "kind": "solid", "changes": dict(part.changes),
             "seconds": time.perf_counter() - t0}
    return OffsetResult(part.mesh, radius, bound, step, stats)


def _stages(part: Classified, radius: float, second: float, eps, max_cells,
            names: tuple[str, str, str], progress: bool | None, method: str, *, t0: float
            ) -> tuple[OffsetResult, OffsetResult]:
    """The two stages of an opening or closing (``names``: the part's, the second stage's
    word for the first, and ``"an opening"`` or ``"a closing"``) of the solid ``part``: by
    ``radius``, then its result by ``second``, each with its bound below the radius."""
    name, stage_name, what = names
    one = _within_radius(
        lambda step: _offset_part(part, radius, step, max_cells, name, progress, method, t0),
        part.mesh, radius, eps, f"{what}'s first stage ({name} {_verb(radius)})")
    # the second stage by the first's method: their errors then largely cancel (an
    # opening inside its input, a closing around it), where mixing a grid and a ball
    # leaves each stage's error in full, on opposite sides
    then = _second_method(method, one.stats["method"])
    # (the ball auto chose, faulty, has both stages done again by the cells: the cells
    # after a ball leave each stage's error in full, on opposite sides)
    stage = functools.partial(_offset_unwarned, one.mesh, second, max_cells=max_cells,
                              name=f"{name} ({stage_name})", progress=progress, kind="solid",
                              repair=False, refuse_faulty_ball=method == "auto")

    def second_stage(step: float) -> OffsetResult:
        try:
            try:
                return stage(eps=step, method=then)
            except InvalidParameterError:
                if then == method:
                    raise
                return stage(eps=step, method=method)  # the first's method does not apply
        except (InvalidMeshError, InvalidParameterError) as error:
            raise _stage_output_refused(error, one, f"{name} ({stage_name})", what) from error
        except _BallFault as fault:
            raise _StageOutputRefused(one.stats["method"], str(fault)) from fault

    two = _within_radius(second_stage, one.mesh, second, eps,
                         f"{what}'s second stage ({name} {_verb(second)})")
    return one, two


OFFSET_EPS_SHARE = 0.5
"""An offset's default ``eps`` (each stage's of an opening or closing) is at most
this share of its radius (and
``tol.eps_rel`` of each stage's result's diagonal, as an offset's): a stage's bound is
``eps`` to about 1.6 times it (the IndustReal gear base eroded by 1 mm by the ball: 1.56),
so it stays below the radius, without which the stage need not even lie on the right side
of its input and the composition means nothing."""

OFFSET_EPS_MARGIN = 0.5
"""A stage whose bound at the default ``eps`` still reaches the radius is done again at
this share of the ``eps`` its bound says would just bring it below."""


def _verb(radius: float) -> str:
    """What an offset by ``radius`` does to a solid."""
    return "grown" if radius > 0 else "eroded"


def _stage_eps(solid: trimesh.Trimesh, radius: float) -> float:
    """The default ``eps`` of an offset (a morphology stage) of ``solid`` by ``radius``: an
    offset's default (``tol.eps_rel`` of the result's diagonal), at most
    :data:`OFFSET_EPS_SHARE` of ``|radius|``."""
    from .tolerances import tol  # noqa: PLC0415

    diagonal = _result_diagonal(np.ptp(np.asarray(solid.bounds), axis=0), radius)
    return min(tol.eps_rel * diagonal, OFFSET_EPS_SHARE * abs(radius))


def _result_diagonal(extent: np.ndarray, radius: float) -> float:
    """The diagonal of the box around a solid of box ``extent`` offset by ``radius``
    (grown: the box grows; eroded: taken as the solid's)."""
    return math.hypot(*(extent + 2.0 * max(radius, 0.0)))  # no overflow for a huge radius


def _within_radius(run, solid: trimesh.Trimesh, radius: float, eps: float | None,
                   what: str, *, refuse: bool = True) -> OffsetResult:
    """``run(eps)``, an offset of ``solid`` by ``radius`` (an offset at its default ``eps``,
    or a morphology stage), with an error bound below ``|radius|``: at the ``eps`` given,
    else refused (nothing is written); by default at :func:`_stage_eps`, done once more
    finer if that was not fine enough. Without ``refuse`` (a plain offset) what that
    gives is returned as it is (:func:`offset` warns of it)."""
    done = run(_stage_eps(solid, radius) if eps is None else eps)
    if done.error_bound < abs(radius):
        return done
    needed = _eps_below(done, radius)
    if eps is None:
        log.info("%s: the error bound %.3g at the default eps %.3g is not below the radius "
                 "%g; again at eps %.3g", what, done.error_bound, done.eps, abs(radius),
                 OFFSET_EPS_MARGIN * needed)
        done = run(OFFSET_EPS_MARGIN * needed)
        if done.error_bound < abs(radius) or not refuse:
            return done
        needed = _eps_below(done, radius)
    raise InvalidParameterError(
        f"eps = {done.eps:.3g}: {what} has the error bound {done.error_bound:.3g}, not below "
        f"the radius {abs(radius):g}, so the result need not even lie "
        f"{'around' if radius > 0 else 'inside'} its input; use eps below {needed:.3g}")


def _stage_output_refused(error: Exception, one: OffsetResult, stage: str, what: str
                          ) -> Exception:
    """The second stage's refusal ``error``: of the first stage's surface ``one`` (named
    ``stage``) a :class:`GeometryError` saying it is minkplan's surface, not the input,
    that is no clean solid (its advice is for an input's author, not for this); any
    other refusal (of a parameter) as it is."""
    if not (isinstance(error, InvalidMeshError) or str(error).startswith(stage)):
        return error
    found = without_advice(str(error)).replace(f"mesh {stage!r}: ", "").replace(
        f"{stage}: ", "")
    return _StageOutputRefused(
        one.stats["method"],
        f"{stage}: {what}'s first stage ({one.stats['method']} at eps {one.eps:.3g}) made a "
        f"surface its second stage cannot take as a solid ({found}); a fault of minkplan's, "
        f"not of the input: try another eps{_other_method(one)}, and please report this "
        f"input")


def _other_method(one: OffsetResult) -> str:
    """The advice of another method after a first stage ``one`` that was not the
    cells'."""
    return "" if one.stats["method"] == "cells" else " or method (--method cells)"


class _BallFault(GeometryError):
    """The ball's surface is no clean solid (a stage that refuses it: see
    :func:`_offset_unwarned`)."""


class _StageOutputRefused(GeometryError):
    """The second stage of an opening or closing refused the first stage's surface (made
    by ``first_method``) as a solid, or made a ball surface that is no clean solid:
    minkplan's fault, not the input's."""

    def __init__(self, first_method: str, message: str) -> None:
        super().__init__(message)
        self.first_method = first_method


def _eps_below(done: OffsetResult, radius: float) -> float:
    """The ``eps`` that would just bring ``done``'s bound below ``|radius|`` (the bound
    about proportional to ``eps``; a tenth of ``eps`` for an unbounded one)."""
    if not math.isfinite(done.error_bound):
        return 0.1 * done.eps
    return done.eps * abs(radius) / done.error_bound


def _refuse_surface_closing(name: str, kind: str) -> None:
    """An opening erodes first (a surface has no inside); a closing's grown triangles
    eroded by as much are the triangles again, of no thickness."""
    taken = " (kind 'surface' asked for)" if kind == "surface" else ""
    raise InvalidParameterError(f"{name}: an opening or closing needs a closed solid, and it "
                                f"is taken for a surface{taken} (grown and eroded by as much, "
                                f"its triangles are themselves again, of no thickness)")


def _positive_radius(r: float, what: str) -> float:
    radius = _radius(r)
    if radius < 0:
        raise InvalidParameterError(f"radius = {r!r}: {what}'s radius must be positive")
    return radius


def _second_method(asked: str, first: str) -> str:
    """The method of a composition's second stage: the first's under ``auto`` (but a
    convex body's hull leaves ``auto`` to choose again: the second stage's input is the
    first's tessellated output)."""
    return first if asked == "auto" and first != "hull" else asked


@single_blas_thread
def opening(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
            name: str = "mesh", progress: bool | None = None,
            method: str = "auto", kind: str = "solid", repair: bool = False) -> OffsetResult:
    """Erode by ``r`` then grow by ``r`` (``r > 0``): features thinner than ``2 r`` go.
    ``kind`` and ``repair`` as :func:`offset`'s (an erosion needs a solid). Each stage's
    error bound is below ``r``: by default its ``eps`` is at most
    :data:`OFFSET_EPS_SHARE` of ``r``; an ``eps`` given that leaves a stage's bound at
    ``r`` or above is refused (:class:`InvalidParameterError`, with the ``eps`` that would
    do)."""
    radius = _positive_radius(r, "an opening")
    return _composed(mesh, -radius, radius, eps, max_cells, name, "eroded", progress, method,
                     kind, repair)


@single_blas_thread
def closing(mesh, r: float, *, eps: float | None = None, max_cells: int | None = None,
            name: str = "mesh", progress: bool | None = None,
            method: str = "auto", kind: str = "solid", repair: bool = False) -> OffsetResult:
    """Grow by ``r`` then erode by ``r`` (``r > 0``): gaps narrower than ``2 r`` close.
    ``kind`` and ``repair`` as :func:`offset`'s (a closing needs a solid); ``eps`` as
    :func:`opening`'s."""
    radius = _positive_radius(r, "a closing")
    return _composed(mesh, radius, -radius, eps, max_cells, name, "grown", progress, method,
                     kind, repair)
