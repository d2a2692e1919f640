"""Independent validation of a found path on the original meshes: FCL conservative
advancement (:meth:`FclChecker.check_path`) and OMPL's ``PathGeometric.check``
(:func:`planner.validation.ompl_check_path`), summarised as JSON-ready dicts."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from planner.validation import FclChecker, ompl_check_path, ompl_missing

__all__ = ["validate_path"]


def validate_path(waypoints: np.ndarray, checker: FclChecker, bounds: np.ndarray) -> dict[str, Any]:
    """``{"valid": ..., "fcl": {...}, "ompl": {...}}`` for ``waypoints`` ``(n, 3)``.

    ``valid``: both checks passed; where OMPL is not installed, ``ompl`` says so
    (``available: false``, ``reason``) and ``valid`` is FCL's alone."""
    t0 = time.perf_counter()
    fcl = checker.check_path(waypoints)
    t1 = time.perf_counter()
    fcl_doc: dict[str, Any] = {
        "valid": bool(fcl.valid),
        "min_clearance": float(fcl.min_clearance),
        "clearance_lower_bound": float(fcl.clearance_lower_bound),
        "checks": int(fcl.n_checks),
        "contact_tolerance": checker.contact_tolerance,
        "seconds": t1 - t0,
    }
    if not fcl.valid:
        fcl_doc["first_bad_segment"] = fcl.first_bad_segment
        fcl_doc["obstacle"] = fcl.obstacle
        where = [] if fcl.first_invalid is None else np.round(fcl.first_invalid, 6).tolist()
        fcl_doc["detail"] = f"segment {fcl.first_bad_segment} hits {fcl.obstacle} at {where}"
    missing = ompl_missing()
    if missing is not None:
        return {"valid": fcl_doc["valid"], "fcl": fcl_doc,
                "ompl": {"available": False, "reason": missing}}
    ompl = ompl_check_path(waypoints, checker, bounds,
                           clearance=fcl.min_clearance if fcl.valid else 0.0)
    ompl_doc = {
        "available": True,
        "valid": bool(ompl.valid),
        "length": float(ompl.length),
        "resolution": float(ompl.resolution_used),
        "step": float(ompl.step),
        "states_checked": int(ompl.n_valid_checks + ompl.n_invalid_checks),
        "seconds": time.perf_counter() - t1,
    }
    return {"valid": fcl_doc["valid"] and ompl_doc["valid"], "fcl": fcl_doc, "ompl": ompl_doc}
