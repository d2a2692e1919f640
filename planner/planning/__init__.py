"""Planning a translational path for a scenario.

Entry point: :func:`plan` -> :class:`PlanOutcome` (``status`` ``"found"``, ``"no_path"``
or ``"not_found"``; waypoints, length, clearance, timings, validation, certificate,
report). ``planner="minkplan"`` (default) is the octree roadmap of
:mod:`.octree_planner`; ``planner="ompl:NAME"`` runs OMPL's planner ``NAME`` with the FCL
checker (:mod:`.ompl_baseline`) and reports the same way.
"""

from __future__ import annotations

from planner.errors import InvalidParameterError
from planner.scenario import Scenario

from .octree_planner import OctreeParams, default_contact_tolerance, plan_octree
from .outcome import FOUND, NO_PATH, NOT_FOUND, PlanOutcome

__all__ = [
    "FOUND",
    "NOT_FOUND",
    "NO_PATH",
    "OctreeParams",
    "PlanOutcome",
    "default_contact_tolerance",
    "plan",
]


def plan(scenario: Scenario, *, planner: str = "minkplan", cache_dir=None,
         progress: bool | None = None, params: OctreeParams | None = None,
         validate: bool = True) -> PlanOutcome:
    """Plan a translational path for ``scenario``.

    Args:
        scenario: a :class:`~planner.scenario.Scenario` (``planner.load_scenario``).
        planner: ``"minkplan"`` or ``"ompl:NAME"`` (``ompl:RRTConnect``, ``ompl:PRM``,
            ``ompl:BITstar``, ...).
        cache_dir: decomposition cache directory (default ``$MINKPLAN_CACHE_DIR`` or
            ``~/.cache/minkplan/decompositions``).
        progress: status line on stderr; ``None``: only on a TTY.
        params: octree planner parameters (scale-free defaults).
        validate: validate found paths with FCL and OMPL on the original meshes.

    Returns:
        :class:`PlanOutcome`; planning outcomes are statuses, never exceptions.

    Raises:
        InvalidParameterError: unknown planner, or ``planner.exact: true`` with a part
            that needs an approximate decomposition.
        InvalidMeshError, GeometryError: unusable meshes.
    """
    if planner == "minkplan":
        return plan_octree(scenario, params=params, cache_dir=cache_dir, progress=progress,
                           validate=validate)
    if planner.startswith("ompl:") and len(planner) > 5:
        from .ompl_baseline import plan_ompl

        return plan_ompl(scenario, planner[5:], validate=validate)
    raise InvalidParameterError(
        f"planner {planner!r}: use 'minkplan' or 'ompl:NAME' (e.g. ompl:RRTConnect)")
