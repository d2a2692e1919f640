"""What a planning run returns: :class:`PlanOutcome`, and its JSON forms.

``PlanOutcome.path_json()`` is the ``path.json`` contract of ``minkplan plan``::

    {"status": "found" | "no_path" | "not_found", "waypoints": [[x, y, z], ...],
     "length", "clearance", "timings": {...}, "validation": {"fcl": ..., "ompl": ...}}

plus ``message``, ``reason`` and ``planner``; ``report_json()`` is ``report.json``
(cells per label and level, graph size, refinement rounds, seconds per stage, the
certificate's summary) and ``certificate_json()`` the full no-path certificate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from planner.output import jsonable, schema_id
from planner.roles import FOUND, PlanStatus

from .report import stage_seconds

__all__ = ["PlanOutcome"]

@dataclass
class PlanOutcome:
    """The result of :func:`planner.planning.plan`.

    Attributes:
        status: a :class:`~planner.roles.PlanStatus` (``"found"``, ``"no_path"`` or
            ``"not_found"``).
        waypoints: ``(n, 3)`` translations from start to goal; ``(0, 3)`` unless found.
        length: path length (``nan`` without a path).
        clearance: minimum robot-obstacle distance along the path measured by FCL on the
            original meshes (``nan`` without a path).
        timings: seconds per stage, every key of
            :data:`~planner.planning.report.STAGES` (0.0 for a stage that did not run).
        validation: ``{"fcl": {...}, "ompl": {...}}`` (empty dicts when not validated).
        message: one line saying what happened.
        reason: machine-readable cause: ``"path"``, ``"certificate"``,
            ``"start_in_collision"``, ``"goal_in_collision"``, ``"floor"``,
            ``"budget"``, ``"time_limit"``, ``"validation_failed"``,
            ``"certificate_unverified"``, or an OMPL planner's reason.
        planner: ``"minkplan"`` or ``"ompl:NAME"``.
        certificate: for a proved no-path: summary plus the walled-off component and its
            FULL wall cells (boxes, primitives, obstacles), else ``None``.
        collision: for a start or goal in collision: obstacle name and depth estimates.
        report: everything else worth keeping (cells per level and label, refinement
            rounds, graph size, decomposition, resolution).
        cspace: the native C-space (octree leaves, roadmap) the answer came from, for
            visualisation (``planner.viz.scene_for_plan``); ``None`` for OMPL baselines.
        source: the C-obstacle :class:`~planner.sources.Source` the answer came from (the
            viz draws its C-obstacles); ``None`` for OMPL baselines.
    """

    status: PlanStatus
    waypoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    length: float = float("nan")
    clearance: float = float("nan")
    timings: dict[str, float] = field(default_factory=dict)
    validation: dict[str, Any] = field(default_factory=lambda: {"fcl": {}, "ompl": {}})
    message: str = ""
    reason: str = ""
    planner: str = "minkplan"
    certificate: dict[str, Any] | None = None
    collision: dict[str, Any] | None = None
    report: dict[str, Any] = field(default_factory=dict)
    cspace: Any = field(default=None, repr=False, compare=False)
    source: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.timings = stage_seconds(self.timings)

    @property
    def found(self) -> bool:
        return self.status == FOUND

    @property
    def exit_code(self) -> int:
        """The CLI's exit code: 0 found, 1 otherwise."""
        return 0 if self.found else 1

    def path_json(self) -> dict[str, Any]:
        """The ``path.json`` document."""
        return jsonable(
            {
                "schema": schema_id("path"),
                "status": self.status,
                "waypoints": np.asarray(self.waypoints, dtype=float).reshape(-1, 3),
                "length": self.length,
                "clearance": self.clearance,
                "timings": self.timings,
                "validation": self.validation,
                "message": self.message,
                "reason": self.reason,
                "planner": self.planner,
            }
        )

    def certificate_summary(self) -> dict[str, Any] | None:
        if self.certificate is None:
            return None
        return {k: v for k, v in self.certificate.items() if k not in ("walls", "component")}

    def report_json(self) -> dict[str, Any]:
        """The ``report.json`` document."""
        return jsonable(
            {
                "schema": schema_id("report"),
                "status": self.status,
                "reason": self.reason,
                "message": self.message,
                "planner": self.planner,
                "seconds": self.timings,
                "certificate": self.certificate_summary(),
                "collision": self.collision,
                **self.report,
            }
        )

    def certificate_json(self) -> dict[str, Any] | None:
        """The full certificate (wall cells and the walled-off component), or ``None``."""
        if self.certificate is None:
            return None
        return jsonable({"schema": schema_id("certificate"), **self.certificate})
