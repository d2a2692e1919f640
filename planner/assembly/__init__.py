"""Assembly planning by disassembly: which part can leave, along which path, and the
order that puts the parts together.

- :mod:`.model` -- :class:`AssemblyStep`, :class:`AssemblyResult` (``sequence.json``,
  ``report.json``).
- :mod:`.geometry` -- exit boxes, exit points, the six directions.
- :mod:`.pairs` -- :class:`PairCache`: each pair's C-obstacle and ray verdicts, once.
- :mod:`.enclosure` -- :func:`~.enclosure.prove_enclosed`: a part walled in near its
  start, proved on a small box (before any planning).
- :mod:`.search` -- :func:`plan_assembly`, :func:`removal_scenario`,
  :func:`removal_problems`.

Assembly files are read by :func:`planner.io.load_assembly` into a
:class:`~planner.problem.Assembly`; the animation is :func:`planner.viz.scene_for_assembly`.
"""

from planner.problem import DEFAULT_CONTACT_REL, Assembly

from .geometry import DIRECTIONS, ESCAPE_MARGIN_REL
from .model import INTERLOCKED, SEQUENCE, AssemblyResult, AssemblyStep
from .pairs import PairCache, RayVerdict
from .search import GOAL_SIDE, plan_assembly, removal_problems, removal_scenario

__all__ = [
    "DEFAULT_CONTACT_REL",
    "DIRECTIONS",
    "ESCAPE_MARGIN_REL",
    "GOAL_SIDE",
    "INTERLOCKED",
    "SEQUENCE",
    "Assembly",
    "AssemblyResult",
    "AssemblyStep",
    "PairCache",
    "RayVerdict",
    "plan_assembly",
    "removal_problems",
    "removal_scenario",
]
