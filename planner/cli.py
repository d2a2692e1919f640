"""The ``minkplan`` command line: thin, lazy imports, one-line errors.

Exit codes: 0 success, 1 no result (planning: no path / not found; assembly: no
sequence), 2 bad input or a resource limit (one line on stderr naming the field or file),
3 an internal error (one line naming the command; -vv adds the traceback) or a fault of
minkplan's on valid input (a ``GeometryError``: a numerical limit, a surface of its own it
cannot take on; one line), 130 interrupted (Ctrl+C), 143 terminated (SIGTERM).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path
from typing import NoReturn


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("minkplan")
    except PackageNotFoundError:
        return "unknown"


class _Parser(argparse.ArgumentParser):
    """Argument errors as one line (``minkplan: error: …``), exit code 2, like every other
    input error, with a did-you-mean for a misspelled command, choice or option;
    ``--help`` shows the usage."""

    def _option_strings(self) -> list[str]:
        """Every option of this parser and of its subcommands."""
        options: list[str] = []
        for action in self._actions:
            options += action.option_strings
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    options += [o for a in sub._actions for o in a.option_strings]
        return sorted(set(options))

    def parse_known_args(self, args=None, namespace=None):
        """argparse's, keeping the arguments for the did-you-mean: a misspelled option can
        end the parse in another error first (``plan x.yaml --outt o``: "the following
        arguments are required: --out")."""
        self._given = list(sys.argv[1:] if args is None else args)
        return super().parse_known_args(args, namespace)

    def _close_option(self, tokens: list[str]) -> str:
        """A did-you-mean for the first of ``tokens`` that looks like an option this parser
        does not know (``--outt``: ``--out``), or ``""``."""
        import difflib

        options = self._option_strings()
        for token in tokens:
            name = token.split("=")[0]
            if not name.startswith("-") or _is_number(name) or name in options or any(
                    o.startswith(name) for o in options if name.startswith("--")):
                continue  # a value, a known option or an abbreviation argparse accepts
            close = difflib.get_close_matches(name, options, n=1)
            if close:
                return f"; did you mean {close[0]!r} (for {token!r})?"
        return ""

    def _suggestion(self, message: str) -> str:
        import difflib
        import re

        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            choices = re.findall(r"[\w-]+", choice.group(2))
            close = difflib.get_close_matches(choice.group(1), choices, n=1)
            return f"; did you mean {close[0]!r}?" if close else ""
        unknown = re.search(r"unrecognized arguments: (.*)", message)
        if unknown:
            return self._close_option(unknown.group(1).split())
        return self._close_option(getattr(self, "_given", []))

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"minkplan: error: {message}{self._suggestion(message)} "
                         f"(see {self.prog} --help)\n")
        raise SystemExit(2)


def _is_number(text: str) -> bool:
    """``text`` is a number (``-1`` is a value, not an option)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


_MEMORY_HELP = ("memory budget in GiB (default: half of this machine's memory); work that "
                "would need more is refused before it starts (exit 2)")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="minkplan",
        description="Translational motion planning for rigid parts on Minkowski-sum "
        "C-obstacles: plan paths with proofs of no path, find assembly sequences, compute "
        "Minkowski sums and C-obstacles, look at them in meshcat.",
    )
    p.add_argument("-v", "--verbose", action="count", default=0, help="more logging (-vv: debug)")
    p.add_argument("--version", action="version", version=f"minkplan {_version()}")
    p.add_argument("--memory-limit", dest="memory_limit_gib", metavar="GB", default=None,
                   help=_MEMORY_HELP)
    sub = p.add_subparsers(dest="command", required=True)
    # the global options are accepted after the subcommand too (minkplan plan ... -v)
    common = _Parser(add_help=False)
    common.add_argument("-v", "--verbose", action="count", default=argparse.SUPPRESS,
                        help="more logging (-vv: debug)")
    # ... and the memory limit on every command that computes (batch has its own, in MB)
    computing = _Parser(add_help=False, parents=[common])
    computing.add_argument("--memory-limit", dest="memory_limit_gib", metavar="GB",
                           default=argparse.SUPPRESS, help=_MEMORY_HELP)

    m = sub.add_parser(
        "minkowski", parents=[computing],
        help="Minkowski sum A ⊕ B (or C-obstacle A ⊕ −B) of two closed meshes",
        description="Compute A ⊕ B of two closed meshes and write it as a mesh file. "
        "With --mirror-b, compute A ⊕ (−B): the C-obstacle of obstacle A for robot B.",
    )
    m.add_argument("a", help="first mesh file (obstacle with --mirror-b)")
    m.add_argument("b", help="second mesh file (robot with --mirror-b)")
    m.add_argument("-o", "--output", required=True,
                   help="output mesh (.stl .obj .ply .off .glb; missing folders are created)")
    m.add_argument(
        "--eps",
        type=float,
        default=None,
        help="grid error bound (default 0.5%% of the result's diagonal)",
    )
    m.add_argument(
        "--mirror-b", action="store_true", help="use −B: the translational C-obstacle A ⊕ (−B)"
    )
    m.add_argument(
        "--threshold",
        type=float,
        default=None,
        help="CoACD concavity threshold for non-convex bodies",
    )
    m.add_argument("--seed", type=int, default=0, help="CoACD seed")
    from planner.cli_shapes import add_repair_option

    add_repair_option(m)
    m.add_argument(
        "--exact",
        choices=("auto", "true", "false"),
        default="auto",
        help="true: exact boundary-convolution source (no decomposition, two-sided bound); "
        "false: convex decomposition (CoACD for non-convex bodies); auto (default): the "
        "decomposition when every body is convex, else exact",
    )
    m.add_argument(
        "--stats", default=None, help="also write error bound and statistics as JSON here"
    )
    m.add_argument("--no-progress", action="store_true", help="no progress bar")

    pl = sub.add_parser(
        "plan", parents=[computing],
        help="plan a translational path for a scenario (YAML or OMPL.app .cfg)",
        description="Plan a collision-free translation of the robot from start to goal. "
        "Writes DIR/path.json (status, waypoints, length, clearance, timings, validation) "
        "and DIR/report.json (cells, graph, refinement, seconds, certificate summary), and "
        "DIR/certificate.json for a proved no-path. Exit 0: path found; 1: no path or not "
        "found; 2: bad input; 3: a fault of minkplan's.",
    )
    pl.add_argument("scenario", help="scenario .yaml, or an OMPL.app problem .cfg")
    pl.add_argument("--out", required=True, help="output directory (created if needed)")
    pl.add_argument(
        "--planner",
        default="minkplan",
        help="minkplan (default: octree roadmap with proofs of no path) or ompl:NAME "
        "(ompl:RRTConnect, ompl:PRM, ompl:BITstar, ...)",
    )
    pl.add_argument("--time-limit", type=float, default=None,
                    help="seconds (default: the scenario's planner.time_limit)")
    pl.add_argument("--seed", type=int, default=None,
                    help="seed (default: the scenario's planner.seed)")
    pl.add_argument("--cache-dir", default=None, help="decomposition cache directory")
    pl.add_argument("--no-progress", action="store_true", help="no progress line")
    pl.add_argument("--hold-orientation", choices=("start", "goal"), default=None,
                    help="when start and goal orientations differ (a 6-DOF problem), plan "
                    "translation-only with this one throughout (said in report.json)")
    pl.add_argument(
        "--exact",
        choices=("auto", "true", "false"),
        default=None,
        help="C-obstacle source (default: the scenario's planner.exact): true exact "
        "boundary convolution of the meshes, false convex decomposition, auto the "
        "decomposition only when every body is convex",
    )
    pl.add_argument("--export-path", default=None, metavar="FILE.path",
                    help="also write a found path in OMPL's SE(3) path format (x y z qx qy "
                    "qz qw per line, the robot's orientation throughout), as OMPL.app reads it")
    pl.add_argument(
        "--html",
        action="store_true",
        help="also write DIR/scene.html: the scene, C-obstacles, cells, roadmap and path "
        "(self-contained, opens offline)",
    )
    pl.add_argument("--glb", default=None, metavar="FILE.glb",
                    help="also write the scene as binary glTF for any 3D viewer (the "
                    "layers the page opens with; cells and roadmap left out, said in it)")
    _add_viz_parsers(sub, computing)
    asm = sub.add_parser(
        "assemble", parents=[computing],
        help="find an assembly sequence (and insertion paths) for an assembly YAML",
        description="Take the assembly apart one part at a time (straight removals "
        "first, then the planner) and reverse it. Writes DIR/sequence.json (parts in "
        "assembly order, each with its insertion path) and DIR/report.json. Exit 0: a "
        "sequence exists; 1: none (names the interlocked parts); 2: bad input.",
    )
    asm.add_argument("assembly", help="assembly .yaml (see docs/assembly.md)")
    asm.add_argument("--out", required=True, help="output directory (created if needed)")
    asm.add_argument("--cache-dir", default=None, help="decomposition cache directory")
    asm.add_argument("--no-progress", action="store_true", help="no progress line")
    asm.add_argument("--html", action="store_true",
                     help="also write DIR/assembly.html: the parts moving in one after "
                     "another (self-contained, opens offline)")
    asm.add_argument("--glb", default=None, metavar="FILE.glb",
                     help="also write the scene as binary glTF for any 3D viewer (each part "
                     "where its insertion path starts; the motion is the page's)")
    asm.add_argument("--interference", type=float, default=None, metavar="DEPTH",
                     help="accept parts that overlap by up to DEPTH (units) in the "
                     "assembled pose, and plan with that much penetration allowed "
                     "(replaces the file's 'interference')")
    from planner import cli_batch, cli_shapes, cli_verify

    cli_shapes.add_parsers(sub, computing)
    cli_batch.add_parser(sub, common)
    cli_verify.add_parser(sub, common)
    return p


EXIT_INTERNAL = 3
"""Exit code of an internal error (a bug, not the input): never 0 or 1, whose meanings
are answers."""


def _fail(message: str) -> int:
    sys.stderr.write(f"minkplan: error: {message}\n")
    return 2


def _missing_mesh(label: str, path: str) -> str | None:
    """Why the mesh file argument ``label`` cannot be read, if it cannot (named as its
    operand is named: ``"a (peg.obj)"``)."""
    if Path(path).is_dir():
        return f"{label} ({path}): a directory, not a mesh file"
    if not Path(path).is_file():
        return f"{label} ({path}): file not found"
    return None


def _unwritable_folder(out: Path) -> str | None:
    """Why the output folder ``out`` cannot be written (checked before the work)."""
    from planner.output import unwritable

    try:
        if out.exists() and not out.is_dir():
            return "exists and is not a directory"
    except OSError as exc:  # a name over the file system's limit
        return f"cannot be used ({exc.strerror or exc})"
    return unwritable(out / "path.json")


def _cmd_minkowski(args) -> int:
    out = Path(args.output)
    from planner.output import unknown_mesh_format

    problem = unknown_mesh_format(out)
    if problem:
        return _fail(f"--output {out}: {problem}")
    missing = _missing_mesh("a", args.a) or _missing_mesh("b", args.b)
    if missing:
        return _fail(missing)
    from planner.output import created_text, missing_folder, unwritable, write_mesh

    targets = [("--output", out)] + ([("--stats", Path(args.stats))] if args.stats else [])
    for flag, target in targets:
        problem = unwritable(target)
        if problem:
            return _fail(f"{flag} {target}: {problem}")
    created = missing_folder(out)

    import planner

    kwargs = {}
    if args.threshold is not None:
        kwargs["threshold"] = args.threshold
    fn = planner.c_obstacle if args.mirror_b else planner.minkowski_sum
    parts = _operand_parts(args)
    result = fn(
        *parts,
        eps=args.eps,
        seed=args.seed,
        progress=False if args.no_progress else None,
        exact=args.exact,
        **kwargs,
    )
    try:
        write_mesh(result.mesh, out)
    except OSError as exc:
        return _fail(f"--output {out}: cannot write it ({exc.strerror or exc})")
    from planner.cli_shapes import _warn_if_float32_breaks
    from planner.output import schema_id

    _warn_if_float32_breaks(result.mesh, out, progress=False if args.no_progress else None)

    summary = {
        "schema": schema_id("minkowski_stats"),
        "output": str(out),
        "error_bound": result.error_bound,
        "eps": result.eps,
        "bound_guaranteed": result.bound_guaranteed,
        "bound_kind": result.bound_kind,
        "source": result.stats["source"],
        "exact": result.exact,
        "stats": result.stats,
    }
    if args.stats:
        from planner.output import jsonable, write_json

        stats_path = Path(args.stats)
        try:  # strict JSON: an unbounded error bound is null, as the schema says
            write_json(stats_path, jsonable(summary))
        except OSError as exc:
            return _fail(f"--stats {stats_path}: cannot write it ({exc.strerror or exc})")
    from planner.cli_shapes import made_solid_text

    made = made_solid_text([(args.a, parts[0].repairs), (args.b, parts[1].repairs)])
    sys.stdout.write(
        f"wrote {out}: {result.stats['triangles']} triangles ({result.stats['source']} source), "
        f"error bound {result.error_bound:.4g} "
        f"(grid {result.stats['grid_error_bound']:.4g} + decomposition "
        f"{result.stats['decomposition_excess']:.4g}), {result.stats['seconds']['total']:.2f} s"
        f"{made}{created_text(created)}\n"
    )
    return 0


def _operand_parts(args) -> tuple:
    """The two mesh files of ``minkplan minkowski`` as solid parts, named by their roles as
    :func:`planner.minkowski_sum` and :func:`planner.c_obstacle` name them, holes filled
    with ``--repair`` (an open one's refusal offers it)."""
    import planner
    from planner.operands import solid_part

    roles = ("obstacle", "robot") if args.mirror_b else ("a", "b")
    return tuple(solid_part(planner.load_mesh(path, name=f"{role} ({path})"), role,
                            repair=args.repair)
                 for path, role in zip((args.a, args.b), roles, strict=True))


def _cmd_plan(args) -> int:
    import dataclasses

    out = Path(args.out)
    problem = _unwritable_folder(out)
    if problem:
        return _fail(f"--out {out}: {problem}")
    if not (args.planner == "minkplan" or args.planner.startswith("ompl:")):
        return _fail(f"--planner {args.planner!r}: use minkplan or ompl:NAME (e.g. "
                     f"ompl:RRTConnect){_close_planner(args.planner)}")
    scenario_path = Path(args.scenario)
    if not scenario_path.is_file():
        return _fail(f"scenario: file {str(scenario_path)!r} not found")
    for flag, target, suffix in (("--export-path", args.export_path, None),
                                 ("--glb", args.glb, ".glb")):
        problem = _unwritable_file(target, suffix)
        if problem:
            return _fail(f"{flag} {target}: {problem}")

    from planner.io import load_scenario
    from planner.output import write_json
    from planner.planning import plan

    scenario = load_scenario(scenario_path, hold_orientation=args.hold_orientation)
    overrides = {}
    if args.time_limit is not None:
        overrides["time_limit"] = args.time_limit
    if args.seed is not None:
        overrides["seed"] = args.seed
    if args.exact is not None:
        overrides["exact"] = args.exact
    if overrides:
        from planner.errors import InvalidParameterError

        try:
            settings = dataclasses.replace(scenario.settings, **overrides)
        except InvalidParameterError as exc:
            flag = "--time-limit" if "time_limit" in str(exc) else "--seed"
            return _fail(f"{flag}: {str(exc).split(': ', 1)[-1]}")
        scenario = dataclasses.replace(scenario, settings=settings)
    outcome = plan(
        scenario,
        planner=args.planner,
        cache_dir=args.cache_dir,
        progress=False if args.no_progress else None,
        source=_source_of_exact_option(args, scenario),
    )
    write_json(out / "path.json", outcome.path_json())
    write_json(out / "report.json", outcome.report_json())
    certificate = outcome.certificate_json()
    if certificate is not None:
        write_json(out / "certificate.json", certificate, indent=None)
    detail = ""
    if outcome.found:
        detail = (
            f": {len(outcome.waypoints)} waypoints, length {outcome.length:.6g}, "
            f"clearance {outcome.clearance:.4g}"
        )
    surfaces = [p.name for p in [scenario.robot, *scenario.obstacles] if not p.solid]
    if surfaces:  # an open mesh changes what collides: say so where the answer is read
        detail += (f" [surfaces, colliding only where triangles meet: "
                   f"{', '.join(surfaces)}; see report.json]")
    sys.stdout.write(
        f"{scenario.name}: {outcome.status}{detail} ({outcome.message}); "
        f"{outcome.timings.get('total', 0.0):.2f} s; wrote {out}/path.json, report.json"
        f"{', certificate.json' if certificate is not None else ''}\n"
    )
    ompl = outcome.validation.get("ompl", {})
    if ompl.get("available") is False:  # said where it is read, not only in path.json
        sys.stderr.write(f"minkplan: note: {ompl['reason']}\n")
    if args.export_path is not None and outcome.found:
        from planner.io.omplapp import write_omplapp_path

        write_omplapp_path(args.export_path, outcome.waypoints, scenario.orientation)
        sys.stdout.write(f"wrote {args.export_path} (OMPL's SE(3) path format)\n")
    if args.html or args.glb:
        from planner import viz
        from planner.progress import StatusLine

        with StatusLine(False if args.no_progress else None) as line:
            line.show("minkplan: drawing the scene (C-obstacle surfaces)")
            scene = viz.scene_for_plan(scenario, outcome, c_obstacle=True)
            _write_views(scene, out / "scene.html" if args.html else None, args.glb)
    return outcome.exit_code


def _source_of_exact_option(args, scenario):
    """The C-obstacle source ``--exact true`` or ``--exact false`` asks for, chosen here so
    that what it says (a surface the decomposition refuses, report.json's ``why``) names
    the option, not the scenario's ``planner.exact``; ``None`` for the planner to choose
    (no such option, ``auto``, which names no setting and whose convexity checks stay in
    the planner's timings, or an OMPL planner, which takes no source)."""
    if args.exact not in ("true", "false") or args.planner != "minkplan":
        return None
    from planner.sources import choose_for

    return choose_for([scenario.robot, *scenario.obstacles], scenario.settings,
                      cache_dir=args.cache_dir,
                      progress=False if args.no_progress else None, field="--exact")


def _close_planner(name: str) -> str:
    """A did-you-mean for a misspelled planner (``minkpln``, ``omp:PRM``), or ``""``; the
    OMPL names are asked of OMPL only here, on the way to an error."""
    import difflib

    from planner.validation import available_planners

    every = ["minkplan", *(f"ompl:{n}" for n in available_planners())]
    close = difflib.get_close_matches(name, every, n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def _unwritable_file(target: str | None, suffix: str | None = None) -> str | None:
    """Why the file ``target`` (if given) cannot be written, or ``None``; ``suffix``: the
    name must end so."""
    if target is None:
        return None
    if suffix is not None and not target.lower().endswith(suffix):
        return f"expected a file name ending in {suffix}"
    from planner.output import unwritable

    return unwritable(Path(target))


def _write_views(scene, page: Path | None, glb: str | None) -> None:
    """Write ``scene`` as the HTML ``page`` and as the GLB file ``glb`` (each if given)."""
    from planner import viz

    if page is not None:
        viz.write_html(scene, page)
        sys.stdout.write(f"wrote {page} (self-contained; open it in a browser)\n")
    if glb is not None:
        viz.write_glb(scene, glb)
        sys.stdout.write(f"wrote {glb} (binary glTF, for any 3D viewer)\n")


def _cmd_assemble(args) -> int:
    out = Path(args.out)
    problem = _unwritable_folder(out)
    if problem:
        return _fail(f"--out {out}: {problem}")
    if not Path(args.assembly).is_file():
        return _fail(f"assembly: file {args.assembly!r} not found")
    problem = _unwritable_file(args.glb, ".glb")
    if problem:
        return _fail(f"--glb {args.glb}: {problem}")
    from planner.assembly import plan_assembly
    from planner.errors import ScenarioError
    from planner.io import load_assembly
    from planner.output import schema_id, write_json

    try:
        assembly = load_assembly(args.assembly, interference=args.interference)
    except ScenarioError as exc:
        if exc.details:  # e.g. an overlap in the assembled pose, with its penetration depth
            write_json(out / "report.json", {"schema": schema_id("assembly_error"),
                                             "status": "invalid_input", "error": str(exc),
                                             **exc.details})
        raise
    result = plan_assembly(assembly, cache_dir=args.cache_dir,
                           progress=False if args.no_progress else None)
    write_json(out / "sequence.json", result.sequence_json())
    write_json(out / "report.json", result.report_json())
    fits = "" if not assembly.interference else (
        f", interference {assembly.interference:.3g}: {len(assembly.overlaps)} overlapping "
        f"pair(s) accepted")
    sys.stdout.write(f"{assembly.name}: {result.message} (contact tolerance "
                     f"{result.contact_tolerance:.3g}{fits}); {result.seconds:.2f} s; "
                     f"wrote {out}/sequence.json, report.json\n")
    if args.html or args.glb:
        from planner.viz import scene_for_assembly

        _write_views(scene_for_assembly(result), out / "assembly.html" if args.html else None,
                     args.glb)
    return result.exit_code


def _not_a_path(document) -> str | None:
    """What keeps a JSON document from being a plan's path.json, if anything."""
    from planner.output import schema_id

    if not isinstance(document, dict) or "status" not in document:
        return "no 'status'"
    schema = document.get("schema")
    if schema is not None and schema != schema_id("path"):
        return f"its schema is {schema!r}"
    return None


def _path_of_another(document: dict, scenario) -> str | None:
    """Why a found path's waypoints are not the scenario's (they must run from its start to
    its goal), if they are not."""
    import numpy as np

    waypoints = np.asarray(document.get("waypoints") or [], dtype=float).reshape(-1, 3)
    if document.get("status") != "found" or len(waypoints) < 2:
        return None
    lo, hi = scenario.bounds
    near = 1e-6 * float(np.linalg.norm(hi - lo))
    ends = (waypoints[0], waypoints[-1])
    if max(float(np.linalg.norm(ends[0] - scenario.start)),
           float(np.linalg.norm(ends[1] - scenario.goal))) <= near:
        return None
    return (f"its path runs from {np.round(ends[0], 6).tolist()} to "
            f"{np.round(ends[1], 6).tolist()}, not from this scenario's start "
            f"{np.round(scenario.start, 6).tolist()} to its goal "
            f"{np.round(scenario.goal, 6).tolist()} (a path of another scenario?)")


def _cmd_view(args) -> int:
    import socket

    try:
        socket.getaddrinfo(args.host, None)
    except OSError as exc:
        return _fail(f"--host {args.host!r}: not an address of this machine's network ({exc})")
    scenario_path = Path(args.scenario)
    if not scenario_path.is_file():
        return _fail(f"scenario: file {str(scenario_path)!r} not found")
    plan_json = None
    if args.path is not None:
        path_file = Path(args.path)
        if path_file.is_dir():  # a plan's --out folder, as verify takes it
            path_file = path_file / "path.json"
        if not path_file.is_file():
            return _fail(f"--path: file {str(path_file)!r} not found")
        try:
            document = json.loads(path_file.read_text())
        except (OSError, ValueError) as exc:
            return _fail(f"--path {path_file}: not a path.json file ({exc})")
        problem = _not_a_path(document)
        if problem:
            return _fail(f"--path {path_file}: not a path.json file ({problem})")
        plan_json = path_file

    from planner import viz
    from planner.io import load_scenario
    from planner.progress import StatusLine

    scenario = load_scenario(scenario_path, hold_orientation=args.hold_orientation)
    if plan_json is not None:
        other = _path_of_another(document, scenario)
        if other:
            return _fail(f"--path {plan_json}: {other}")
    with StatusLine(False if args.no_progress else None) as line:
        line.show("minkplan: drawing the scene (C-obstacle surfaces)")
        scene = viz.scene_for_plan(scenario, plan_json, c_obstacle=not args.no_c_obstacle)

    import signal

    stopped_by = [signal.SIGINT]

    def _terminate(signum, frame):  # SIGTERM stops the server like Ctrl+C (no orphans)
        stopped_by[0] = signal.SIGTERM
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, _terminate)
    viz.serve(scene, out=sys.stdout, host=args.host)
    # it serves until interrupted: 130 for Ctrl+C, 143 for SIGTERM, as every command
    return EXIT_TERMINATED if stopped_by[0] == signal.SIGTERM else 130


def _add_viz_parsers(sub, common: _Parser) -> None:
    v = sub.add_parser(
        "view", parents=[common],
        help="show a scenario (and a planned path) live in meshcat on localhost",
        description="Serve the scenario's scene (obstacles, robot at start and goal, "
        "C-obstacles, and the path of --path with the robot moving along it) with meshcat "
        "on localhost; prints the URL and serves until interrupted (Ctrl+C).",
    )
    v.add_argument("scenario", help="scenario .yaml, or an OMPL.app problem .cfg")
    v.add_argument("--path", default=None, help="a path.json written by minkplan plan")
    v.add_argument("--hold-orientation", choices=("start", "goal"), default=None,
                   help="as given to minkplan plan for a problem whose orientations differ")
    v.add_argument("--no-c-obstacle", action="store_true", help="do not compute C-obstacles")
    v.add_argument("--no-progress", action="store_true", help="no progress line")
    v.add_argument("--host", default="127.0.0.1",
                   help="the address the viewer listens on (default 127.0.0.1: this machine "
                   "only; 0.0.0.0 lets anyone on the network watch)")


class _Terminated(BaseException):
    """SIGTERM, raised where the work is, so it stops like Ctrl+C (outputs are written
    atomically: the earlier ones or none, never half of one)."""


EXIT_TERMINATED = 143
"""Exit code after SIGTERM (128 + 15, as a shell reports it)."""


def _on_sigterm(signum, frame) -> NoReturn:
    raise _Terminated


TERMINATE_GRACE = 5.0
"""Seconds SIGTERM waits for the work to stop like Ctrl+C before the process ends anyway:
Python runs the handler only between its own steps; the core's long calls (octree builds,
surface extractions, sums' convolutions) let it run every 50 ms and stop their work,
other native work runs on until it returns."""


def _watch_for_sigterm() -> int:
    """A write end for :func:`signal.set_wakeup_fd`: the signal's number arrives there at
    once, even while the core runs; a daemon thread reading it ends the process
    (:data:`EXIT_TERMINATED`) when the work has not stopped within
    :data:`TERMINATE_GRACE`. Closing the write end ends the thread."""
    import os
    import signal
    import threading
    import time

    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)

    def watch() -> None:
        with os.fdopen(read_end, "rb", buffering=0) as wakeups:
            while chunk := wakeups.read(64):
                if signal.SIGTERM in chunk:
                    time.sleep(TERMINATE_GRACE)
                    sys.stderr.write("minkplan: terminated\n")
                    sys.stderr.flush()
                    os._exit(EXIT_TERMINATED)

    threading.Thread(target=watch, name="minkplan-sigterm", daemon=True).start()
    return write_end


def main(argv: list[str] | None = None) -> int:
    import os
    import signal
    import threading

    watched = threading.current_thread() is threading.main_thread()
    if watched:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
        write_end = _watch_for_sigterm()
        previous_fd = signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
    try:
        return _main(argv)
    except _Terminated:
        sys.stderr.write("minkplan: terminated\n")
        return EXIT_TERMINATED
    finally:
        if watched:
            signal.set_wakeup_fd(previous_fd)
            os.close(write_end)
            signal.signal(signal.SIGTERM, previous)


def _memory_limit(args) -> str | None:
    """Set the process's memory budget from ``--memory-limit`` (the default without it);
    what is wrong with the value, if anything."""
    from planner import budget
    from planner.errors import InvalidParameterError

    value = getattr(args, "memory_limit_gib", None)
    if args.command == "batch":
        return (None if value is None else "--memory-limit GB goes with the commands that "
                "compute; batch has its own --memory-limit MB per task, after 'batch'")
    try:
        budget.set_memory_limit(value)
    except InvalidParameterError as exc:
        return str(exc)
    return None


NUMBER_OPTIONS = ("-r", "--radius")
"""Options whose value may be negative: argparse takes ``-4e-4`` or ``-inf`` after them for
an option of its own (it knows only ``-4`` and ``-0.4`` as numbers)."""


def _negative_values_joined(argv: list[str]) -> list[str]:
    """``argv`` with ``-r -4e-4`` written ``-r=-4e-4`` (see :data:`NUMBER_OPTIONS`)."""
    out: list[str] = []
    k = 0
    while k < len(argv):
        token = argv[k]
        value = argv[k + 1] if k + 1 < len(argv) else None
        if token in NUMBER_OPTIONS and value is not None and value.startswith("-"):
            try:
                float(value)
            except ValueError:
                pass
            else:
                out.append(f"{token}={value}")
                k += 2
                continue
        out.append(token)
        k += 1
    return out


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(_negative_values_joined(sys.argv[1:] if argv is None
                                                        else list(argv)))
    level = (
        logging.WARNING
        if args.verbose == 0
        else logging.INFO
        if args.verbose == 1
        else logging.DEBUG
    )
    from planner.progress import LogAround

    handler = LogAround()  # (a log line clears the status line and draws it again)
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    logging.basicConfig(level=level, handlers=[handler])
    try:
        from planner.errors import GeometryError, MinkplanError
    except ImportError as exc:  # the native module is missing: a broken install
        return _fail(f"minkplan is not installed correctly: {exc}")
    try:
        problem = _memory_limit(args)
        if problem:
            return _fail(problem)
        if args.command == "minkowski":
            return _cmd_minkowski(args)
        if args.command == "depth":
            from planner.cli_shapes import cmd_depth

            return cmd_depth(args)
        if args.command == "plan":
            return _cmd_plan(args)
        if args.command == "view":
            return _cmd_view(args)
        if args.command == "assemble":
            return _cmd_assemble(args)
        if args.command == "batch":
            from planner.cli_batch import cmd_batch

            return cmd_batch(args)
        if args.command == "verify":
            from planner.cli_verify import cmd_verify

            return cmd_verify(args)
        if args.command == "offset":
            from planner.cli_shapes import cmd_offset

            return cmd_offset(args)
        return _fail(f"unknown command {args.command!r}")
    except GeometryError as exc:  # minkplan's fault (or a numerical limit), not the input's
        _fail(str(exc))
        return EXIT_INTERNAL
    except MinkplanError as exc:
        return _fail(str(exc))
    except KeyboardInterrupt:
        sys.stderr.write("minkplan: interrupted\n")
        return 130
    except MemoryError:
        sys.stderr.write(f"minkplan: error: {args.command}: out of memory (an estimate before "
                         f"the work should have refused this input; please report it)\n")
        return EXIT_INTERNAL
    except Exception as exc:  # noqa: BLE001 (a bug: never exit 0 or 1 for it)
        if args.verbose >= 2:
            import traceback

            traceback.print_exc()
        first = (str(exc).strip().splitlines() or [""])[0]
        sys.stderr.write(f"minkplan: internal error in {args.command}: "
                         f"{type(exc).__name__}: {first}; please report it (-vv shows the "
                         f"traceback)\n")
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
