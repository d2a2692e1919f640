"""Planning a translational path for a scenario.

Entry point: :func:`plan` -> :class:`PlanOutcome` (``status`` ``"found"``, ``"no_path"``
or ``"not_found"``; waypoints, length, clearance, timings, validation, certificate,
report). ``planner="minkplan"`` (default) is the octree roadmap,
:class:`~.octree_planner.OctreePlanner` (setup and solve, as OMPL's planners);
``planner="ompl:NAME"`` runs OMPL's planner ``NAME`` with the FCL checker
(:mod:`.ompl_baseline`) and reports the same way. :class:`~.cspace_checker.CSpaceChecker`
makes the native C-space a validity checker and motion validator for OMPL.
"""

from __future__ import annotations

from planner.blas import single_blas_thread
from planner.errors import InvalidParameterError
from planner.problem import Assembly, Scenario, outside_bounds
from planner.roles import FOUND, NO_PATH, NOT_FOUND, PlanStatus
from planner.sources import Source

from .cspace_checker import CSpaceChecker
from .octree_planner import OctreeParams, OctreePlanner, default_contact_tolerance
from .outcome import PlanOutcome

__all__ = [
    "FOUND",
    "NOT_FOUND",
    "NO_PATH",
    "CSpaceChecker",
    "OctreeParams",
    "OctreePlanner",
    "PlanOutcome",
    "PlanStatus",
    "default_contact_tolerance",
    "plan",
]


@single_blas_thread
def plan(scenario: Scenario, *, planner: str = "minkplan", cache_dir=None,
         progress: bool | None = None, params: OctreeParams | None = None,
         validate: bool = True, source: Source | None = None) -> PlanOutcome:
    """Plan a translational path for ``scenario``.

    Args:
        scenario: a :class:`~planner.problem.Scenario` (``planner.load_scenario``).
        planner: ``"minkplan"`` or ``"ompl:NAME"`` (``ompl:RRTConnect``, ``ompl:PRM``,
            ``ompl:BITstar``, ...).
        cache_dir: decomposition cache directory (default ``$MINKPLAN_CACHE_DIR`` or
            the user cache folder, see :func:`planner.decompose.default_cache_dir`).
        progress: status line on stderr; ``None``: only on a TTY.
        params: octree planner parameters (scale-free defaults).
        validate: validate found paths with FCL and OMPL on the original meshes.
        source: the C-obstacle source (default: chosen from the scenario's settings).

    Returns:
        :class:`PlanOutcome`; planning outcomes are statuses, never exceptions.

    Raises:
        InvalidParameterError: unknown planner; ``scenario`` not a Scenario, or its start
            or goal outside its bounds.
        ScenarioError: ``planner.exact: false`` with a part that is a surface.
        InvalidMeshError, GeometryError: unusable meshes.
    """
    if not isinstance(scenario, Scenario):
        hint = "; an assembly goes to planner.plan_assembly" \
            if isinstance(scenario, Assembly) else ""
        raise InvalidParameterError(f"plan takes a Scenario (planner.load_scenario), not "
                                    f"{type(scenario).__name__}{hint}")
    _check_within_bounds(scenario)
    if planner == "minkplan":
        return OctreePlanner(scenario, params=params, source=source, cache_dir=cache_dir,
                             progress=progress, validate=validate).solve()
    if planner.startswith("ompl:") and len(planner) > 5:
        from .ompl_baseline import plan_ompl

        return plan_ompl(scenario, planner[5:], validate=validate)
    raise InvalidParameterError(
        f"planner {planner!r}: use 'minkplan' or 'ompl:NAME' (e.g. ompl:RRTConnect)")


def _check_within_bounds(scenario: Scenario) -> None:
    """Refuse a start or goal outside the scenario's bounds (the readers refuse it in a
    file; a scenario made in Python is checked here)."""
    for name, point in (("start", scenario.start), ("goal", scenario.goal)):
        outside = outside_bounds(point, scenario.bounds)
        if outside:
            raise InvalidParameterError(f"Scenario.{name}: {point.tolist()} is outside the "
                                        f"bounds ({'; '.join(outside)})")
