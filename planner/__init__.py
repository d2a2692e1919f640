"""minkplan: translational motion planning on Minkowski-sum C-obstacles.

Public API:

- :func:`load_problem` (scenario YAML, OMPL.app ``.cfg``, assembly YAML),
  :func:`load_scenario` -> :class:`Scenario`; :func:`plan` -> :class:`PlanOutcome`
- :func:`load_assembly`, :func:`plan_assembly` -> :class:`AssemblyResult`
- :func:`minkowski_sum`, :func:`c_obstacle` -> :class:`MinkowskiResult`
- :func:`penetration_depth` -> :class:`PenetrationDepth` (proved interval, direction)
- :func:`offset`, :func:`opening`, :func:`closing` -> :class:`OffsetResult` (grown or
  eroded solids with a two-sided bound)
- :func:`choose_source` -> a C-obstacle :class:`Source` (exact or decomposition) that
  every one of those takes
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
import sys as _sys
import types as _types
from typing import TYPE_CHECKING

__version__ = _minkowski_core.__version__

_EXPORTS = {
    "AssemblyResult": "assembly", "plan_assembly": "assembly",
    "memory_limit": "budget", "set_memory_limit": "budget",
    "Decomposition": "decompose", "decompose": "decompose",
    "PenetrationDepth": "depth", "penetration_depth": "depth",
    "OffsetResult": "offsets", "offset": "offsets", "opening": "offsets",
    "closing": "offsets",
    "GeometryError": "errors", "InvalidMeshError": "errors",
    "InvalidParameterError": "errors", "MinkplanError": "errors",
    "ResourceLimitError": "errors", "ScenarioError": "errors",
    "load_assembly": "io", "load_problem": "io", "load_scenario": "io",
    "load_mesh": "meshes", "mirror": "meshes", "repair_mesh": "meshes",
    "validate_solid": "meshes",
    "MinkowskiResult": "minkowski", "c_obstacle": "minkowski", "minkowski_sum": "minkowski",
    "PlanOutcome": "planning", "PlanStatus": "planning", "plan": "planning",
    "Assembly": "problem", "Part": "problem", "PlannerSettings": "problem",
    "Scenario": "problem",
    "Source": "sources", "SourceSettings": "sources",
    "Tolerances": "tolerances", "tol": "tolerances",
}
"""Where each public name lives: imported when first used, so ``import planner`` (and
``minkplan --help``) does not load trimesh, FCL and OMPL until something needs them."""


class _Package(_types.ModuleType):
    """The ``planner`` module's type: importing a submodule makes the import system set the
    package's attribute of that name to the submodule, which would hide the public function
    of the same name (``planner.decompose`` after anything imported ``planner.decompose``,
    e.g. a sum). The function is kept; the submodule stays in ``sys.modules``."""

    def __setattr__(self, name: str, value) -> None:
        if isinstance(value, _types.ModuleType) and _EXPORTS.get(name) == name:
            value = getattr(value, name)
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package


def __getattr__(name: str):
    if name == "choose_source":
        from .sources import choose

        globals()[name] = choose
        return choose
    module = _EXPORTS.get(name)
    if module is None:
        return _submodule(name)
    import importlib

    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def _submodule(name: str):
    """The subpackage or module ``planner.NAME`` (``planner.meshes``), imported when first
    used: reachable after ``import planner`` alone, as messages name its functions
    (``planner.meshes.repair_mesh``)."""
    import importlib
    import importlib.util

    if name.startswith("__") or "." in name or \
            importlib.util.find_spec(f"{__name__}.{name}") is None:
        raise AttributeError(f"module 'planner' has no attribute {name!r}")
    return importlib.import_module(f".{name}", __name__)


if TYPE_CHECKING:
    from .assembly import AssemblyResult, plan_assembly
    from .budget import memory_limit, set_memory_limit
    from .decompose import Decomposition, decompose
    from .depth import PenetrationDepth, penetration_depth
    from .errors import (
        GeometryError,
        InvalidMeshError,
        InvalidParameterError,
        MinkplanError,
        ResourceLimitError,
        ScenarioError,
    )
    from .io import load_assembly, load_problem, load_scenario
    from .meshes import load_mesh, mirror, repair_mesh, validate_solid
    from .minkowski import MinkowskiResult, c_obstacle, minkowski_sum
    from .offsets import OffsetResult, closing, offset, opening
    from .planning import PlanOutcome, PlanStatus, plan
    from .problem import Assembly, Part, PlannerSettings, Scenario
    from .sources import Source, SourceSettings
    from .sources import choose as choose_source
    from .tolerances import Tolerances, tol

__all__ = [
    "Assembly",
    "AssemblyResult",
    "Decomposition",
    "GeometryError",
    "InvalidMeshError",
    "InvalidParameterError",
    "MinkowskiResult",
    "MinkplanError",
    "OffsetResult",
    "Part",
    "PenetrationDepth",
    "PlanOutcome",
    "PlanStatus",
    "PlannerSettings",
    "ResourceLimitError",
    "Scenario",
    "ScenarioError",
    "Source",
    "SourceSettings",
    "Tolerances",
    "c_obstacle",
    "choose_source",
    "closing",
    "decompose",
    "load_assembly",
    "load_mesh",
    "load_problem",
    "load_scenario",
    "memory_limit",
    "minkowski_sum",
    "mirror",
    "offset",
    "opening",
    "penetration_depth",
    "plan",
    "plan_assembly",
    "repair_mesh",
    "set_memory_limit",
    "tol",
    "validate_solid",
]
