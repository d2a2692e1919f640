"""One task, run as ``minkplan plan`` / ``minkplan assemble`` would run it, turned into
the record ``results.jsonl`` keeps (a flat JSON object; strict JSON, no NaN).

Answers are the planners' own (``found``, ``no_path``, ``not_found``; for an assembly
``found`` is a sequence, ``no_path`` a proved interlock, ``not_found`` an interlock some
planner only gave up on). A problem the readers refuse, or a resource limit the planner
hits, is ``error`` with the one-line message the CLI would print; anything else raised is
``error`` with reason ``internal`` (a bug).

Entry point: :func:`execute`.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

from planner.errors import MinkplanError, ResourceLimitError
from planner.output import jsonable, schema_id

from .tasks import ASSEMBLY, Task

__all__ = ["ERROR", "FAILURES", "execute"]

ERROR = "error"
"""The task raised: bad input, a resource limit, or a bug (``reason`` says which)."""
FAILURES = (ERROR, "timeout", "memory_limit", "crashed")
"""Statuses of a task that gave no answer (the others are the planners' answers)."""


def _plan(task: Task) -> dict[str, Any]:
    from planner.io import load_scenario
    from planner.planning import plan

    scenario = load_scenario(task.problem, hold_orientation=task.hold_orientation)
    overrides: dict[str, Any] = {"seed": scenario.settings.seed + task.run}
    if task.time_limit is not None:
        overrides["time_limit"] = task.time_limit
    settings = dataclasses.replace(scenario.settings, **overrides)
    scenario = dataclasses.replace(scenario, settings=settings)
    outcome = plan(scenario, planner=task.planner, cache_dir=task.cache_dir, progress=False)
    validation = outcome.validation or {}
    valid = bool(outcome.found and validation.get("valid"))
    timings = outcome.timings
    return {"status": str(outcome.status), "reason": outcome.reason,
            "message": outcome.message, "seed": settings.seed,
            "effective_time_limit": settings.time_limit, "length": outcome.length,
            "clearance": outcome.clearance, "valid": valid,
            "waypoints": outcome.waypoints if outcome.found else None,
            "planner_seconds": timings.get("total", 0.0) - timings.get("validate", 0.0)}


def _assemble(task: Task) -> dict[str, Any]:
    from planner.assembly import plan_assembly
    from planner.io import load_assembly

    result = plan_assembly(load_assembly(task.problem), cache_dir=task.cache_dir)
    status = "found" if result.found else "no_path" if result.proved else "not_found"
    return {"status": status, "reason": result.status, "message": result.message,
            "order": result.order, "interlocked": result.interlocked,
            "valid": result.found, "planner_seconds": result.seconds}


def execute(task: Task) -> dict[str, Any]:
    """Run ``task`` here and now; never raises for what the task's input does."""
    t0 = time.perf_counter()
    try:
        body = _assemble(task) if task.kind == ASSEMBLY else _plan(task)
    except ResourceLimitError as exc:
        body = {"status": ERROR, "reason": "resource_limit", "message": str(exc)}
    except MinkplanError as exc:
        body = {"status": ERROR, "reason": "input", "message": str(exc)}
    except Exception as exc:  # noqa: BLE001 (a bug: recorded, the batch goes on)
        first = (str(exc).strip().splitlines() or [""])[0]
        body = {"status": ERROR, "reason": "internal",
                "message": f"{type(exc).__name__}: {first}"}
    return jsonable({"schema": schema_id("batch_record"), **task.to_json(), "key": task.key,
                     **body,
                     "seconds": time.perf_counter() - t0})
