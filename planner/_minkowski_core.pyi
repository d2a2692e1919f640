"""Type stub of the native core ``planner._minkowski_core`` (hand-written, checked by
``mypy.stubtest`` in the tests)."""

from typing import Any, final

import numpy as np
import numpy.typing as npt

__all__ = ["Primitives", "__version__", "build_octree", "num_threads", "union_surface"]
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
