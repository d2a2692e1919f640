"""The benchmark driver of assembly removals: per-step planning time of several planners
on the removal problems an assembly result was decided on (an interlocked part proved by
an enclosure: minkplan's row is that proof, timed). Used by bench_assembly.py and
bench_exact.py, and by the tests of the assembly search."""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from planner.assembly import AssemblyResult, removal_problems, removal_scenario  # noqa: E402
from planner.assembly.enclosure import prove_enclosed  # noqa: E402
from planner.assembly.geometry import direction_vector  # noqa: E402
from planner.assembly.search import validate_removal  # noqa: E402
from planner.errors import InvalidParameterError, ResourceLimitError  # noqa: E402
from planner.output import jsonable  # noqa: E402
from planner.planning import FOUND, NO_PATH, NOT_FOUND, plan  # noqa: E402
from planner.sources import choose_for  # noqa: E402

__all__ = ["benchmark_removals"]


def benchmark_removals(result: AssemblyResult, planners=("minkplan", "ompl:RRTConnect"),
                       *, cache_dir=None, runs: int = 1,
                       time_limit: float | None = None) -> list[dict[str, Any]]:
    """Per-step planning time of several planners on the removal problems of a result
    (:func:`removal_problems`, each as a :func:`removal_scenario`). A group's step is
    left out (the planners move one part).

    Args:
        result: from :func:`plan_assembly`.
        planners: ``"minkplan"`` and/or ``"ompl:NAME"``.
        cache_dir: decomposition cache (use a warm one to leave decomposition out).
        runs: runs per problem and planner; OMPL run ``k`` uses seed ``k`` (minkplan is
            deterministic and keeps the assembly's seed).
        time_limit: seconds per run (default: the assembly's ``planner.time_limit``).

    Returns:
        One row per problem, planner and run: ``part``, ``method``, ``obstacles``,
        ``direction``, ``expected``, ``planner``, ``run``, ``seed``, ``status``,
        ``seconds`` (wall clock of :func:`planner.planning.plan`), ``planning_seconds``
        (the same without its validation), ``length`` and FCL ``valid`` (at the
        assembly's contact tolerance, plus its interference tolerance; ``None`` when no
        path was found).
    """
    if runs < 1:
        raise InvalidParameterError(f"runs = {runs}: must be >= 1")
    parts = {p.name: p for p in result.assembly.parts}
    rows = []
    for problem in removal_problems(result):
        if problem["method"] == "group":
            continue
        scenario = removal_scenario(result.assembly, problem["part"], problem["obstacles"],
                                    problem["direction"])
        direction = direction_vector(problem["direction"])[0]
        for name in planners:
            for run in range(runs):
                seed = scenario.settings.seed if name == "minkplan" else run
                settings = dataclasses.replace(
                    scenario.settings, seed=seed,
                    time_limit=scenario.settings.time_limit if time_limit is None
                    else time_limit)
                t0 = time.perf_counter()
                if name == "minkplan" and problem.get("proof") == "enclosure":
                    rows.append({**_enclosure_row(result, problem, settings.time_limit),
                                 "direction": direction, "run": run, "seed": seed})
                    continue
                try:
                    outcome = plan(dataclasses.replace(scenario, settings=settings),
                                   planner=name, cache_dir=cache_dir, progress=False)
                except ResourceLimitError as error:  # a refusal is a row, not a crash
                    rows.append({"part": problem["part"], "method": problem["method"],
                                 "obstacles": problem["obstacles"], "direction": direction,
                                 "expected": problem["expected"], "planner": name,
                                 "run": run, "seed": seed, "status": "refused",
                                 "reason": str(error), "seconds": time.perf_counter() - t0,
                                 "planning_seconds": time.perf_counter() - t0,
                                 "length": float("nan"), "valid": None})
                    continue
                seconds = time.perf_counter() - t0
                valid = None
                if outcome.status == FOUND:
                    valid = validate_removal(parts[problem["part"]],
                                      [parts[n] for n in problem["obstacles"]],
                                      np.asarray(outcome.waypoints),
                                      result.assembly.tolerance)["valid"]
                rows.append({
                    "part": problem["part"], "method": problem["method"],
                    "obstacles": problem["obstacles"], "direction": direction,
                    "expected": problem["expected"], "planner": name, "run": run,
                    "seed": seed, "status": outcome.status, "reason": outcome.reason,
                    "seconds": seconds,
                    "planning_seconds": outcome.timings.get("total", seconds)
                    - outcome.timings.get("validate", 0.0),
                    "length": outcome.length, "valid": valid})
    return jsonable(rows)


def _enclosure_row(result: AssemblyResult, problem: dict[str, Any],
                   time_limit: float) -> dict[str, Any]:
    """minkplan's answer to an interlocked part that the search proved by an enclosure:
    the same proof (:func:`planner.assembly.enclosure.prove_enclosed`) on a fresh source,
    timed (the planner over the whole exit box is not what ``minkplan assemble`` runs)."""
    assembly = result.assembly
    parts = {p.name: p for p in assembly.parts}
    present = [parts[n] for n in problem["obstacles"]]
    t0 = time.perf_counter()
    source = choose_for([parts[problem["part"]], *present], assembly.settings)
    proof = prove_enclosed(source, parts[problem["part"]], present, delta=assembly.tolerance,
                           diagonal=assembly.diagonal, deadline=t0 + time_limit)
    seconds = time.perf_counter() - t0
    return {"part": problem["part"], "method": problem["method"],
            "obstacles": problem["obstacles"], "expected": problem["expected"],
            "planner": "minkplan", "status": NO_PATH if proof else NOT_FOUND,
            "reason": "enclosure", "seconds": seconds, "planning_seconds": seconds,
            "length": float("nan"), "valid": None}
