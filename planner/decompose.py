"""Convex decomposition of solids for the native core, cached on disk.

Entry point: :func:`decompose` splits a solid into bodies; a body that is convex (its
hull volume equals its volume within ``tol.convex_volume_rel``) is used as it is, and
every other body goes through CoACD (approximate convex decomposition). The result,
:class:`Decomposition`, holds the vertices of the convex pieces, whether they are exact,
and sampled estimates of how far the union of their hulls sticks out of the solid
(``excess``, which adds to every error bound downstream) and how far the solid sticks out
of it (``deficit``).

CoACD takes seconds to minutes, so results are cached on disk (see
:func:`default_cache_dir`), keyed by a hash of the mesh and every parameter that affects
the result. Entries are written atomically and carry a checksum: a truncated, corrupt or
foreign entry is detected on load, logged, deleted and recomputed.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
import logging
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import platformdirs
import trimesh
from scipy.spatial import ConvexHull, QhullError

from .blas import single_blas_thread
from .decompose_cache import FORMAT_VERSION, SUFFIX, load_entry, store_entry
from .errors import GeometryError, InvalidParameterError
from .meshes import split_solid, validate_solid
from .progress import StatusLine
from .tolerances import scale_of, tol
from .values import check_seed

__all__ = ["CACHE_ENV", "Decomposition", "check_threshold", "decompose", "default_cache_dir",
           "is_convex_body"]

log = logging.getLogger(__name__)

CACHE_ENV = "MINKPLAN_CACHE_DIR"
"""Environment variable naming the decomposition cache directory."""



@dataclass(frozen=True)
class Decomposition:
    """Convex pieces whose union approximates a solid.

    Attributes:
        pieces: one ``(k, 3)`` float64 array per convex piece: the vertices of its hull.
        exact: True when every body was convex as given, so the pieces are the bodies
            themselves and their union is exactly the solid.
        excess: estimated one-sided Hausdorff distance from the union of the piece
            hulls to the solid (absolute units; 0.0 when exact): how far the
            approximation sticks out. A sampled estimate (a lower bound in principle,
            see :func:`decompose`).
        deficit: estimated distance by which the solid sticks out of the union of the
            hulls (should be ~0: CoACD hulls cover the part they were cut from).
        method: ``"convex"`` (all bodies convex), ``"coacd"`` (all went through CoACD)
            or ``"mixed"``.
        bodies: number of bodies (outer shells with their cavities) in the solid.
        cache_hit: True when the result was loaded from the cache.
        seconds: wall-clock time of this call.
        threshold: the CoACD concavity threshold used.
    """

    pieces: list[np.ndarray]
    exact: bool
    excess: float
    deficit: float
    method: str
    bodies: int
    cache_hit: bool
    seconds: float
    threshold: float


def default_cache_dir() -> Path:
    """Cache directory: ``$MINKPLAN_CACHE_DIR`` if set, else ``decompositions`` in the
    platform's user cache folder (platformdirs: ``$XDG_CACHE_HOME/minkplan`` or
    ``~/.cache/minkplan`` on Linux, ``~/Library/Caches/minkplan`` on macOS,
    ``%LOCALAPPDATA%\\minkplan\\Cache`` on Windows)."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    return platformdirs.user_cache_path("minkplan", appauthor=False) / "decompositions"


@single_blas_thread
def decompose(
    mesh,
    *,
    threshold: float = tol.coacd_threshold,
    seed: int = 0,
    cache_dir=None,
    name: str = "mesh",
    progress: bool | None = None,
    coacd_options: dict | None = None,
    checked: bool = False,
) -> Decomposition:
    """Decompose a solid into convex pieces (exact where possible, else CoACD), cached.

    The mesh is validated with :func:`planner.meshes.validate_solid` and split into
    bodies (outer shells with their cavities). A body whose convex hull volume equals
    its volume within ``tol.convex_volume_rel`` contributes its hull vertices as one
    exact piece; every other body is decomposed by CoACD (deterministic for a given
    ``seed``), each CoACD part contributing its hull vertices.

    Error estimates (only for CoACD bodies; exact pieces contribute nothing): ``excess``
    is the largest distance to the solid of ``tol.excess_samples`` points sampled on
    the piece hulls' surfaces (plus their vertices) that lie outside the solid;
    ``deficit`` is the largest distance to the nearest hull of as many points sampled
    on the solid's surface that lie outside every hull. Sampling gives estimates, not
    bounds: a spike of the hulls between samples can be missed, and a void strictly
    inside a hull (away from its surface) is not seen by surface samples.

    Args:
        mesh: ``trimesh.Trimesh`` of a solid.
        threshold: CoACD concavity threshold in ``(0, 1]`` (smaller: more, tighter
            pieces, slower). Not used when every body is convex.
        seed: CoACD random seed (see :data:`planner.values.SEED_LIMIT`).
        cache_dir: cache directory; default :func:`default_cache_dir`. Caching is
            skipped (with a warning) when the directory cannot be written.
        name: label for messages and logs.
        progress: a status line on stderr naming the body being decomposed
            (:mod:`planner.progress`); ``None`` shows it only when stderr is a terminal.
        coacd_options: extra keyword arguments for ``coacd.run_coacd`` (e.g.
            ``{"resolution": 1000}``); part of the cache key.
        checked: the mesh is already the output of :func:`validate_solid` (not checked
            again).

    Returns:
        :class:`Decomposition`.

    Raises:
        InvalidMeshError: the mesh is not a valid solid.
        InvalidParameterError: bad ``threshold``, ``seed`` or ``coacd_options``.
        GeometryError: CoACD failed or returned no usable piece for a body.
    """
    start = time.perf_counter()
    threshold = check_threshold(threshold)
    seed = _check_seed(seed)
    options = _check_options(coacd_options)
    solid = mesh if checked else validate_solid(mesh, name=name)
    vertices = np.ascontiguousarray(solid.vertices, dtype="<f8")
    faces = np.ascontiguousarray(solid.faces, dtype="<i8")
    key = _cache_key(vertices, faces, threshold, seed, options)
    directory = Path(cache_dir).expanduser() if cache_dir is not None else default_cache_dir()
    entry = directory / f"{key}{SUFFIX}"

    cached = load_entry(entry, key, name, np.asarray(solid.bounds, dtype=np.float64))
    if cached is not None:
        cached_pieces, meta = cached
        log.debug("%s: decomposition cache hit %s", name, entry)
        return Decomposition(
            pieces=cached_pieces,
            exact=bool(meta["exact"]),
            excess=float(meta["excess"]),
            deficit=float(meta["deficit"]),
            method=str(meta["method"]),
            bodies=int(meta["bodies"]),
            cache_hit=True,
            seconds=time.perf_counter() - start,
            threshold=threshold,
        )

    bodies = split_solid(solid)
    pieces: list[np.ndarray] = []
    approx: list[np.ndarray] = []
    approx_bodies: list[trimesh.Trimesh] = []
    with StatusLine(progress) as line:
        for index, body in enumerate(bodies):
            line.show(f"minkplan: decomposing {name}: body {index + 1} of {len(bodies)}")
            body_label = name if len(bodies) == 1 else f"{name} body {index}"
            hull_points = _hull_points(np.asarray(body.vertices))
            if hull_points is not None and _is_convex(body, hull_points):
                pieces.append(hull_points)
                continue
            parts = _run_coacd(body, threshold, seed, options, body_label)
            pieces.extend(parts)
            approx.extend(parts)
            approx_bodies.append(body)
        exact = not approx
        if exact:
            method, excess, deficit = "convex", 0.0, 0.0
        else:
            line.show(f"minkplan: decomposing {name}: measuring the hulls' excess")
            method = "coacd" if len(approx_bodies) == len(bodies) else "mixed"
            excess, deficit = _measure(solid, approx, approx_bodies, pieces)
    meta = {
        "key": key,
        "exact": exact,
        "excess": excess,
        "deficit": deficit,
        "method": method,
        "bodies": len(bodies),
        "threshold": threshold,
        "seed": seed,
        "compute_seconds": time.perf_counter() - start,
    }
    store_entry(directory, entry, pieces, meta, name)
    seconds = time.perf_counter() - start
    log.info(
        "%s: %d bodies -> %d pieces (%s), excess %.3g, deficit %.3g, %.2f s",
        name, len(bodies), len(pieces), method, excess, deficit, seconds,
    )
    return Decomposition(
        pieces=pieces,
        exact=exact,
        excess=excess,
        deficit=deficit,
        method=method,
        bodies=len(bodies),
        cache_hit=False,
        seconds=seconds,
        threshold=threshold,
    )


# ------------------------------------------------------------------ parameters


def check_threshold(threshold) -> float:
    """A CoACD concavity threshold in ``(0, 1]``, or :class:`InvalidParameterError`."""
    try:
        value = float(threshold)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            f"threshold = {threshold!r}: must be a number in (0, 1]"
        ) from exc
    if not (math.isfinite(value) and 0 < value <= 1):
        raise InvalidParameterError(
            f"threshold = {threshold!r}: CoACD's concavity threshold must be in (0, 1] "
            f"(typical 0.01 .. 0.1)"
        )
    return value


def _check_seed(seed) -> int:
    try:
        return check_seed(seed)
    except ValueError as error:
        raise InvalidParameterError(f"seed = {seed!r}: {error}") from None


_COACD_FORBIDDEN = {"mesh", "threshold", "seed"}


def _check_options(options) -> dict:
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise InvalidParameterError(
            f"coacd_options = {options!r}: must be a dict of coacd.run_coacd arguments"
        )
    bad = _COACD_FORBIDDEN & set(options)
    if bad:
        raise InvalidParameterError(
            f"coacd_options: pass {', '.join(sorted(bad))} as decompose() arguments"
        )
    for key, value in options.items():
        if not isinstance(value, (bool, int, float, str)):
            raise InvalidParameterError(
                f"coacd_options[{key!r}] = {value!r}: must be a bool, number or string"
            )
    return dict(sorted(options.items()))


def _coacd_version() -> str:
    try:
        return importlib.metadata.version("coacd")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


def _cache_key(vertices, faces, threshold, seed, options) -> str:
    h = hashlib.sha256()
    settings = {
        "format": FORMAT_VERSION,
        "coacd": _coacd_version(),
        "threshold": repr(float(threshold)),
        "seed": seed,
        "options": options,
        "convex_volume_rel": repr(tol.convex_volume_rel),
        "excess_samples": tol.excess_samples,
        "sample_seed": tol.sample_seed,
    }
    h.update(json.dumps(settings, sort_keys=True).encode())
    h.update(np.asarray(vertices.shape, dtype="<i8").tobytes())
    h.update(vertices.tobytes())
    h.update(np.asarray(faces.shape, dtype="<i8").tobytes())
    h.update(faces.tobytes())
    return h.hexdigest()


# ------------------------------------------------------------------ geometry


def _hull_points(points: np.ndarray) -> np.ndarray | None:
    """Vertices of the convex hull (in input order), or None for a flat point set."""
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return None
    return np.ascontiguousarray(points[np.sort(hull.vertices)], dtype=np.float64)


def _hull_volume(points: np.ndarray) -> float:
    return float(ConvexHull(points).volume)


def is_convex_body(body: trimesh.Trimesh) -> bool:
    """Whether a body (see :func:`planner.meshes.split_solid`) is convex by the test
    :func:`decompose` uses to keep a body as one exact piece."""
    hull_points = _hull_points(np.asarray(body.vertices))
    return hull_points is not None and _is_convex(body, hull_points)


def _is_convex(body: trimesh.Trimesh, hull_points: np.ndarray) -> bool:
    hull_volume = _hull_volume(hull_points)
    return hull_volume - float(body.volume) <= tol.convex_volume_rel * hull_volume


def _run_coacd(body, threshold, seed, options, label) -> list[np.ndarray]:
    import coacd

    coacd.set_log_level("error")
    started = time.perf_counter()
    try:
        parts = coacd.run_coacd(
            coacd.Mesh(
                np.ascontiguousarray(body.vertices, dtype=np.float64),
                np.ascontiguousarray(body.faces, dtype=np.int32),
            ),
            threshold=threshold,
            seed=seed,
            **options,
        )
    except TypeError as exc:
        raise InvalidParameterError(f"coacd_options: {exc}") from exc
    except Exception as exc:
        raise GeometryError(
            f"{label}: CoACD failed ({type(exc).__name__}: {exc}); try another threshold "
            f"or seed"
        ) from exc
    pieces = []
    dropped = 0
    for part_vertices, _ in parts:
        points = _hull_points(np.asarray(part_vertices, dtype=np.float64))
        if points is None:
            dropped += 1
            continue
        pieces.append(points)
    if not pieces:
        raise GeometryError(
            f"{label}: CoACD returned no solid piece ({len(parts)} flat); try another "
            f"threshold or seed"
        )
    log.info(
        "%s: CoACD (threshold %g, seed %d) gave %d pieces in %.2f s%s",
        label, threshold, seed, len(pieces), time.perf_counter() - started,
        f" ({dropped} flat parts dropped)" if dropped else "",
    )
    return pieces


def _measure(solid, approx, approx_bodies, all_pieces) -> tuple[float, float]:
    """Sampled (excess, deficit) of the CoACD pieces w.r.t. the solid."""
    count = tol.excess_samples
    scale = scale_of(solid)
    slack = tol.merge_rel * scale

    # excess: hull surface samples (and hull vertices) outside the solid, distance to it
    hulls = [trimesh.convex.convex_hull(points) for points in approx]
    samples, _ = trimesh.sample.sample_surface(
        trimesh.util.concatenate(hulls), count, seed=tol.sample_seed
    )
    samples = np.concatenate([samples, *approx])
    outside = ~_inside_solid(solid, samples)
    excess = 0.0
    if outside.any():
        _, distance, _ = trimesh.proximity.closest_point(solid, samples[outside])
        excess = float(distance.max())

    # deficit: solid surface samples outside every hull, distance to the nearest hull
    points, _ = trimesh.sample.sample_surface(
        trimesh.util.concatenate(approx_bodies), count, seed=tol.sample_seed + 1
    )
    # plane excess max_k(n_k.x - d_k): <= 0 inside a hull, a lower bound of the
    # distance outside it
    plane = np.stack(
        [_plane_excess(ConvexHull(piece).equations, points) for piece in all_pieces], axis=1
    )
    uncovered = plane.min(axis=1) > slack
    deficit = 0.0
    if uncovered.any():
        # exact distance to the hull with the smallest lower bound: an upper bound of
        # the distance to the union (and equal to it in all but contrived cases)
        nearest = plane[uncovered].argmin(axis=1)
        lost = points[uncovered]
        for piece_index in np.unique(nearest):
            hull = trimesh.convex.convex_hull(all_pieces[piece_index])
            _, d, _ = trimesh.proximity.closest_point(hull, lost[nearest == piece_index])
            deficit = max(deficit, float(d.max()))
    return excess, deficit


def _plane_excess(equations: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``max_k (n_k . x + d_k)`` over the facets of a qhull hull for each point."""
    return (points @ equations[:, :3].T + equations[:, 3]).max(axis=1)


def _inside_solid(solid, points: np.ndarray) -> np.ndarray:
    """Points inside the solid, by the core's exact winding number (a BVH ray cast per
    point; robust to bodies touching face to face and to cavities; points on the surface
    count as inside)."""
    from ._minkowski_core import winding_numbers as core_windings  # noqa: PLC0415

    vertices = np.ascontiguousarray(solid.vertices, dtype=np.float64)
    faces = np.ascontiguousarray(solid.faces, dtype=np.int64)
    return core_windings(vertices, faces, np.ascontiguousarray(points, dtype=np.float64)) != 0


# ------------------------------------------------------------------ cache
