"""``--planner ompl:NAME``: an OMPL planner driven by the FCL checker on the original
meshes, with the same outputs as minkplan's own planner (statuses, validation, timings).

OMPL cannot prove that no path exists: a start or goal in collision is ``no_path`` (FCL
shows the collision), everything else that is not a solution is ``not_found``.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from planner.problem import Scenario
from planner.roles import FOUND, NO_PATH, NOT_FOUND
from planner.validation import FclChecker, OmplPlanner

from .octree_planner import default_contact_tolerance
from .outcome import PlanOutcome
from .validate import validate_path

__all__ = ["plan_ompl"]


def plan_ompl(scenario: Scenario, name: str, *, validate: bool = True) -> PlanOutcome:
    """Plan with the OMPL planner ``name`` (``RRTConnect``, ``PRM``, ``BITstar``, ...;
    case-insensitive) for ``planner.time_limit`` seconds, seeded with ``planner.seed``.

    Raises:
        InvalidParameterError: unknown planner name.
    """
    t0 = time.perf_counter()
    delta = default_contact_tolerance(scenario)
    checker = FclChecker.for_parts(scenario.robot, scenario.obstacles, contact_tolerance=delta)
    bounds = np.stack(scenario.bounds)
    planner = OmplPlanner(name, checker, bounds, seed=scenario.settings.seed)
    label = f"ompl:{planner.name}"
    result = planner.solve(scenario.start, scenario.goal, scenario.settings.time_limit)
    timings = {"search": result.seconds}
    report = {"scenario": scenario.describe(), "contact_tolerance": delta,
              "ompl": {"planner": planner.name, "status": str(result.status),
                       "reason": result.reason,
                       "valid_checks": result.n_valid_checks,
                       "invalid_checks": result.n_invalid_checks,
                       "message": result.message}}

    def done(status, reason, message, **kw) -> PlanOutcome:
        timings["total"] = time.perf_counter() - t0
        return PlanOutcome(status=status, reason=reason, message=message, planner=label,
                           timings=timings, report=report, **kw)

    for which in ("start", "goal"):
        if result.reason not in (f"{which}_in_collision", f"{which}_out_of_bounds"):
            continue
        p = np.asarray(scenario.start if which == "start" else scenario.goal)
        collision = {"which": which, "position": p.tolist()}
        hit = checker.colliding_obstacle(p)
        if result.status == NO_PATH and hit is not None:
            collision.update(obstacle=hit[0], depth_upper_bound=hit[1])
            message = f"the {which} is in collision with {hit[0]} (depth about {hit[1]:.4g})"
            return done(NO_PATH, f"{which}_in_collision", message, collision=collision)
        return done(NOT_FOUND, f"{which}_invalid", f"the {which} is out of bounds",
                    collision=collision)
    if not result.solved:
        return done(NOT_FOUND, result.reason or "planner_status",
                    f"{planner.name}: {result.status} ({result.reason}) "
                    f"{result.message}".strip())
    waypoints = np.asarray(result.waypoints, dtype=np.float64)
    validation: dict[str, Any] = {"fcl": {}, "ompl": {}}
    clearance = float("nan")
    if validate:
        t1 = time.perf_counter()
        validation = validate_path(waypoints, checker, bounds)
        timings["validate"] = time.perf_counter() - t1
        clearance = validation["fcl"]["min_clearance"]
        if not validation["valid"]:
            return done(NOT_FOUND, "validation_failed",
                        f"{planner.name}'s path failed validation", validation=validation)
    return done(FOUND, "path", f"{planner.name} found a path", waypoints=waypoints,
                length=result.length, clearance=clearance, validation=validation)
