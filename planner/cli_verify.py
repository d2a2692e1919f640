"""The ``minkplan verify`` command: a no-path certificate checked with independent libraries
(:mod:`planner.validation.certificate_check`)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from planner.cli import _fail

__all__ = ["add_parser", "cmd_verify"]


def add_parser(sub, common) -> None:
    """The ``verify`` subcommand."""
    v = sub.add_parser(
        "verify", parents=[common],
        help="check a no-path certificate with independent libraries (FCL, trimesh, scipy)",
        description="Check DIR/certificate.json (written by minkplan plan for a proved no "
        "path) against the scenario's meshes with independent libraries (the native core "
        "only loads the scenario: it tells solids from surfaces): the walled "
        "point lies in the component, the component's cells are closed by its wall cells, "
        "and every wall cell's witnesses hold (a robot triangle meeting an obstacle "
        "triangle: scipy's convex hulls; a vertex inside a solid: trimesh and FCL; a "
        "connected part crossing a closed shell of the other part: the shell's closedness "
        "and a ray's parity counted with numpy, FCL; the bounds); the witnesses must be "
        "the scenario's own triangles and vertices, the "
        "walled point its start or goal. Exit 0: the certificate holds; 1: it does not "
        "(the failures are listed), or rests on a decomposition's primitives, which are not "
        "checked; 2: bad input.",
    )
    v.add_argument("scenario", help="the scenario .yaml, or OMPL.app .cfg, that was planned")
    v.add_argument("certificate", help="its certificate.json (or the --out folder holding it)")
    v.add_argument("--hold-orientation", choices=("start", "goal"), default=None,
                   help="as given to minkplan plan for a problem whose orientations differ "
                   "(without it: the one the certificate records)")


def cmd_verify(args) -> int:
    path = Path(args.certificate)
    if path.is_dir():
        missing = _no_certificate_in(path)
        if missing:
            return _fail(missing)
        path = path / "certificate.json"
    if not path.is_file():
        return _fail(f"certificate: file {str(path)!r} not found")
    try:
        certificate = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        return _fail(f"certificate: {path}: not a minkplan certificate ({exc})")
    scenario_path = Path(args.scenario)
    if not scenario_path.is_file():
        return _fail(f"scenario: file {str(scenario_path)!r} not found")

    from planner.validation.certificate_check import check_certificate

    scenario = _scenario(scenario_path, args.hold_orientation, certificate)
    try:
        check = check_certificate(certificate, scenario)
    except (ValueError, KeyError, TypeError, IndexError, AttributeError) as exc:
        return _fail(f"certificate: {path}: not a minkplan certificate ({exc})")
    kinds = ", ".join(f"{n} {k}" for k, n in sorted(check.witnesses.items()))
    if check.valid and check.unchecked:
        sys.stdout.write(f"{path}: not checked: the {certificate['walled']} lies in a closed "
                         f"component, but its wall cells rest on {check.unchecked} convex "
                         f"primitives of the decomposition source, which this check does not "
                         f"cover (plan with --exact true for witnesses checked cell by cell); "
                         f"{check.seconds:.2f} s\n")
        return 1
    if check.valid:
        sys.stdout.write(f"{path}: holds: the {certificate['walled']} lies in a closed "
                         f"component; {check.walls} wall cells blocked ({kinds}); "
                         f"{check.seconds:.2f} s\n")
        return 0
    sys.stdout.write(f"{path}: does not hold: {check.n_failures} failures\n")
    for failure in check.failures:
        sys.stdout.write(f"  {failure}\n")
    if check.n_failures > len(check.failures):
        sys.stdout.write(f"  ... and {check.n_failures - len(check.failures)} more\n")
    return 1


def _no_certificate_in(folder: Path) -> str | None:
    """Why the ``--out`` folder ``folder`` holds no certificate, if it holds none: its
    plan's status from its report (a path found, a start in collision), else that it is
    no plan's folder."""
    if (folder / "certificate.json").is_file():
        return None
    try:
        report = json.loads((folder / "report.json").read_text(encoding="utf-8"))
        status = str(report["status"])
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return (f"certificate: {str(folder)!r} holds no certificate.json (nor a plan's "
                f"report.json): give the --out folder of a plan that proved no path")
    message = str(report.get("message") or "").strip()
    said = f" ({message})" if message else ""
    return (f"certificate: {str(folder)!r} holds no certificate.json: its plan's status is "
            f"{status!r}{said}; a certificate is written only when the planner proves there "
            f"is no path")


def _scenario(path: Path, hold: str | None, certificate: dict):
    """The scenario the certificate was made for: read with ``hold`` (``--hold-orientation``),
    or, without it, for a problem whose start and goal orientations differ, with the one
    the certificate records. An assembly, or a problem neither orientation of which the
    certificate is for, is refused (one line)."""
    from planner.errors import ScenarioError
    from planner.io import load_problem, load_scenario
    from planner.problem import Scenario

    try:
        problem = load_problem(path, hold_orientation=hold)
    except ScenarioError as error:
        if hold is not None or "--hold-orientation" not in str(error):
            raise
        if "robot_orientation" not in certificate:
            raise ScenarioError(f"{path}: its start and goal orientations differ, and the "
                                f"certificate records no orientation: give verify "
                                f"--hold-orientation start or goal, as given to plan") \
                from error
        for held in ("start", "goal"):
            scenario = load_scenario(path, hold_orientation=held)
            if _orientation_is(certificate, scenario.orientation):
                return scenario
        raise ScenarioError(f"{path}: its start and goal orientations differ, and the "
                            f"certificate is for neither: give verify --hold-orientation "
                            f"start or goal, as given to plan") from error
    if not isinstance(problem, Scenario):
        raise ScenarioError(f"{path}: an assembly, not a planning problem: verify checks the "
                            f"certificate of a plan's scenario (.yaml or OMPL.app .cfg)")
    return problem


def _orientation_is(certificate: dict, orientation) -> bool:
    """Whether the certificate records the robot at ``orientation`` (3 x 3)."""
    import numpy as np

    try:
        given = np.asarray(certificate["robot_orientation"], dtype=np.float64)
        return given.shape == (3, 3) and bool(np.allclose(given, np.asarray(orientation),
                                                          rtol=0.0, atol=1e-9))
    except (KeyError, TypeError, ValueError):
        return False
