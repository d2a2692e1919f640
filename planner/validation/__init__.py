"""Independent validation of translation paths (FCL, OMPL) and OMPL planners as baselines.

- :mod:`.protocols` -- ``StateValidityChecker``, ``MotionValidator``, ``Planner``
  protocols, ``PlanStatus`` and ``PlanResult``.
- :mod:`.fcl_checker` -- :class:`FclChecker`: collision (including containment),
  clearance and conservative-advancement segment/path checks on the original meshes.
- :mod:`.ompl_check` -- :func:`ompl_check_path`: OMPL's ``PathGeometric.check()`` of a
  path at a clearance-derived resolution, optional ``PathSimplifier``.
- :mod:`.ompl_planners` -- :class:`OmplPlanner`: RRTConnect, PRM, BIT*, ... driven by
  the same checker, every returned path re-validated.

OMPL is imported lazily (only when an OMPL function runs).
"""

from .fcl_checker import CheckerTolerances, FclChecker, PathCheck, SegmentCheck, winding_numbers
from .ompl_check import OmplPathCheck, ompl_check_path, resolution_for_clearance
from .ompl_planners import OmplPlanner, available_planners
from .protocols import MotionValidator, Planner, PlanResult, PlanStatus, StateValidityChecker

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
    "ompl_check_path",
    "resolution_for_clearance",
    "winding_numbers",
]
