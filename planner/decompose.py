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
import io
import json
import logging
import math
import os
import stat
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import ConvexHull, QhullError

from .errors import GeometryError, InvalidParameterError
from .meshes import split_solid, validate_solid
from .tolerances import scale_of, tol
from .values import check_seed

__all__ = ["CACHE_ENV", "Decomposition", "check_threshold", "decompose", "default_cache_dir",
           "is_convex_body"]

log = logging.getLogger(__name__)

CACHE_ENV = "MINKPLAN_CACHE_DIR"
"""Environment variable naming the decomposition cache directory."""

_FORMAT_VERSION = 1
_MAGIC = b"MKPDEC01"
_SUFFIX = ".mkdec"
_HEADER = len(_MAGIC) + 32 + 8  # magic, sha256 of payload, payload length


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
    """Cache directory: ``$MINKPLAN_CACHE_DIR`` if set, else
    ``~/.cache/minkplan/decompositions``."""
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "minkplan" / "decompositions"


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
        progress: show a progress bar over bodies on stderr; ``None`` shows it only
            when stderr is a terminal.
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
    entry = directory / f"{key}{_SUFFIX}"

    cached = _load_entry(entry, key, name, np.asarray(solid.bounds, dtype=np.float64))
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
    show = sys.stderr.isatty() if progress is None else bool(progress)
    pieces: list[np.ndarray] = []
    approx: list[np.ndarray] = []
    approx_bodies: list[trimesh.Trimesh] = []
    for index, body in enumerate(_progress(bodies, show, name)):
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
    _store_entry(directory, entry, pieces, meta, name)
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
        "format": _FORMAT_VERSION,
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


def _progress(items, show: bool, name: str):
    if not show or len(items) < 1:
        return items
    from tqdm import tqdm

    return tqdm(items, desc=f"decompose {name}", unit="body", file=sys.stderr, leave=False)


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


def _encode(pieces: list[np.ndarray], meta: dict) -> bytes:
    offsets = np.cumsum([0] + [len(p) for p in pieces]).astype("<i8")
    points = (
        np.concatenate(pieces).astype("<f8")
        if pieces
        else np.zeros((0, 3), dtype="<f8")
    )
    buffer = io.BytesIO()
    np.savez(
        buffer,
        points=points,
        offsets=offsets,
        meta=np.frombuffer(json.dumps(meta, sort_keys=True).encode(), dtype=np.uint8),
    )
    payload = buffer.getvalue()
    digest = hashlib.sha256(payload).digest()
    return _MAGIC + digest + len(payload).to_bytes(8, "little") + payload


class _CorruptEntry(Exception):
    pass


def _decode(data: bytes, key: str):
    if len(data) < _HEADER or not data.startswith(_MAGIC):
        raise _CorruptEntry("bad header")
    digest = data[len(_MAGIC):len(_MAGIC) + 32]
    length = int.from_bytes(data[len(_MAGIC) + 32:_HEADER], "little")
    payload = data[_HEADER:]
    if len(payload) != length:
        raise _CorruptEntry(f"truncated ({len(payload)} of {length} payload bytes)")
    if hashlib.sha256(payload).digest() != digest:
        raise _CorruptEntry("checksum mismatch")
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as archive:
            points = np.array(archive["points"], dtype=np.float64)
            offsets = np.array(archive["offsets"], dtype=np.int64)
            meta = json.loads(bytes(archive["meta"]).decode())
    except Exception as exc:  # a checksummed payload should never fail to parse
        raise _CorruptEntry(f"unreadable payload ({type(exc).__name__})") from exc
    if meta.get("key") != key:
        raise _CorruptEntry("entry belongs to another key")
    if (
        points.ndim != 2
        or points.shape[1] != 3
        or offsets.ndim != 1
        or offsets[0] != 0
        or offsets[-1] != len(points)
        or np.any(np.diff(offsets) < 1)
    ):
        raise _CorruptEntry("inconsistent arrays")
    pieces = [points[a:b].copy() for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    return pieces, meta


MAX_ENTRY_BYTES = 1 << 30
"""The largest cache entry read (1 GiB; a CoACD decomposition takes kilobytes to
megabytes): anything larger is not an entry this code wrote."""


def _read_regular(entry: Path) -> bytes:
    """The bytes of ``entry`` if it is a regular file (not a link, a FIFO or a device)
    of at most :data:`MAX_ENTRY_BYTES`.

    Raises:
        FileNotFoundError: no entry.
        _CorruptEntry: anything else there.
    """
    try:
        fd = os.open(entry, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
                     | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise
    except OSError as exc:  # ELOOP: a symbolic link
        raise _CorruptEntry(f"not a regular file ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise _CorruptEntry("not a regular file")
        if info.st_size > MAX_ENTRY_BYTES:
            raise _CorruptEntry(f"{info.st_size} bytes, over {MAX_ENTRY_BYTES}")
        return handle.read(MAX_ENTRY_BYTES + 1)


def _check_content(pieces: list[np.ndarray], meta: dict, box: np.ndarray) -> None:
    """An entry's pieces must fit the part they claim to decompose: finite points, at
    least four per piece, none outside the part's box grown by the recorded excess.

    Raises:
        _CorruptEntry: they do not.
    """
    try:
        excess = float(meta["excess"])
        for field in ("exact", "deficit", "method", "bodies"):
            meta[field]  # noqa: B018 (present, or the entry is not ours)
    except (KeyError, TypeError, ValueError):
        raise _CorruptEntry("incomplete metadata") from None
    if not math.isfinite(excess) or excess < 0:
        raise _CorruptEntry(f"impossible excess {excess!r}")
    slack = excess + 1e-6 * float(np.linalg.norm(box[1] - box[0]))
    for piece in pieces:
        if len(piece) < 4 or not np.all(np.isfinite(piece)):
            raise _CorruptEntry("a piece with fewer than 4 points or a non-finite point")
        if np.any(piece < box[0] - slack) or np.any(piece > box[1] + slack):
            raise _CorruptEntry("a piece outside the part's box")


def _load_entry(entry: Path, key: str, name: str, box: np.ndarray | None = None):
    try:
        data = _read_regular(entry)
        pieces, meta = _decode(data, key)
        if box is not None:
            _check_content(pieces, meta, box)
        return pieces, meta
    except FileNotFoundError:
        return None
    except OSError as exc:
        log.warning("%s: cannot read decomposition cache entry %s (%s)", name, entry, exc)
        return None
    except _CorruptEntry as exc:
        log.warning(
            "%s: corrupt decomposition cache entry %s (%s); deleting it and recomputing",
            name, entry, exc,
        )
        try:
            entry.unlink()
        except OSError:
            pass
        return None


def _store_entry(directory: Path, entry: Path, pieces, meta, name: str) -> None:
    data = _encode(pieces, meta)
    temp = None
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, temp = tempfile.mkstemp(dir=directory, prefix=f".{entry.stem[:16]}.", suffix=".tmp")
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, entry)
        temp = None
        _fsync_directory(directory)
    except OSError as exc:
        log.warning(
            "%s: cannot write decomposition cache in %s (%s); continuing without cache",
            name, directory, exc,
        )
    finally:
        if temp is not None:
            try:
                os.unlink(temp)
            except OSError:
                pass


def _fsync_directory(directory: Path) -> None:
    if os.name != "posix":
        return
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
