"""Independent validation of translation paths (FCL, OMPL) and OMPL planners as baselines.

- :mod:`.fcl_checker` -- :class:`FclChecker`: collision (including containment),
  clearance and conservative-advancement segment/path checks on the original meshes.
- :mod:`.ompl_check` -- :func:`ompl_check_path`: OMPL's ``PathGeometric.check()`` of a
  path at a clearance-derived resolution, optional ``PathSimplifier``.
- :mod:`.ompl_planners` -- :class:`OmplPlanner`: RRTConnect, PRM, BIT*, ... driven by
  the same checker, every returned path re-validated.

The roles these fill (``StateValidityChecker``, ``MotionValidator``, ``Planner``,
``PlanStatus``, ``PlanResult``) are in :mod:`planner.roles`, re-exported here. OMPL is
imported lazily (only when an OMPL function runs).
"""

from planner.roles import MotionValidator, Planner, PlanResult, PlanStatus, StateValidityChecker

from .checks import CheckerTolerances, PathCheck, SegmentCheck
from .fcl_checker import FclChecker
from .ompl_check import OmplPathCheck, ompl_check_path, ompl_missing, resolution_for_clearance
from .ompl_planners import OmplPlanner, available_planners

__all__ = [
    "CheckerTolerances",
    "FclChecker",
    "MotionValidator",
    "OmplPathCheck",
    "OmplPlanner",
    "PathCheck",
    "PlanResult",
    "PlanStatus",
    "Planner",
    "SegmentCheck",
    "StateValidityChecker",
    "available_planners",
    "ompl_missing",
    "ompl_check_path",
    "resolution_for_clearance",
]
