"""The ``minkplan offset`` and ``minkplan depth`` commands: grow or shrink a closed mesh,
and the penetration depth of two (see :mod:`planner.offsets`, :mod:`planner.depth`)."""

from __future__ import annotations

import json
import logging
import math
import sys
import time
from pathlib import Path

from planner.cli import _fail, _missing_mesh
from planner.errors import EmptyResultError, InvalidParameterError, MinkplanError

__all__ = ["add_parsers", "add_repair_option", "cmd_depth", "cmd_offset", "made_solid_text"]

log = logging.getLogger(__name__)


def add_parsers(sub, common) -> None:
    """The ``offset`` and ``depth`` subcommands."""
    _add_depth_parser(sub, common)
    _add_offset_parser(sub, common)


def _add_depth_parser(sub, common) -> None:
    d = sub.add_parser(
        "depth", parents=[common],
        help="penetration depth of two overlapping closed meshes (or their distance)",
        description="The length of the shortest translation of A that frees it from B, as "
        "a proved interval [lower, upper], with its direction; for disjoint meshes, their "
        "separation distance as a negative depth. Exit 0; 2: bad input; 3: a fault of "
        "minkplan's.",
    )
    d.add_argument("a", help="the mesh that moves")
    d.add_argument("b", help="the mesh it penetrates")
    d.add_argument("--tolerance", type=float, default=None,
                   help="widest interval wanted (default 1e-3 of the pair's size)")
    d.add_argument("--json", action="store_true",
                   help="print the result as JSON (docs/schemas/depth.schema.json; a "
                   "refusal as docs/schemas/depth_error.schema.json, besides the error line)")
    add_repair_option(d)
    d.add_argument("--no-progress", action="store_true", help="no progress line")


def _add_offset_parser(sub, common) -> None:
    o = sub.add_parser(
        "offset", parents=[common],
        help="grow or shrink a closed mesh by a radius (offset, erosion, opening, closing)",
        description="Write the offset {x : dist(x, P) <= r} of a closed mesh P (r > 0), its "
        "erosion (r < 0), or with --opening / --closing both in turn, with a two-sided "
        "error bound. Exit 0; 1: nothing is left (every part of the solid no thicker than 2|r|, "
        "eroded or opened away; nothing written); 2: bad input; 3: a fault of minkplan's "
        "(nothing written).",
    )
    o.add_argument("mesh", help="closed mesh file")
    o.add_argument("-r", "--radius", type=float, required=True,
                   help="offset radius (negative: erode)")
    o.add_argument("-o", "--output", required=True,
                   help="output mesh (.stl .obj .ply .off .glb; missing folders are created)")
    o.add_argument("--eps", type=float, default=None,
                   help="resolution: the error bound is about this (default 0.5%% of the "
                   "result's diagonal)")
    o.add_argument("--method", choices=("auto", "hull", "ball", "cells"), default="auto",
                   help="hull: a convex body by its hull; ball: the exact sum with a polytope "
                   "inscribed in the ball; cells: exact distances cell by cell; auto (default): "
                   "the first that applies")
    morph = o.add_mutually_exclusive_group()
    morph.add_argument("--opening", action="store_true", help="erode then grow by r (r > 0)")
    morph.add_argument("--closing", action="store_true", help="grow then erode by r (r > 0)")
    o.add_argument("--kind", choices=("solid", "surface", "auto"), default="solid",
                   help="solid (default): a closed solid, else an error; surface: grow its "
                   "triangles as they are (an open mesh, as FCL sees it; hollow where the "
                   "part is thicker than 2r; no erosion); auto: a solid when it is one")
    add_repair_option(o)
    o.add_argument("--no-progress", action="store_true", help="no progress line")


def add_repair_option(parser) -> None:
    """``--repair``: an open mesh may have its holes filled (the commands that take solids)."""
    parser.add_argument("--repair", action="store_true",
                        help="fill holes to make a solid (says what it changed)")


def made_solid_text(changes: list[tuple[str, dict]]) -> str:
    """``"; made a solid by: b t_junctions_split 28"``: what was changed to make each
    operand (name, changes) a solid, or ``""``."""
    from planner.offsets import changes_text

    made = [f"{name} {changes_text(done)}" for name, done in changes if done]
    return f"; made a solid by: {'; '.join(made)}" if made else ""


def _warn_if_float32_breaks(mesh, out: Path, *, progress: bool | None) -> float:
    """Say on stderr when the file's float32 copy of the clean solid ``mesh`` is no clean
    solid (:func:`planner.output.float32_fault`), the check shown on the status line (a
    920k-triangle gear takes some 20 s, 60 s when the copy is broken: the full cleaning
    then reads it). Returns the check's seconds (0 for a format that keeps every digit)."""
    from planner.output import FLOAT32_SUFFIXES, float32_fault
    from planner.progress import StatusLine

    if out.suffix.lower() not in FLOAT32_SUFFIXES:
        return 0.0
    t0 = time.perf_counter()
    with StatusLine(progress) as status:
        status.show(f"checking that {out.name}'s float32 coordinates keep "
                    f"{len(mesh.faces):,} triangles a solid")
        fault = float32_fault(mesh, out)
    if fault:
        log.warning("%s: its float32 coordinates make the solid no clean solid (%s); "
                    "minkplan and other tools may refuse the file: write .obj or .off to "
                    "keep every digit", out, fault)
    return time.perf_counter() - t0


def cmd_offset(args) -> int:
    out = Path(args.output)
    from planner.offsets import changes_text
    from planner.output import (
        created_text,
        float32_move,
        missing_folder,
        unknown_mesh_format,
        unwritable,
        write_mesh,
    )

    problem = unwritable(out) or unknown_mesh_format(out)
    if problem:
        return _fail(f"--output {out}: {problem}")
    created = missing_folder(out)
    missing = _missing_mesh("mesh", args.mesh)
    if missing:
        return _fail(missing)
    import planner

    mesh = planner.load_mesh(args.mesh, name=args.mesh)
    options = dict(name=args.mesh, progress=False if args.no_progress else None,
                   method=args.method, kind=args.kind, repair=args.repair)
    how = planner.opening if args.opening else planner.closing if args.closing else \
        planner.offset
    try:
        result = how(mesh, args.radius, eps=args.eps, **options)
    except EmptyResultError as empty:  # an answer, not an error: no result, exit 1
        sys.stderr.write(f"minkplan: offset: {empty}; nothing written\n")
        return 1
    write_mesh(result.mesh, out)
    checked = 0.0
    if result.stats["kind"] == "solid":
        checked = _warn_if_float32_breaks(result.mesh, out, progress=options["progress"])
    stats = result.stats
    of = "" if stats["kind"] == "solid" else ", of its triangles"
    if "stage_bounds" in stats and math.isinf(result.error_bound):  # each stage's bound
        bound = ("error bounds {:.4g} then {:.4g} by stage (together where no feature's "
                 "thickness is within their sum of 2r)".format(*stats["stage_bounds"]))
    else:
        bound = f"error bound {result.error_bound:.4g}"
    # the bound is the float64 mesh's: a float32 format moves it by its rounding too
    moved = float32_move(result.mesh, out)
    stored = (f"; {out.suffix} stores float32: the bound is {result.error_bound + moved:.4g} "
              f"in the file" if moved > 0.01 * result.error_bound else "")
    made = f"; made a solid by: {changes_text(stats['changes'])}" if stats["changes"] else ""
    how_made = f"{stats['method']}: {stats['convex']}" if "convex" in stats else stats["method"]
    check = (f" (and {checked:.2f} s checking that the file's float32 coordinates keep it a "
             f"solid)" if checked >= 0.5 else "")
    sys.stdout.write(f"wrote {out}: {stats['triangles']} triangles, {bound} "
                     f"({how_made}{of}), {stats['seconds']:.2f} s{check}{made}{stored}"
                     f"{created_text(created)}\n")
    return 0


def cmd_depth(args) -> int:
    """``minkplan depth``; with ``--json`` a refusal is also a JSON line on stdout
    (``docs/schemas/depth_error.schema.json``), besides the one-line error on stderr."""
    try:
        return _depth(args)
    except MinkplanError as error:
        if args.json:
            from planner.output import schema_id

            document = {"schema": schema_id("depth_error"), "a": args.a, "b": args.b,
                        "error": str(error)}
            sys.stdout.write(json.dumps(document) + "\n")
        raise


def _depth(args) -> int:
    missing = _missing_mesh("a", args.a) or _missing_mesh("b", args.b)
    if missing:
        raise InvalidParameterError(missing)
    import planner
    from planner.depth import SEPARATION_BY_TRIANGLES

    r = planner.penetration_depth(planner.load_mesh(args.a, name=f"a ({args.a})"),
                                  planner.load_mesh(args.b, name=f"b ({args.b})"),
                                  tolerance=args.tolerance,
                                  progress=False if args.no_progress else None,
                                  repair=args.repair)
    if args.json:  # strict JSON (an unbounded upper end is null), named by its schema
        from planner.output import jsonable, schema_id

        document = jsonable({"schema": schema_id("depth"), "a": args.a, "b": args.b,
                             **r.describe()})
        sys.stdout.write(json.dumps(document, allow_nan=False) + "\n")
        return 0
    along = ", ".join(f"{x:.6g}" for x in r.direction)
    checked = "FCL agrees" if r.validated else "FCL DISAGREES"
    if r.separated:
        what = f"separated: distance {r.distance:.9g} along ({along})"
    else:
        stuck = r.stats["smallest_cells"]
        why = (f"{stuck} smallest cells unresolved" if stuck else "the cell budget ran out")
        what = (f"penetration depth in [{r.lower:.9g}, {r.upper:.9g}] along ({along})"
                + ("" if r.converged else f" (wider than the tolerance: {why})"))
    made = made_solid_text([(args.a, r.stats["changes"]["a"]), (args.b, r.stats["changes"]["b"])])
    searched = ("boxes apart, no convolution" if r.stats["method"] == SEPARATION_BY_TRIANGLES
                else f"{r.stats['cells']} cells")
    sys.stdout.write(f"{args.a} into {args.b}: {what}; {checked}; {searched}, "
                     f"{r.stats['seconds']['total']:.3f} s{made}\n")
    return 0
