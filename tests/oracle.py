"""Independent references for Minkowski sums and C-obstacles.

Nothing here imports ``planner``: these are the yardsticks the native core is measured
against.  Conventions (DESIGN.md):

* ``A ⊕ B = {a + b}``.  ``p ∈ A ⊕ B  ⟺  ∃ b ∈ B: p − b ∈ A  ⟺  A ∩ (p − B) ≠ ∅`` where
  ``p − B = {p − b}`` is B mirrored through the origin, then translated by p.
* C-obstacle ``CO = O ⊕ (−R) = {t : (R + t) ∩ O ≠ ∅}``.
* Solids, not surfaces: a part wholly inside another collides.

Membership is decided with python-fcl (triangle–triangle tests on BVHs) plus an explicit
containment test, because FCL's mesh–mesh ``collide`` only reports intersecting
triangles and says "no contact" when one solid lies wholly inside the other.  The
containment test is libigl's generalised winding number (solid angles; shares no code
with the native core's ray-cast one); see :func:`winding_numbers`.

Entry points: :func:`points_in_mesh`, :class:`MinkowskiOracle` (batched membership and
exact outside distance), :func:`in_minkowski_sum`, :class:`CollisionOracle`,
:func:`in_c_obstacle`, :func:`boundary_points_by_bisection`, :func:`hausdorff_estimate`,
:func:`exact_convex_sum`, :func:`surface_distance`, :func:`sampled_hausdorff`.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict, defaultdict

import fcl
import igl
import numpy as np
import trimesh
from scipy.spatial import ConvexHull

from planner.meshes.closest import mesh_distance

__all__ = [
    "CollisionOracle",
    "MinkowskiOracle",
    "approx_to_true_distances",
    "assert_component_closed",
    "boundary_points_by_bisection",
    "clear_caches",
    "exact_convex_sum",
    "hausdorff_estimate",
    "in_c_obstacle",
    "in_minkowski_sum",
    "interior_points",
    "lattice_boxes",
    "mirrored",
    "points_in_mesh",
    "sampled_hausdorff",
    "surface_distance",
    "surface_samples",
    "winding_numbers",
]

# --------------------------------------------------------------------------------------
# point in mesh
# --------------------------------------------------------------------------------------

class _PointInMesh:
    """Reusable point-in-closed-mesh classifier (see :func:`winding_numbers`)."""

    def __init__(self, mesh: trimesh.Trimesh):
        self.vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)

    def winding(self, points: np.ndarray) -> np.ndarray:
        points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
        if len(points) == 0:
            return np.zeros(0, dtype=np.int64)
        solid_angles = igl.winding_number(self.vertices, self.faces, points)
        return np.rint(solid_angles).astype(np.int64)

    def contains(self, points: np.ndarray) -> np.ndarray:
        return self.winding(points) != 0


_PIM_CACHE: OrderedDict = OrderedDict()


def _mesh_key(mesh: trimesh.Trimesh) -> str:
    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return h.hexdigest()


def _cached(cache: OrderedDict, key, build, size: int = 16):
    if key in cache:
        cache.move_to_end(key)
        return cache[key]
    value = build()
    cache[key] = value
    while len(cache) > size:
        cache.popitem(last=False)
    return value


def clear_caches() -> None:
    """Drop the cached FCL models and point-in-mesh grids (they can be large for big
    meshes: an FCL BVH takes ~0.5 kB per triangle)."""
    _PIM_CACHE.clear()
    _ORACLE_CACHE.clear()
    _SURFACE_CACHE.clear()


def _pim(mesh: trimesh.Trimesh) -> _PointInMesh:
    return _cached(_PIM_CACHE, _mesh_key(mesh), lambda: _PointInMesh(mesh))


def winding_numbers(mesh: trimesh.Trimesh, points) -> np.ndarray:
    """Winding number of a closed triangle mesh around each of ``(n, 3)`` points.

    libigl's generalised winding number (the direct sum of the triangles' signed solid
    angles / 4π, exact up to rounding; not its approximate ``fast_winding_number``),
    rounded to the nearest integer, which is the winding number for a closed mesh.
    Points on the surface get either answer.  ``(n,)`` int64.
    """
    return _pim(mesh).winding(points)


def points_in_mesh(mesh: trimesh.Trimesh, points) -> np.ndarray:
    """``(n,)`` bool: is each of ``(n, 3)`` points inside the closed mesh (winding ≠ 0)."""
    return _pim(mesh).winding(points) != 0


# --------------------------------------------------------------------------------------
# membership oracles
# --------------------------------------------------------------------------------------

def mirrored(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """−mesh = {−x}: negated vertices, faces flipped so it stays outward oriented."""
    return trimesh.Trimesh(vertices=-np.asarray(mesh.vertices, dtype=np.float64),
                           faces=np.asarray(mesh.faces)[:, ::-1].copy(), process=False)


def _bvh(vertices: np.ndarray, faces: np.ndarray) -> fcl.BVHModel:
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64),
                      np.ascontiguousarray(faces, dtype=np.int32))
    model.endModel()
    return model


def _component_representatives(mesh: trimesh.Trimesh) -> np.ndarray:
    """One vertex of each face-connected component, ``(k, 3)``."""
    labels = trimesh.graph.connected_component_labels(mesh.face_adjacency, len(mesh.faces))
    _, first = np.unique(labels, return_index=True)
    return np.asarray(mesh.vertices)[mesh.faces[first, 0]]


class _PairCollider:
    """Does ``X ∩ (Y + p) ≠ ∅`` (solids) for many translations ``p``?"""

    def __init__(self, x: trimesh.Trimesh, y: trimesh.Trimesh):
        self.x, self.y = x, y
        self._obj_x = fcl.CollisionObject(_bvh(x.vertices, x.faces), fcl.Transform())
        self._obj_y = fcl.CollisionObject(_bvh(y.vertices, y.faces), fcl.Transform())
        self._rep_x = _component_representatives(x)
        self._rep_y = _component_representatives(y)
        self._pim_x = _pim(x)
        self._pim_y = _pim(y)
        # Y + p can only touch X if p lies in this box
        self.lo = x.bounds[0] - y.bounds[1]
        self.hi = x.bounds[1] - y.bounds[0]
        self.n_fcl = 0
        self.n_inside_tests = 0

    def triangles_touch(self, p: np.ndarray) -> bool:
        self._obj_y.setTranslation(p)
        req = fcl.CollisionRequest(num_max_contacts=1, enable_contact=False)
        return fcl.collide(self._obj_x, self._obj_y, req, fcl.CollisionResult()) > 0

    def collides(self, ps: np.ndarray, *, use_inside_test: bool = True) -> np.ndarray:
        ps = np.asarray(ps, dtype=np.float64).reshape(-1, 3)
        out = np.zeros(len(ps), dtype=bool)
        cand = np.flatnonzero(np.all((ps >= self.lo) & (ps <= self.hi), axis=1))
        if cand.size == 0:
            return out
        touch = np.fromiter((self.triangles_touch(ps[i]) for i in cand), dtype=bool,
                            count=cand.size)
        self.n_fcl += cand.size
        out[cand] = touch
        if not use_inside_test:
            return out
        rest = cand[~touch]
        if rest.size == 0:
            return out
        self.n_inside_tests += rest.size
        p = ps[rest]
        # no triangle contact: the solids are disjoint or one holds a whole component
        # of the other; one vertex per component decides which.
        ky, kx = len(self._rep_y), len(self._rep_x)
        y_in_x = self._pim_x.contains((p[:, None, :] + self._rep_y[None]).reshape(-1, 3))
        x_in_y = self._pim_y.contains((self._rep_x[None] - p[:, None, :]).reshape(-1, 3))
        out[rest] = y_in_x.reshape(-1, ky).any(axis=1) | x_in_y.reshape(-1, kx).any(axis=1)
        return out

    def distance(self, ps: np.ndarray) -> np.ndarray:
        """Distance between the surfaces of X and Y + p (equals the distance between the
        solids when they do not overlap)."""
        ps = np.asarray(ps, dtype=np.float64).reshape(-1, 3)
        d = np.zeros(len(ps))
        req = fcl.DistanceRequest(enable_nearest_points=False)
        for i, p in enumerate(ps):
            self._obj_y.setTranslation(p)
            d[i] = fcl.distance(self._obj_x, self._obj_y, req, fcl.DistanceResult())
        return d


class MinkowskiOracle:
    """Membership in, and distance to, ``A ⊕ B`` for closed meshes A and B.

    ``contains(p)``: ``A ∩ (p − B) ≠ ∅`` via FCL on A and −B translated by p, plus the
    containment test FCL lacks.  ``distance_outside(p)`` for p outside the sum is exact:
    ``dist(p, A ⊕ B) = dist(A, p − B)`` (FCL mesh distance).
    """

    def __init__(self, a: trimesh.Trimesh, b: trimesh.Trimesh):
        self.a, self.b = a, b
        self._pair = _PairCollider(a, mirrored(b))
        self.bounds = np.array([a.bounds[0] + b.bounds[0], a.bounds[1] + b.bounds[1]])
        self.diagonal = float(np.linalg.norm(self.bounds[1] - self.bounds[0]))

    @property
    def n_queries(self) -> int:
        return self._pair.n_fcl

    def contains(self, points) -> np.ndarray:
        """``(n,)`` bool for ``(n, 3)`` points (or a single ``(3,)`` point)."""
        return self._pair.collides(points)

    def distance_outside(self, points) -> np.ndarray:
        """Exact distance to ``A ⊕ B`` for points outside it (0 for points inside)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        d = self._pair.distance(points)
        return np.where(self.contains(points), 0.0, np.maximum(d, 0.0))


class CollisionOracle:
    """``R + t`` collides with ``O`` (solids), for many translations t.

    Built on R itself (not −R): an independent path to the C-obstacle convention
    ``CO = O ⊕ (−R)``.
    """

    def __init__(self, obstacle: trimesh.Trimesh, robot: trimesh.Trimesh):
        self._pair = _PairCollider(obstacle, robot)

    def collides(self, ts, *, use_inside_test: bool = True) -> np.ndarray:
        return self._pair.collides(ts, use_inside_test=use_inside_test)


_ORACLE_CACHE: OrderedDict = OrderedDict()


def _oracle(a, b) -> MinkowskiOracle:
    return _cached(_ORACLE_CACHE, ("sum", _mesh_key(a), _mesh_key(b)),
                   lambda: MinkowskiOracle(a, b))


def _squeeze(points, result):
    return bool(result[0]) if np.asarray(points).ndim == 1 else result


def in_minkowski_sum(p, a: trimesh.Trimesh, b: trimesh.Trimesh):
    """Is p in ``A ⊕ B``?  ``p`` is ``(3,)`` (returns bool) or ``(n, 3)`` (returns
    ``(n,)`` bool).  The FCL models are cached per mesh pair."""
    return _squeeze(p, _oracle(a, b).contains(p))


def in_c_obstacle(t, obstacle: trimesh.Trimesh, robot: trimesh.Trimesh):
    """Does the robot translated by t collide with the obstacle (solids)?  Equivalently
    ``t ∈ O ⊕ (−R)``.  ``t`` is ``(3,)`` or ``(n, 3)``."""
    oracle = _cached(_ORACLE_CACHE, ("co", _mesh_key(obstacle), _mesh_key(robot)),
                     lambda: CollisionOracle(obstacle, robot))
    return _squeeze(t, oracle.collides(t))


# --------------------------------------------------------------------------------------
# boundary sampling and Hausdorff estimates
# --------------------------------------------------------------------------------------

def interior_points(mesh: trimesh.Trimesh, n: int, rng: np.random.Generator) -> np.ndarray:
    """``(n, 3)`` uniform random points inside a closed mesh (rejection sampling)."""
    lo, hi = mesh.bounds
    pim = _pim(mesh)
    found = []
    total = 0
    for _ in range(200):
        cand = rng.uniform(lo, hi, size=(max(4 * n, 64), 3))
        keep = cand[pim.contains(cand)]
        found.append(keep)
        total += len(keep)
        if total >= n:
            break
    pts = np.concatenate(found)
    if len(pts) < n:
        raise ValueError("could not sample the interior: is the mesh a closed solid?")
    return pts[:n]


def _unit_vectors(n: int, rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _bisect(contains, lo_pts, hi_pts, lo_state, iterations: int):
    """Batched bisection between ``lo_pts`` (membership ``lo_state``) and ``hi_pts``."""
    lo_pts, hi_pts = lo_pts.copy(), hi_pts.copy()
    for _ in range(iterations):
        mid = 0.5 * (lo_pts + hi_pts)
        same = contains(mid) == lo_state
        lo_pts[same] = mid[same]
        hi_pts[~same] = mid[~same]
    return 0.5 * (lo_pts + hi_pts)


def _ray_crossings(contains, origins, dirs, t_max, samples: int, tol: float):
    """All membership changes along rays ``origin + t dir, t ∈ [0, t_max]`` found at
    ``samples`` steps, each bisected to ``tol``.  Returns ``(points, ray_index)``."""
    ts = np.linspace(0.0, 1.0, samples)[None, :] * t_max[:, None]        # (r, s)
    pts = origins[:, None, :] + ts[..., None] * dirs[:, None, :]
    inside = contains(pts.reshape(-1, 3)).reshape(len(origins), samples)
    ray, step = np.nonzero(inside[:, 1:] != inside[:, :-1])
    if ray.size == 0:
        return np.zeros((0, 3)), ray
    lo = pts[ray, step]
    hi = pts[ray, step + 1]
    width = float(np.max(np.linalg.norm(hi - lo, axis=1)))
    iterations = int(np.ceil(np.log2(max(width / tol, 2.0))))
    return _bisect(contains, lo, hi, inside[ray, step], iterations), ray


def boundary_points_by_bisection(a: trimesh.Trimesh, b: trimesh.Trimesh, n: int = 200,
                                 seed: int = 0, *, tol: float | None = None,
                                 samples_per_ray: int = 96, n_seeds: int = 16,
                                 oracle: MinkowskiOracle | None = None) -> np.ndarray:
    """``(n, 3)`` points on the true boundary of ``A ⊕ B`` (to ``tol``, default 1e-6 of
    the sum's bounding-box diagonal).

    Rays start at ``n_seeds`` interior points of the sum (sums of random interior points
    of A and of B, so non-star-shaped sums are reached from several places) and run in
    random directions out of the sum's bounding box.  Each ray is sampled at
    ``samples_per_ray`` steps; every membership change is bisected, so a ray crossing the
    boundary several times yields several points.  Features thinner than a step can be
    missed (that only weakens the true→approx estimate).
    """
    oracle = oracle or _oracle(a, b)
    rng = np.random.default_rng(seed)
    tol = 1e-6 * oracle.diagonal if tol is None else tol
    seeds = interior_points(a, n_seeds, rng) + interior_points(b, n_seeds, rng)
    lo, hi = oracle.bounds
    pad = 1e-3 * oracle.diagonal
    found: list[np.ndarray] = []
    total = 0
    while total < n:
        rays = max(n - total, 8)
        origins = seeds[rng.integers(len(seeds), size=rays)]
        dirs = _unit_vectors(rays, rng)
        # distance to leave the (padded) bounding box of the sum
        with np.errstate(divide="ignore"):
            t_hi = np.where(dirs > 0, (hi + pad - origins) / dirs,
                            np.where(dirs < 0, (lo - pad - origins) / dirs, np.inf))
        t_max = t_hi.min(axis=1)
        pts, _ = _ray_crossings(oracle.contains, origins, dirs, t_max, samples_per_ray, tol)
        found.append(pts)
        total += len(pts)
    pts = np.concatenate(found)
    return pts[rng.permutation(len(pts))[:n]]


_SURFACE_CACHE: OrderedDict = OrderedDict()


def surface_distance(mesh: trimesh.Trimesh, points) -> np.ndarray:
    """``(n,)`` unsigned distance from ``(n, 3)`` points to the mesh surface (triangles),
    exact up to rounding: FCL distance from a 1e-12-radius sphere to the mesh BVH
    (50x faster than ``trimesh.proximity.closest_point`` on big meshes), and where that
    says the point is on the mesh, :func:`planner.meshes.closest.mesh_distance`."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)

    def build():
        return fcl.CollisionObject(_bvh(mesh.vertices, mesh.faces), fcl.Transform())

    obj = _cached(_SURFACE_CACHE, _mesh_key(mesh), build, size=8)
    probe = fcl.CollisionObject(fcl.Sphere(1e-12), fcl.Transform())
    req = fcl.DistanceRequest(enable_nearest_points=False)
    out = np.zeros(len(points))
    for i, p in enumerate(points):
        probe.setTranslation(p)
        out[i] = fcl.distance(obj, probe, req, fcl.DistanceResult())
    out = np.maximum(out, 0.0)   # FCL reports -1 for touching
    # FCL now and then reports about 0 (4e-320 on IndustReal's gear) for a point well
    # off the mesh: where its own nearest point is not the point, measured again exactly
    scale = float(np.ptp(np.asarray(mesh.vertices), axis=0).max())
    again = np.flatnonzero(out <= 1e-9 * scale)
    near = fcl.DistanceRequest(enable_nearest_points=True)
    wrong = []
    for i in again:
        probe.setTranslation(points[i])
        result = fcl.DistanceResult()
        fcl.distance(obj, probe, near, result)
        if np.linalg.norm(np.asarray(result.nearest_points[0]) - points[i]) > 1e-9 * scale:
            wrong.append(i)
    if wrong:
        out[wrong] = mesh_distance(mesh.vertices, mesh.faces, points[wrong])
    return out


def surface_samples(mesh: trimesh.Trimesh, n: int, seed: int = 0) -> np.ndarray:
    """``n`` area-weighted random points of a mesh's surface plus its vertices and edge
    midpoints (the corners and creases, where approximations stray; at most ``n`` of
    each, a random subset for big meshes), ``(k, 3)``."""
    rng = np.random.default_rng(seed)
    pts, _ = trimesh.sample.sample_surface(mesh, n, seed=seed)
    verts = np.asarray(mesh.vertices)
    if len(verts) > n:
        verts = verts[rng.choice(len(verts), n, replace=False)]
    faces = np.asarray(mesh.faces)
    if len(faces) > n:
        faces = faces[rng.choice(len(faces), n, replace=False)]
    corners = np.asarray(mesh.vertices)[faces]
    mids = 0.5 * (corners + np.roll(corners, 1, axis=1))
    return np.concatenate([verts, mids.reshape(-1, 3)[:n], pts])


def sampled_hausdorff(x: trimesh.Trimesh, y: trimesh.Trimesh, n: int = 20000,
                      seed: int = 0) -> tuple[float, float]:
    """One-sided surface distances ``(max_x dist(·, ∂y), max_y dist(·, ∂x))`` over dense
    samples (:func:`surface_samples`) of each surface: lower estimates of the two
    one-sided Hausdorff distances, exact up to the sampling."""
    dxy = surface_distance(y, surface_samples(x, n, seed)).max()
    dyx = surface_distance(x, surface_samples(y, n, seed + 1)).max()
    return float(dxy), float(dyx)


def _fan(normals: np.ndarray, angles_deg=(0.0, 20.0, 40.0), per_ring: int = 8):
    """Directions around each normal: ``(n, k, 3)``."""
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    helper = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(n, u)
    dirs = []
    for ang in np.radians(angles_deg):
        k = 1 if ang == 0 else per_ring
        for phi in 2 * np.pi * np.arange(k) / k:
            dirs.append(np.cos(ang) * n + np.sin(ang) * (np.cos(phi) * u + np.sin(phi) * v))
    return np.stack(dirs, axis=1)


def _first_exit(contains, starts, dirs, max_dist, steps: int, tol: float,
                geometric: bool = True):
    """Distance along each ray from an inside start to the first outside sample, bisected
    to ``tol``; ``inf`` where none within ``max_dist`` (scalar or per ray).  Samples are
    geometric (fine near the start) or evenly spaced."""
    max_dist = np.broadcast_to(np.asarray(max_dist, dtype=np.float64), (len(starts),))
    if geometric:
        frac = 2.0 ** -np.arange(steps - 1, -1, -1.0)
    else:
        frac = np.arange(1, steps + 1) / steps
    d = max_dist[:, None] * frac[None, :]                                  # (n, steps)
    pts = starts[:, None, :] + d[..., None] * dirs[:, None, :]
    inside = contains(pts.reshape(-1, 3)).reshape(len(starts), steps)
    outside = ~inside
    has = outside.any(axis=1)
    first = np.argmax(outside, axis=1)
    dist = np.full(len(starts), np.inf)
    idx = np.flatnonzero(has)
    if idx.size:
        f = first[idx]
        d_lo = np.where(f > 0, d[idx, np.maximum(f - 1, 0)], 0.0)
        d_hi = d[idx, f]
        lo = starts[idx] + d_lo[:, None] * dirs[idx]
        hi = starts[idx] + d_hi[:, None] * dirs[idx]
        iterations = int(np.ceil(np.log2(max(float(np.max(d_hi - d_lo)) / tol, 2.0))))
        mid = _bisect(contains, lo, hi, np.ones(idx.size, dtype=bool), iterations)
        dist[idx] = np.linalg.norm(mid - starts[idx], axis=1)
    return dist


def approx_to_true_distances(approx: trimesh.Trimesh, points, normals,
                             oracle: MinkowskiOracle, *, max_dist: float | None = None,
                             tol: float | None = None) -> np.ndarray:
    """Distance from each point to the true boundary of the sum.

    Outside the sum: exact (FCL distance).  Inside: the shortest way out found along the
    surface normal, its opposite, and, for the points that matter for the maximum, a fan
    of directions out to 45° around the normal, bisected: an upper bound, within a few
    percent for a locally flat boundary.  ``inf`` where no way out within ``max_dist``
    (default a quarter of the sum's diagonal).
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    max_dist = 0.25 * oracle.diagonal if max_dist is None else max_dist
    tol = 1e-6 * oracle.diagonal if tol is None else tol
    inside = oracle.contains(points)
    dist = np.zeros(len(points))
    out_idx = np.flatnonzero(~inside)
    if out_idx.size:
        dist[out_idx] = np.maximum(oracle._pair.distance(points[out_idx]), 0.0)
    in_idx = np.flatnonzero(inside)
    if in_idx.size:
        p, nrm = points[in_idx], normals[in_idx]
        # cheap pass: along +normal and −normal
        d_in = np.minimum(_first_exit(oracle.contains, p, nrm, max_dist, 24, tol),
                          _first_exit(oracle.contains, p, -nrm, max_dist, 24, tol))
        # the ones that can set the maximum: shave off the obliquity with a fan of
        # directions, searching no farther than the way out already found
        finite = d_in[np.isfinite(d_in)]
        cut = max(0.5 * float(finite.max()), 1e-4 * oracle.diagonal) if finite.size else 0.0
        big = np.flatnonzero(np.isfinite(d_in) & (d_in >= cut))
        if big.size:
            fan = np.concatenate([_fan(nrm[big], (15.0, 30.0, 45.0), 8),
                                  _fan(-nrm[big], (15.0, 30.0), 6)], axis=1)   # (m, k, 3)
            k = fan.shape[1]
            starts = np.repeat(p[big], k, axis=0)
            reach = np.repeat(d_in[big], k)
            d_fan = _first_exit(oracle.contains, starts, fan.reshape(-1, 3), reach, 8, tol,
                                geometric=False).reshape(-1, k)
            d_in[big] = np.minimum(d_in[big], d_fan.min(axis=1))
        dist[in_idx] = d_in
    return dist


def hausdorff_estimate(approx_mesh: trimesh.Trimesh, a: trimesh.Trimesh, b: trimesh.Trimesh,
                       n: int = 200, seed: int = 0, *, max_dist: float | None = None
                       ) -> tuple[float, float]:
    """Estimate the two one-sided Hausdorff distances between ``approx_mesh`` and the
    boundary of ``A ⊕ B``: ``(d_true_to_approx, d_approx_to_true)``.

    true→approx: ``n`` bisected true boundary points, exact distance to the approx
    surface (a lower estimate: it only sees the sampled points).  approx→true: ``n``
    points sampled on the approx surface, distance to the true boundary by
    :func:`approx_to_true_distances` (exact outside the sum, a slight over-estimate
    inside).  ``inf`` means no true boundary within ``max_dist`` (default a quarter of
    the sum's diagonal) of some approx point inside the sum.
    """
    oracle = _oracle(a, b)
    truth = boundary_points_by_bisection(a, b, n, seed, oracle=oracle)
    d_true_to_approx = float(surface_distance(approx_mesh, truth).max())
    pts, face = trimesh.sample.sample_surface(approx_mesh, n, seed=seed)
    normals = approx_mesh.face_normals[face]
    d = approx_to_true_distances(approx_mesh, pts, normals, oracle, max_dist=max_dist)
    return d_true_to_approx, float(d.max())


# --------------------------------------------------------------------------------------
# exact convex reference
# --------------------------------------------------------------------------------------

def _hull_vertices(points: np.ndarray) -> np.ndarray:
    points = np.asarray(points, dtype=np.float64)
    return points[ConvexHull(points).vertices]


def exact_convex_sum(a: trimesh.Trimesh, b: trimesh.Trimesh) -> trimesh.Trimesh:
    """``A ⊕ B`` for convex A and B: the hull of all pairwise vertex sums (exact).  For
    non-convex inputs this is ``conv(A) ⊕ conv(B)``, a superset."""
    va = _hull_vertices(a.vertices)
    vb = _hull_vertices(b.vertices)
    sums = (va[:, None, :] + vb[None, :, :]).reshape(-1, 3)
    hull = trimesh.convex.convex_hull(sums)
    hull.fix_normals()
    return hull


# ---- no-path certificates ---------------------------------------------------------------

def lattice_boxes(boxes, origin, floor) -> np.ndarray:
    """Octree cell boxes ``(n, 2, 3)`` as integers on the lattice of spacing ``floor`` from
    ``origin`` (asserting they lie on it), for exact arithmetic on cell faces."""
    b = (np.asarray(boxes, dtype=np.float64) - origin) / floor
    r = np.rint(b)
    assert np.allclose(b, r, atol=1e-6), "cells lie on the lattice"
    return r.astype(np.int64)


def assert_component_closed(cert, origin) -> None:
    """The walled-off component of a no-path certificate is closed: every face of every
    component cell is covered, in exact integer lattice arithmetic, by component cells
    and wall cells."""
    floor = cert["floor"]
    comp = lattice_boxes(cert["component"]["boxes"], origin, floor)
    walls = lattice_boxes([w["box"] for w in cert["walls"]], origin, floor)
    allb = np.vstack([comp, walls])
    by_plane = defaultdict(list)  # (axis, side, plane coordinate) -> boxes
    for k, b in enumerate(allb):
        for axis in range(3):
            by_plane[(axis, 0, b[0, axis])].append(k)
            by_plane[(axis, 1, b[1, axis])].append(k)
    by_plane = {key: allb[np.array(v)] for key, v in by_plane.items()}
    for c in comp:
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            area = (c[1, u] - c[0, u]) * (c[1, v] - c[0, v])
            # the cells across the upper face start at c[1, axis]; across the lower face
            # they end at c[0, axis]
            for other in (by_plane.get((axis, 0, c[1, axis])),
                          by_plane.get((axis, 1, c[0, axis]))):
                assert other is not None, "a component face at the root boundary"
                du = np.minimum(other[:, 1, u], c[1, u]) - np.maximum(other[:, 0, u], c[0, u])
                dv = np.minimum(other[:, 1, v], c[1, v]) - np.maximum(other[:, 0, v], c[0, v])
                assert (np.clip(du, 0, None) * np.clip(dv, 0, None)).sum() == area
