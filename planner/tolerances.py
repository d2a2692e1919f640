"""Tolerances, in one place.

All numerical tolerances minkplan uses are fields of one frozen :class:`Tolerances`
object; the module-level default is :data:`tol` (in the spirit of
``trimesh.constants.tol``). Geometric tolerances are *relative*: multiply by the scale of
the input, :func:`scale_of` (its bounding-box diagonal), to get an absolute length in the
input's units. To change one, derive a new object rather than mutating the default::

    import dataclasses
    from planner.tolerances import tol
    fine = dataclasses.replace(tol, eps_rel=0.001)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InvalidParameterError

__all__ = ["Tolerances", "scale_of", "tol"]


@dataclass(frozen=True)
class Tolerances:
    """Numerical tolerances; relative ones are fractions of the input's scale.

    Attributes:
        eps_rel: default Minkowski-sum / C-obstacle resolution ``eps`` as a fraction of
            the result's bounding-box diagonal.
        convex_volume_rel: a body counts as convex when
            ``hull_volume - volume <= convex_volume_rel * hull_volume``.
        degenerate_area_rel: a triangle whose area is below
            ``degenerate_area_rel * scale**2`` is degenerate (zero area).
        zero_volume_rel: a closed shell whose ``|volume|`` is below
            ``zero_volume_rel * scale**3`` is flat (has no interior).
        merge_rel: vertices closer than ``merge_rel * scale`` are merged.
        fold_angle: faces of one closed shell whose normals are opposite within this
            angle (radians), that lie in the same plane (within ``coplanar_rel *
            scale``) and overlap there, make the surface overlap itself: that is what a
            wrongly triangulated (fanned non-convex) polygon looks like, and
            :func:`~planner.meshes.validate_solid` rejects it.
        coplanar_rel: distance, relative to the scale, under which two faces count
            as lying in the same plane for that check.
        max_cells: budget of grid/octree cells of one surface (a sum, an offset), used to
            estimate memory before heavy work; exceeding it raises
            :class:`~planner.errors.ResourceLimitError`. ``None`` (the default): derived
            from the memory limit (:mod:`planner.budget`, ``--memory-limit``).
        coacd_threshold: default CoACD concavity threshold (CoACD normalises the mesh,
            so this is relative; smaller is finer and slower; CoACD accepts 0.01 .. 1).
        excess_samples: number of surface samples used to estimate a decomposition's
            excess (hull surfaces) and its deficit (solid surface).
        sample_seed: seed of the random generator used for those samples, so that the
            estimates are reproducible.
        touch_rel: faces of one shell closer than ``touch_rel * scale`` across their
            shared plane only touch (the self-overlap test of
            :func:`~planner.meshes.validate_solid` does not count them).
        orientation_deg: start and goal orientations that differ by at most this angle
            (degrees) are equal (scenario YAML and OMPL.app files alike).
        quaternion_norm: a quaternion ``[w, x, y, z]`` whose norm is within this of 1 is
            accepted and normalised; anything else is a typo or a wrong component order.
        flat_rel: a piece of an imported world thinner than ``flat_rel`` times the
            world's size is flat (it has no interior).
        planar_rel: a boundary loop whose points leave their best-fit plane by at most
            ``planar_rel`` times the loop's size is planar.
        depth_rel: default width of a penetration-depth interval
            (:func:`~planner.depth.penetration_depth`) as a fraction of the pair's size.
        depth_max_cells: budget of cells one penetration-depth search may classify
            (``None``: :meth:`planner.budget.MemoryBudget.depth_cells`).
    """

    eps_rel: float = 0.005
    convex_volume_rel: float = 1e-6
    degenerate_area_rel: float = 1e-12
    zero_volume_rel: float = 1e-12
    merge_rel: float = 1e-9
    fold_angle: float = 1e-3
    coplanar_rel: float = 1e-5
    max_cells: int | None = None
    coacd_threshold: float = 0.05
    excess_samples: int = 20_000
    sample_seed: int = 0
    touch_rel: float = 1e-7
    orientation_deg: float = 1e-4
    quaternion_norm: float = 1e-3
    flat_rel: float = 1e-9
    planar_rel: float = 1e-6
    depth_rel: float = 1e-3
    depth_max_cells: int | None = None

    def __post_init__(self) -> None:
        for field in (
            "eps_rel",
            "convex_volume_rel",
            "degenerate_area_rel",
            "zero_volume_rel",
            "merge_rel",
            "fold_angle",
            "coplanar_rel",
            "coacd_threshold",
            "touch_rel",
            "orientation_deg",
            "quaternion_norm",
            "flat_rel",
            "planar_rel",
            "depth_rel",
        ):
            value = getattr(self, field)
            if not (np.isfinite(value) and value > 0):
                raise InvalidParameterError(
                    f"Tolerances.{field} = {value!r}: must be a finite number > 0"
                )
        for field in ("max_cells", "excess_samples", "depth_max_cells"):
            value = getattr(self, field)
            if value is None and field != "excess_samples":
                continue
            if int(value) != value or value < 1:
                raise InvalidParameterError(
                    f"Tolerances.{field} = {value!r}: must be an integer >= 1"
                )


tol = Tolerances()
"""The default tolerances."""


def scale_of(mesh_or_bounds) -> float:
    """Length scale of an input: the diagonal of its axis-aligned bounding box.

    Args:
        mesh_or_bounds: anything with a ``.bounds`` attribute (a ``trimesh.Trimesh``,
            ``trimesh.Scene``, ...), a ``(2, 3)`` array ``[min, max]`` of bounds, or an
            ``(n, 3)`` array of points (``n != 2``).

    Returns:
        The diagonal length, ``>= 0``, in the input's units.

    Raises:
        InvalidParameterError: the input has no bounds (empty) or non-finite ones.
    """
    bounds = getattr(mesh_or_bounds, "bounds", mesh_or_bounds)
    if bounds is None:
        raise InvalidParameterError("scale_of: input has no bounds (is it empty?)")
    array = np.asarray(bounds, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3 or len(array) == 0:
        raise InvalidParameterError(
            f"scale_of: expected a mesh, (2, 3) bounds or (n, 3) points, got shape "
            f"{array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise InvalidParameterError("scale_of: bounds are not finite (NaN or inf)")
    if len(array) != 2:
        array = np.stack([array.min(axis=0), array.max(axis=0)])
    return float(np.linalg.norm(array[1] - array[0]))
