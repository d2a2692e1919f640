"""minkplan: translational motion planning on Minkowski-sum C-obstacles.

Public API:

- :func:`load_scenario` -> :class:`Scenario`; :func:`plan` -> :class:`PlanOutcome`
- :func:`load_assembly`, :func:`plan_assembly` -> :class:`AssemblyResult`
- :func:`minkowski_sum`, :func:`c_obstacle` -> :class:`MinkowskiResult`
- :func:`decompose` -> :class:`Decomposition` (convex pieces, cached)
- :func:`load_mesh`, :func:`validate_solid`, :func:`repair_mesh`, :func:`mirror`
- :mod:`planner.errors` (every error minkplan raises), :data:`tol` (all tolerances)
"""

try:
    from . import _minkowski_core  # native core
except ImportError as _exc:  # pragma: no cover - depends on how it was installed
    import os as _os

    raise ImportError(
        f"planner's native module _minkowski_core is not built in {_os.path.dirname(__file__)}: "
        "this is probably the source tree shadowing an installed minkplan (run from another "
        "directory, or install with `pip install -e .` so the module is built here)"
    ) from _exc
from .assembly import AssemblyResult, load_assembly, plan_assembly
from .decompose import Decomposition, decompose
from .errors import (
    GeometryError,
    InvalidMeshError,
    InvalidParameterError,
    MinkplanError,
    ResourceLimitError,
    ScenarioError,
)
from .meshes import load_mesh, mirror, repair_mesh, validate_solid
from .minkowski import MinkowskiResult, c_obstacle, minkowski_sum
from .planning import PlanOutcome, plan
from .scenario import Scenario, load_scenario
from .tolerances import Tolerances, tol

__version__ = _minkowski_core.__version__

__all__ = [
    "AssemblyResult",
    "Decomposition",
    "GeometryError",
    "InvalidMeshError",
    "InvalidParameterError",
    "MinkowskiResult",
    "MinkplanError",
    "PlanOutcome",
    "ResourceLimitError",
    "Scenario",
    "ScenarioError",
    "Tolerances",
    "c_obstacle",
    "decompose",
    "load_assembly",
    "load_mesh",
    "load_scenario",
    "minkowski_sum",
    "mirror",
    "plan",
    "plan_assembly",
    "repair_mesh",
    "tol",
    "validate_solid",
]
