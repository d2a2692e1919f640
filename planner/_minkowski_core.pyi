"""Type stub of the native core ``planner._minkowski_core`` (hand-written, checked by
``mypy.stubtest`` in the tests)."""

from collections.abc import Sequence
from typing import Any, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "CSpace",
    "CheckedMesh",
    "ExactSum",
    "Primitives",
    "__version__",
    "budget_units",
    "build_octree",
    "closed_shell_sizes",
    "crossing_windings",
    "front_windings",
    "num_threads",
    "offset_surface",
    "rounded_polytope",
    "set_record_budget",
    "set_time_limit",
    "solid_windings",
    "tidy_solid_windings",
    "union_surface",
    "winding_numbers",
]
__version__: str

@final
class Primitives:
    """A union of convex primitives (for a C-obstacle: the pairwise sums) with a BVH."""

    @staticmethod
    def pairwise_sums(
        pieces_a: list[npt.NDArray[np.float64]],
        pieces_b: list[npt.NDArray[np.float64]],
        subtract: bool = False,
    ) -> Primitives: ...
    @staticmethod
    def from_pieces(pieces: list[npt.NDArray[np.float64]]) -> Primitives: ...
    def __len__(self) -> int: ...
    @property
    def bounds(self) -> npt.NDArray[np.float64]: ...
    def facet_counts(self) -> npt.NDArray[np.int64]: ...
    def polytope(self, i: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]: ...
    def contains(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]: ...
    def signed_distance(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def segment_is_free(self, a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]) -> bool: ...
    def segment_intervals(
        self, a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]
    ) -> list[tuple[float, float]]: ...

def union_surface(
    prims: Primitives,
    eps: float,
    max_cells: int = 8000000,
    max_refinements: int = 2,
    simplify: bool = True,
) -> dict[str, Any]: ...
def build_octree(
    prims: Primitives,
    h: float,
    bounds: npt.NDArray[np.float64] | None = None,
    max_cells: int = 40000000,
) -> dict[str, Any]: ...
def num_threads() -> int: ...
def set_record_budget(bytes: int) -> int:
    """Set the octree's candidate-record budget (bytes) for what follows; the previous."""
def set_time_limit(seconds: float | None = None) -> None:
    """Stop octree builds and refinements ``seconds`` from now (None: never)."""
def budget_units() -> dict[str, int]:
    """Bytes of the units the budgets count: leaf, record_word, facet; max_record_words."""
def front_windings(
    vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64]
) -> npt.NDArray[np.int64]:
    """Winding number just in front of each face of a closed mesh (int64 min: unknown)."""
def crossing_windings(
    vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64]
) -> npt.NDArray[np.int64]:
    """Winding number in front of both faces of each crossing (int64 min: unknown)."""
def solid_windings(
    vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64], name: str = "mesh"
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], int, CheckedMesh | None]:
    """Both windings above, how many crossings have the solid on both sides of both
    faces (winding 2 or more behind both: shells that overlap), and the checked solid
    when no winding is negative or unknown."""
def tidy_solid_windings(
    vertices: npt.NDArray[np.float64],
    faces: npt.NDArray[np.int64],
    limits: tuple[float, float, float, float, float],
    name: str = "mesh",
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], int, CheckedMesh] | None:
    """``solid_windings`` of a mesh the cleaning would not change (``limits``: merge
    distance, degenerate area, flat volume, fold angle, coplanar distance, in the mesh's
    units) that is a solid; ``None`` otherwise."""
def closed_shell_sizes(
    vertices: npt.NDArray[np.float64], faces: npt.NDArray[np.int64]
) -> list[int]:
    """Triangle counts of the closed shells (mod 2: every edge, welded, used an even
    number of times) the triangles hold, most first, as the exact source's shell
    witnesses find them."""

def winding_numbers(
    vertices: npt.NDArray[np.float64],
    faces: npt.NDArray[np.int64],
    points: npt.NDArray[np.float64],
) -> npt.NDArray[np.int64]:
    """Exact winding numbers of points for a closed mesh (int64 min: on the surface)."""

@final
class CheckedMesh:
    """A part's triangle mesh checked once (a solid, or with ``solid=False`` a surface),
    with its BVH: :class:`ExactSum` and :meth:`CSpace.exact` take it unchecked."""

    def __new__(
        cls,
        vertices: npt.NDArray[np.float64],
        faces: npt.NDArray[np.int64],
        solid: bool = True,
        name: str = "mesh",
    ) -> CheckedMesh: ...
    @property
    def solid(self) -> bool: ...
    @property
    def triangles(self) -> int: ...
    def negated(self) -> CheckedMesh: ...

_MeshArg = tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]] | CheckedMesh

def offset_surface(
    mesh: CheckedMesh,
    radius: float,
    eps: float,
    max_cells: int = 8000000,
    max_refinements: int = 2,
    simplify: bool = True,
    refine_creases: bool = True,
) -> dict[str, Any]: ...
def rounded_polytope(
    points: npt.NDArray[np.float64],
    radius: float,
    tol: float,
    weld: float = 0.0,
    max_triangles: int = 20000000,
) -> dict[str, Any]: ...

@final
class ExactSum:
    """The exact Minkowski sum ``A ⊕ B`` of two closed meshes (boundary convolution)."""

    def __new__(
        cls,
        a: _MeshArg,
        b: _MeshArg,
        a_solid: bool = True,
        b_solid: bool = True,
        max_facets: int = 8000000,
        pieces: bool = False,
        depth_near: tuple[list[float], float] | None = None,
    ) -> ExactSum: ...
    @property
    def bounds(self) -> npt.NDArray[np.float64]: ...
    @property
    def triangles(self) -> tuple[int, int]: ...
    @property
    def facets(self) -> int: ...
    def contains(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]: ...
    def segment_is_free(self, a: list[float], b: list[float], margin: float = 0.0) -> bool: ...
    def signed_distance(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def segment_intervals(
        self, a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]
    ) -> list[tuple[float, float]]: ...
    def surface(
        self, eps: float, max_cells: int = 8000000, max_refinements: int = 2, simplify: bool = True
    ) -> dict[str, Any]: ...
    def depth(
        self, point: npt.NDArray[np.float64], tolerance: float, max_cells: int = 1000000
    ) -> dict[str, Any]:
        """The distance from ``point`` to the sum's boundary as a proved interval (inside:
        penetration depth; outside: separation distance)."""

@final
class CSpace:
    """The translational C-space of a planning problem: C-obstacle primitives (grown by
    ``margin``), walls outside ``bounds`` and a refinable octree with its roadmap."""

    def __new__(
        cls,
        prims: Primitives | None,
        bounds: npt.NDArray[np.float64],
        h_floor: float,
        h_coarse: float,
        margin: float = 0.0,
        max_leaves: int = 20000000,
    ) -> CSpace: ...
    @staticmethod
    def exact(
        obstacles: Sequence[_MeshArg],
        robot: _MeshArg,
        bounds: npt.NDArray[np.float64],
        h_floor: float,
        h_coarse: float,
        margin: float = 0.0,
        max_leaves: int = 20000000,
        solid: Sequence[bool] | None = None,
        robot_solid: bool = True,
        max_facets: int = 8000000,
        reuse: Sequence[ExactSum | None] | None = None,
    ) -> CSpace:
        """C-space of the exact source: C-obstacles of solids or surfaces, no
        decomposition."""
    @property
    def reused(self) -> list[bool]: ...
    @property
    def is_exact(self) -> bool: ...
    def __len__(self) -> int: ...
    @property
    def n_obstacle_prims(self) -> int: ...
    @property
    def n_primitives(self) -> int: ...
    @property
    def floor(self) -> float: ...
    @property
    def coarse_level(self) -> int: ...
    @property
    def depth(self) -> int: ...
    @property
    def origin(self) -> npt.NDArray[np.float64]: ...
    @property
    def margin(self) -> float: ...
    def leaves(self) -> dict[str, Any]: ...
    def leaf(self, i: int) -> tuple[int, int]: ...
    def cell_box(self, i: int) -> npt.NDArray[np.float64]: ...
    def locate(self, point: Sequence[float]) -> int | None: ...
    def neighbors(self, i: int) -> list[tuple[int, list[float]]]: ...
    def adjacency(
        self, labels: Sequence[int]
    ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]: ...
    def components(self, labels: Sequence[int]) -> npt.NDArray[np.int64]: ...
    def contains(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]: ...
    def signed_distance(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    def containing(self, point: Sequence[float]) -> list[tuple[int, float]]: ...
    def segment_is_free(
        self, a: Sequence[float], b: Sequence[float], margin: float = 0.0
    ) -> bool: ...
    def attach(
        self, point: Sequence[float], rings: int = 2
    ) -> list[tuple[int, list[float], float]]: ...
    def free_path(
        self, start: Sequence[float], goal: Sequence[float], rings: int = 2
    ) -> dict[str, Any] | None: ...
    def channel(
        self,
        start: Sequence[float],
        goal: Sequence[float],
        penalty: float = 2.0,
        refinable_only: bool = True,
    ) -> dict[str, Any] | None: ...
    def refine(
        self, leaves: Sequence[int], ring: bool = True, levels: int = 1
    ) -> dict[str, Any]: ...
    def level_counts(self) -> list[list[int]]: ...
    def roadmap_size(self) -> tuple[int, int]: ...
    def shortcut(
        self, waypoints: npt.NDArray[np.float64], margin: float = 0.0, passes: int = 3
    ) -> npt.NDArray[np.float64]: ...
    def certificate(
        self, start: Sequence[float], goal: Sequence[float]
    ) -> dict[str, Any] | None: ...
    def enclosure(self, start: Sequence[float]) -> dict[str, Any] | None: ...
    def primitive_planes(
        self, i: int
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
