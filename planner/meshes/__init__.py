"""Meshes: files, triangulation, index bookkeeping, solids and repair.

- :mod:`.formats` -- :func:`load_mesh`, :func:`load_obj` (n-gons triangulated properly).
- :mod:`.triangulation` -- polygons triangulated in their plane.
- :mod:`.topology` -- edges, components, winding consistency, vertex merging.
- :mod:`.solids` -- :func:`validate_solid`, :func:`split_solid`, :func:`mirror`,
  :func:`winding_numbers`.
- :mod:`.repair` -- :func:`repair_mesh`.
"""

from .formats import MESH_SUFFIXES, load_mesh, load_obj
from .repair import repair_mesh
from .solids import (
    SOLID_REASON,
    mirror,
    not_solid_reason,
    split_solid,
    validate_solid,
    winding_numbers,
)

__all__ = [
    "MESH_SUFFIXES",
    "SOLID_REASON",
    "load_mesh",
    "load_obj",
    "mirror",
    "not_solid_reason",
    "repair_mesh",
    "split_solid",
    "validate_solid",
    "winding_numbers",
]
