"""Independent collision, clearance and path checks with FCL on the original meshes.

Entry points:

- :class:`FclChecker` -- ``collides(t)``, ``is_valid(t)``, ``distance(t)``,
  ``clearance(t)``, ``colliding_obstacle(t)``, ``check_segment(a, b)``,
  ``check_path(waypoints)``, ``check_motion(a, b)``. It is both a
  :class:`~planner.roles.StateValidityChecker` and a
  :class:`~planner.roles.MotionValidator`.
- :class:`~planner.validation.checks.SegmentCheck`, :class:`~planner.validation.checks.PathCheck`
  -- results; :class:`~planner.validation.checks.CheckerTolerances` (in :mod:`.checks`).

The robot ``R`` is a closed triangle mesh in its own frame, with a fixed orientation; at
translation ``t`` it occupies ``R + t``. Obstacles ``O_k`` are meshes already posed in the
world. Parts are *solids* by default: touching counts as contact, and so does one part
lying wholly inside the other (python-fcl's mesh-mesh query tests triangles only and
misses that case; this module adds a winding-number containment test, by solid angles:
:func:`planner.meshes.winding_numbers`, which shares no code with the native core). A
part marked as a *surface* collides only where triangles meet, as FCL sees every mesh.

Contact tolerance ``delta >= 0`` (one definition, shared with the planner): let
``pd(t)`` be the translational penetration depth, the length of the shortest translation
``u`` after which the interiors of ``R + t + u`` and the obstacles are disjoint, which is
also the distance from ``t`` to the closure of the free configuration space. Then::

    t is valid  <=>  pd(t) <= delta

On the Minkowski side this is membership in the C-obstacle eroded by ``delta``:
``t`` is invalid iff ``t in CO (-) B(delta)``, i.e. the signed distance of ``t`` to the
C-obstacle boundary, taken negative inside, is ``< -delta``. With ``delta = 0`` a
configuration is valid iff FCL reports no contact and no containment (touching is
contact); this case is exact.

FCL cannot compute ``pd`` for meshes (``enable_signed_distance`` returns ``0`` for
intersecting BVH meshes and the *positive* surface distance for nested ones), so for
``delta > 0`` the checker certifies validity with a *witness*: a translation ``u``, tried
along the checker's escape hints (a penetration depth's direction, given by the caller),
then the escape directions of FCL's contact normals and the six axis directions, with
lengths ``delta * CheckerTolerances.witness_fractions``, such that ``R + t + u`` is free
with FCL clearance ``d_u``; then ``pd(t) <= |u| - d_u``. The FCL side is therefore
conservative: it never accepts a ``t`` with ``pd(t) > delta``, and it may reject a ``t``
with ``pd(t) <= delta`` whose only escape directions were not tried (for instance a part
that fits its hole exactly, with zero clearance on opposite sides). Along a motion
(:meth:`FclChecker.check_segment`) the last tolerated pose's witness is tried first at
the next: any witness certifies, so a motion may accept a pose whose own directions
would not have freed it, never one deeper than ``delta``.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Sequence
from dataclasses import dataclass

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike

from planner.errors import InvalidParameterError
from planner.meshes import winding_numbers
from planner.tolerances import scale_of

from .checks import CheckerTolerances, PathCheck, SegmentCheck

__all__ = [
    "CheckerTolerances",
    "FclChecker",
    "PathCheck",
    "SegmentCheck",
]


def bvh_model(vertices: np.ndarray, faces: np.ndarray) -> fcl.BVHModel:
    """FCL's BVH of the triangles ``faces`` of ``vertices`` (a surface to FCL)."""
    bvh = fcl.BVHModel()
    bvh.beginModel(len(vertices), len(faces))
    bvh.addSubModel(np.ascontiguousarray(vertices, dtype=np.float64),
                    np.ascontiguousarray(faces, dtype=np.int32))
    bvh.endModel()
    return bvh


class _Part:
    """One mesh prepared for FCL and containment queries (containment only in a solid)."""

    def __init__(self, mesh: trimesh.Trimesh, name: str, solid: bool = True) -> None:
        self.solid = bool(solid)
        vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
        faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
        if len(faces) == 0:
            raise InvalidParameterError(f"mesh {name!r}: has no triangles")
        if not np.all(np.isfinite(vertices)):
            raise InvalidParameterError(f"mesh {name!r}: vertices are not finite")
        self.name = name
        self.vertices = vertices
        self.faces = faces
        self.lo = vertices[faces].reshape(-1, 3).min(axis=0)
        self.hi = vertices[faces].reshape(-1, 3).max(axis=0)
        bvh = bvh_model(vertices, faces)
        self.bvh = bvh
        self.obj = fcl.CollisionObject(bvh, fcl.Transform())
        # One vertex per connected surface component: when no triangles touch, each
        # component lies wholly inside or wholly outside the other solid.
        labels = trimesh.graph.connected_component_labels(
            mesh.face_adjacency, node_count=len(faces)
        )
        _, first_face = np.unique(labels, return_index=True)
        self.representatives = vertices[faces[first_face, 0]]


@dataclass(frozen=True)
class Witness:
    """A translation ``length * direction`` that frees a tolerated pose, and the bound of
    its penetration depth it certifies (``length`` minus the clearance there)."""

    bound: float
    direction: np.ndarray
    length: float


def _aabb_gap(lo_a: np.ndarray, hi_a: np.ndarray, lo_b: np.ndarray, hi_b: np.ndarray) -> float:
    """Euclidean gap between two closed boxes (0 when they touch or overlap)."""
    gap = np.maximum(0.0, np.maximum(lo_a - hi_b, lo_b - hi_a))
    return float(np.linalg.norm(gap))


def _as_translation(t: ArrayLike, what: str = "t") -> np.ndarray:
    arr = np.asarray(t, dtype=np.float64).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidParameterError(f"{what}: expected 3 finite numbers, got {t!r}")
    return arr


class FclChecker:
    """Collision, clearance and motion checks of a translating robot with FCL.

    Args:
        robot: closed triangle mesh in its own frame (its orientation is fixed).
        obstacles: closed triangle meshes posed in the world.
        contact_tolerance: ``delta >= 0`` in scene units; valid iff the translational
            penetration depth is ``<= delta`` (see the module docstring). ``0`` is exact.
        names: one name per obstacle (default: ``mesh.metadata["name"]`` or
            ``"obstacle_<i>"``).
        tolerances: numerical settings, :class:`CheckerTolerances`.
        solid: per obstacle, whether it is a solid (default: all); a surface collides
            only where triangles meet (FCL's own meaning), containment in it does not
            count.
        robot_solid: whether the robot is a solid.
        escape_hints: directions tried first as witnesses of a tolerated overlap (a
            penetration depth's, which frees the robot where no contact normal or axis
            does: a peg pushed sideways into its bore, its shoulder flush on the block).

    Attributes:
        n_valid, n_invalid: :meth:`is_valid` answers so far.
        n_valid_motions, n_invalid_motions: :meth:`check_motion` answers so far.
        n_queries: FCL configuration queries so far (all methods).
        scale: length scale of the scene (bounding-box diagonal).

    Thread safety: not thread-safe. The robot's FCL object is moved for every query and
    the counters are unguarded; use one instance per thread.
    """

    def __init__(
        self,
        robot: trimesh.Trimesh,
        obstacles: Sequence[trimesh.Trimesh],
        *,
        contact_tolerance: float = 0.0,
        names: Sequence[str] | None = None,
        tolerances: CheckerTolerances | None = None,
        solid: Sequence[bool] | None = None,
        robot_solid: bool = True,
        escape_hints: Sequence[ArrayLike] = (),
    ) -> None:
        delta = float(contact_tolerance)
        if not (math.isfinite(delta) and delta >= 0.0):
            raise InvalidParameterError(
                f"contact_tolerance = {contact_tolerance!r}: must be a finite number >= 0"
            )
        obstacles = list(obstacles)
        if names is None:
            names = [
                str(getattr(m, "metadata", {}).get("name") or f"obstacle_{i}")
                for i, m in enumerate(obstacles)
            ]
        names = [str(n) for n in names]
        if len(names) != len(obstacles):
            raise InvalidParameterError(
                f"names: {len(names)} names for {len(obstacles)} obstacles"
            )
        self.contact_tolerance = delta
        self.tolerances = tolerances or CheckerTolerances()
        solid = [True] * len(obstacles) if solid is None else [bool(x) for x in solid]
        if len(solid) != len(obstacles):
            raise InvalidParameterError(
                f"solid: {len(solid)} flags for {len(obstacles)} obstacles"
            )
        self.escape_hints = _unit_hints(escape_hints)
        self.robot = _Part(robot, "robot", robot_solid)
        self.obstacles = [_Part(m, n, k) for m, n, k in zip(obstacles, names, solid)]
        self.names = tuple(names)
        corners = [self.robot.lo, self.robot.hi]
        for part in self.obstacles:
            corners += [part.lo, part.hi]
        self.scale = max(scale_of(np.array(corners)), 1e-300)
        self.floor = self.tolerances.contact_floor_rel * self.scale
        self._origin = np.zeros(3)
        self.n_valid = 0
        self.n_invalid = 0
        self.n_valid_motions = 0
        self.n_invalid_motions = 0
        self.n_queries = 0

    @classmethod
    def for_parts(cls, robot, obstacles, *, contact_tolerance: float = 0.0) -> FclChecker:
        """The checker for problem parts (:class:`planner.problem.Part`): their meshes,
        names and solid flags."""
        obstacles = list(obstacles)
        return cls(robot.mesh, [p.mesh for p in obstacles], contact_tolerance=contact_tolerance,
                   names=[p.name for p in obstacles], solid=[p.solid for p in obstacles],
                   robot_solid=robot.solid, escape_hints=getattr(robot, "escape_hints", ()))

    # ------------------------------------------------------------------ primitives

    def _place(self, t: np.ndarray) -> None:
        if not np.array_equal(t, self._origin):
            self.robot.obj.setTranslation(t)
            self._origin = t.copy()

    def _contained(self, part: _Part, t: np.ndarray) -> bool:
        """Containment either way, assuming no triangle of R + t touches ``part``."""
        r = self.robot
        lo, hi = r.lo + t, r.hi + t
        if part.solid and np.all(lo >= part.lo) and np.all(hi <= part.hi):
            reps = r.representatives + t
            if np.any(winding_numbers(reps, part.vertices[part.faces]) > 0.5):
                return True
        if r.solid and np.all(part.lo >= lo) and np.all(part.hi <= hi):
            reps = part.representatives - t
            if np.any(winding_numbers(reps, r.vertices[r.faces]) > 0.5):
                return True
        return False

    def _touches(self, part: _Part, t: np.ndarray, contacts: bool = False):
        """FCL triangle contact (touching included); returns (bool, CollisionResult)."""
        self._place(t)
        if contacts:
            request = fcl.CollisionRequest(
                num_max_contacts=self.tolerances.max_contacts, enable_contact=True
            )
        else:
            request = fcl.CollisionRequest()
        result = fcl.CollisionResult()
        hit = fcl.collide(self.robot.obj, part.obj, request, result) > 0
        return hit, result

    def _collides_with(self, part: _Part, t: np.ndarray) -> bool:
        if _aabb_gap(self.robot.lo + t, self.robot.hi + t, part.lo, part.hi) > 0.0:
            return False
        hit, _ = self._touches(part, t)
        return hit or self._contained(part, t)

    def _surface_distance(self, part: _Part, t: np.ndarray) -> float:
        self._place(t)
        return float(
            fcl.distance(self.robot.obj, part.obj, fcl.DistanceRequest(), fcl.DistanceResult())
        )

    def _free_distance(self, t: np.ndarray) -> float | None:
        """Clearance at ``t`` if R + t is free (no contact, no containment), else None."""
        self.n_queries += 1
        robot_lo, robot_hi = self.robot.lo + t, self.robot.hi + t
        gaps = [_aabb_gap(robot_lo, robot_hi, p.lo, p.hi) for p in self.obstacles]
        best = math.inf
        for i in np.argsort(gaps, kind="stable"):
            if gaps[i] >= best:
                break
            part = self.obstacles[i]
            if gaps[i] == 0.0 and self._collides_with(part, t):
                return None
            d = self._surface_distance(part, t)
            best = min(best, max(d, 0.0))
        return best

    # ------------------------------------------------------------------ state queries

    def collides(self, t: ArrayLike) -> bool:
        """``True`` when ``R + t`` touches, intersects, contains or lies inside an
        obstacle (contact tolerance not applied)."""
        p = _as_translation(t)
        self.n_queries += 1
        return any(self._collides_with(part, p) for part in self.obstacles)

    def distance(self, t: ArrayLike) -> float:
        """Minimum distance from ``R + t`` to the obstacles; ``0.0`` in contact or
        collision (FCL gives no penetration depth for meshes, see
        :meth:`colliding_obstacle` for an estimate); ``inf`` without obstacles."""
        d = self._free_distance(_as_translation(t))
        return 0.0 if d is None else d

    def clearance(self, t: ArrayLike) -> float:
        """Same as :meth:`distance` (OMPL's ``StateValidityChecker::clearance``)."""
        return self.distance(t)

    def penetration_bound(self, t: ArrayLike) -> float | None:
        """Certified upper bound of the penetration depth ``pd(t)`` from a witness
        translation of length ``<= contact_tolerance`` (``0.0`` when free); ``None``
        when no witness was found (always ``None`` in collision with ``delta = 0``)."""
        p = _as_translation(t)
        if self._free_distance(p) is not None:
            return 0.0
        return self._witness(p)

    def _witness(self, t: np.ndarray, delta: float | None = None,
                 directions: list[np.ndarray] | None = None) -> float | None:
        """The witness bound of ``pd(t)`` under tolerance ``delta`` (default the
        checker's), or ``None`` when no witness of length ``<= delta`` was found."""
        found = self._witness_found(t, delta, directions)
        return None if found is None else found.bound

    def _witness_found(self, t: np.ndarray, delta: float | None = None,
                       directions: list[np.ndarray] | None = None,
                       first: Witness | None = None) -> Witness | None:
        """The shortest witness of ``pd(t)`` found under tolerance ``delta`` (the
        checker's by default): every length of the ladder, shortest first, along every
        escape direction; ``None`` when none of length ``<= delta`` frees ``t``. With
        ``first`` (the witness of a pose just before, on a straight motion), its direction
        at its length is tried before that search, and when it frees ``t``, shorter
        lengths along it only (:meth:`_along`): a witness frees ``t`` whatever found it,
        and on a motion through a tolerated overlap the last one nearly always does (a
        cap pushed 1 mm into its bottle, lifted out under a 1.02 mm tolerance: each pose
        spent 360 FCL queries on the lengths shorter than the overlap)."""
        delta = self.contact_tolerance if delta is None else delta
        if delta <= 0.0:
            return None
        lengths = self._witness_lengths(delta)
        if first is not None and first.length <= delta:
            found = self._along(t, first.direction, first.length, lengths)
            if found is not None:
                return found
        unique = self._witness_directions(t) if directions is None else directions
        for length in lengths:
            for direction in unique:
                d_u = self._free_distance(t + length * direction)
                if d_u is not None:  # the first (shortest) witness found
                    return Witness(max(0.0, length - d_u), direction, length)
        return None

    def _along(self, t: np.ndarray, direction: np.ndarray, length: float,
               lengths: list[float]) -> Witness | None:
        """The witness ``t + length * direction`` if it frees ``t``, made shorter down
        the ladder ``lengths`` while each shorter one frees it too; else ``None``."""
        d_u = self._free_distance(t + length * direction)
        if d_u is None:
            return None
        best = Witness(max(0.0, length - d_u), direction, length)
        for shorter in reversed([x for x in lengths if x < length]):
            d_u = self._free_distance(t + shorter * direction)
            if d_u is None:
                break
            best = Witness(max(0.0, shorter - d_u), direction, shorter)
        return best

    def _witness_lengths(self, delta: float) -> list[float]:
        """The witness lengths tried under tolerance ``delta``, shortest first: ``delta``
        times the checker's fractions, and the lengths of a fixed ladder of
        :attr:`~CheckerTolerances.witness_ladder_steps` per doubling between the smallest
        fraction and ``delta``. The ladder does not move with ``delta``, so a larger
        tolerance tries the lengths a smaller one did (down to its smallest fraction):
        a pose whose free window is narrow (a nut free only near whole thread turns)
        accepted under one tolerance is not rejected under a larger one."""
        fractions = self.tolerances.witness_fractions
        lengths = {f * delta for f in fractions}
        steps = self.tolerances.witness_ladder_steps
        if steps > 0:
            low = min(fractions) * delta
            first, last = (math.ceil(steps * math.log2(low)),
                           math.floor(steps * math.log2(delta)))
            lengths.update(2.0 ** (k / steps) for k in range(first, last + 1))
        return sorted(lengths)

    def _witness_directions(self, t: np.ndarray) -> list[np.ndarray]:
        """The distinct escape directions at ``t``: the checker's hints, then those from
        every obstacle near the robot."""
        unique: list[np.ndarray] = list(self.escape_hints)
        for part in self.obstacles:
            if _aabb_gap(self.robot.lo + t, self.robot.hi + t, part.lo, part.hi) > 0.0:
                continue
            for d in self._escape_directions(part, t):
                if not any(float(np.dot(d, u)) > 1.0 - 1e-9 for u in unique):
                    unique.append(d)
        return unique

    def tolerance_accepting(self, t: ArrayLike, *, upto: float, steps: int = 100,
                            bisections: int = 12) -> float | None:
        """The smallest contact tolerance found (``<= upto``) under which this checker
        would accept ``t``: the shortest free translation along the escape directions,
        scanned in ``steps`` equal steps up to ``upto`` (a free window may be narrow: a
        nut on its thread is free only near whole turns) and bisected at the first free
        step. A witness of that length is then tried, so a checker with the tolerance
        returned accepts ``t``. ``None`` when no scanned translation frees it. A search,
        not the penetration depth: it is the tolerance to suggest for a rejected pose,
        meaningful for surfaces too, which have no penetration depth."""
        p = _as_translation(t)
        if self._free_distance(p) is not None:
            return 0.0
        best: float | None = None
        for direction in self._witness_directions(p):
            free = self._first_free(p, direction, upto if best is None else best, steps,
                                    bisections)
            if free is not None and (best is None or free < best):
                best = free
        return best

    def _first_free(self, t: np.ndarray, direction: np.ndarray, upto: float, steps: int,
                    bisections: int) -> float | None:
        """The shortest free length along ``direction`` from ``t`` (scanned, then
        bisected), ``None`` when none up to ``upto``."""
        step = upto / steps
        lo = 0.0
        for k in range(1, steps + 1):
            hi = k * step
            if self._free_distance(t + hi * direction) is not None:
                for _ in range(bisections):
                    mid = 0.5 * (lo + hi)
                    if self._free_distance(t + mid * direction) is None:
                        lo = mid
                    else:
                        hi = mid
                return hi
            lo = hi
        return None

    def accepts_with(self, t: ArrayLike, tolerance: float) -> bool:
        """Whether a checker with contact tolerance ``tolerance`` would accept ``t``
        (:meth:`is_valid` there; not counted here)."""
        p = _as_translation(t)
        return self._free_distance(p) is not None or self._witness(p, tolerance) is not None

    def is_valid(self, t: ArrayLike) -> bool:
        """``True`` iff ``R + t`` is valid under the contact tolerance (exact for
        ``delta = 0``; for ``delta > 0`` certified by a witness, see the module
        docstring). Counts into :attr:`n_valid` / :attr:`n_invalid`."""
        p = _as_translation(t)
        self.n_queries += 1
        free = not any(self._collides_with(part, p) for part in self.obstacles)
        ok = free or self._witness(p) is not None
        if ok:
            self.n_valid += 1
        else:
            self.n_invalid += 1
        return ok

    def escape_directions(self, t: ArrayLike, obstacle: int = 0) -> list[np.ndarray]:
        """Unit directions that may lead the robot at ``t`` out of contact with obstacle
        number ``obstacle``: FCL's contact normals reversed, then the six axes."""
        return self._escape_directions(self.obstacles[obstacle], _as_translation(t))

    def _escape_directions(self, part: _Part, t: np.ndarray) -> list[np.ndarray]:
        """Unit escape directions: FCL contact normals reversed, then the six axes."""
        directions: list[np.ndarray] = []
        hit, result = self._touches(part, t, contacts=True)
        if hit:
            for contact in result.contacts:
                n = np.asarray(contact.normal, dtype=np.float64)
                norm = np.linalg.norm(n)
                if norm > 0 and np.isfinite(norm):
                    # FCL's normal points from the robot (o1) to the obstacle (o2).
                    directions.append(-n / norm)
        directions += [s * e for e in np.eye(3) for s in (1.0, -1.0)]
        unique: list[np.ndarray] = []
        for d in directions:
            if not any(float(np.dot(d, u)) > 1.0 - 1e-9 for u in unique):
                unique.append(d)
        return unique

    def _depth_bound(self, part: _Part, t: np.ndarray) -> float:
        """Upper bound of the penetration depth of R + t into ``part`` alone: the
        shortest free translation found along the escape directions (doubling, then
        bisection), minus the clearance reached there."""
        best = math.inf
        first = 1e-6 * self.scale
        for direction in self._escape_directions(part, t):
            lo, s = 0.0, first
            while s <= 4.0 * self.scale and self._collides_with(part, t + s * direction):
                lo, s = s, 2.0 * s
            if s > 4.0 * self.scale:
                continue
            hi = s
            best = min(best, hi - self._surface_distance(part, t + hi * direction))
            for _ in range(30):
                if hi - lo <= self.floor or best <= self.floor:
                    break
                mid = 0.5 * (lo + hi)
                if self._collides_with(part, t + mid * direction):
                    lo = mid
                else:
                    hi = mid
                    best = min(best, hi - self._surface_distance(part, t + hi * direction))
            if best <= self.floor:
                break
        return max(0.0, best)

    def colliding_obstacle(self, t: ArrayLike) -> tuple[str, float] | None:
        """The obstacle ``R + t`` collides with most deeply, with a depth estimate.

        Returns:
            ``None`` when free, else ``(name, depth)``. ``depth`` is an upper bound of
            the translational penetration depth into that obstacle alone: the shortest
            translation found, along FCL's contact normals and the six axes, that frees
            the robot from it (exact for boxes; ``0.0`` when only touching; ``inf`` if
            none of those directions frees it). FCL's own per-contact
            ``penetration_depth`` is not used: for meshes it is a triangle-pair measure
            (e.g. ``1.0`` for two unit cubes merely touching face to face).
        """
        p = _as_translation(t)
        self.n_queries += 1
        worst: tuple[str, float] | None = None
        for part in self.obstacles:
            if not self._collides_with(part, p):
                continue
            depth = self._depth_bound(part, p)
            if worst is None or depth > worst[1]:
                worst = (part.name, depth)
        return worst

    # ------------------------------------------------------------------ motions

    def _assess(self, t: np.ndarray, last: Witness | None = None
                ) -> tuple[bool, float, float, Witness | None]:
        """(valid, clearance, certified step, the witness of a tolerated ``t``) at ``t``;
        ``last``: the witness of the pose before on the motion, tried first.

        A free ``t`` with clearance ``d`` certifies every ``t + s`` with
        ``|s| <= d + delta`` (translations move every point of R by exactly ``|s|``, and
        ``pd`` is 1-Lipschitz); a tolerated ``t`` with witness bound ``b`` certifies
        ``|s| <= delta - b``.
        """
        d = self._free_distance(t)
        delta = self.contact_tolerance
        if d is not None:
            if delta == 0.0 and d <= self.floor:
                return False, d, 0.0, None
            return True, d, d + delta, None
        found = self._witness_found(t, first=last)
        if found is None:
            return False, 0.0, 0.0, None
        return True, 0.0, delta - found.bound, found

    def _obstacle_at(self, t: np.ndarray) -> str | None:
        hit = self.colliding_obstacle(t)
        if hit is not None:
            return hit[0]
        d = self._free_distance(t)
        if d is not None and d <= self.floor:
            # Closest obstacle (within the contact floor).
            best, name = math.inf, None
            for part in self.obstacles:
                dist = self._surface_distance(part, t)
                if dist < best:
                    best, name = dist, part.name
            return name
        return None

    def check_segment(
        self, a: ArrayLike, b: ArrayLike, *, max_step: float | None = None
    ) -> SegmentCheck:
        """Check every configuration on the straight motion ``a -> b``.

        Conservative advancement: at a free configuration with clearance ``d`` the
        robot can translate by ``d`` (plus ``delta``) in any direction without an
        invalid contact, so the check steps by that amount; both endpoints are always
        checked. It never relies on FCL's ``continuousCollide`` (whose default
        conservative-advancement solver misses sweeps straight through a mesh).

        Args:
            a, b: ``(3,)`` translations.
            max_step: optional cap on the step length (denser sampling; never needed for
                correctness).

        Returns:
            :class:`SegmentCheck`.
        """
        pa, pb = _as_translation(a, "a"), _as_translation(b, "b")
        if max_step is not None and not (max_step > 0 and math.isfinite(max_step)):
            raise InvalidParameterError(f"max_step = {max_step!r}: must be finite and > 0")
        v = pb - pa
        length = float(np.linalg.norm(v))
        unit = v / length if length > 0 else np.zeros(3)
        s = 0.0
        n = 0
        certified: float | None = None
        last: Witness | None = None  # the last tolerated pose's witness, tried first
        samples: list[tuple[float, float]] = []
        all_free = True
        while True:
            p = pb.copy() if s >= length else pa + s * unit
            valid, d, step, found = self._assess(p, last)
            last = found or last
            n += 1
            if valid and s < length:
                if max_step is not None:
                    step = min(step, max_step)
                if step < self.floor or n >= self.tolerances.max_checks_per_segment:
                    valid = False  # cannot certify further: report as invalid here
            if not valid:
                dists = [x for _, x in samples]
                return SegmentCheck(
                    valid=False,
                    first_invalid=p,
                    min_distance=min(dists + [d]) if d > 0 else 0.0,
                    n_checks=n,
                    last_valid_fraction=None if certified is None else certified / length,
                    clearance_lower_bound=0.0,
                    obstacle=self._obstacle_at(p),
                )
            samples.append((s, d))
            all_free = all_free and d > 0.0
            if s >= length:
                break
            s = min(s + step, length)
            certified = s
        best = min(x for _, x in samples)
        lower = best
        if all_free and len(samples) > 1:
            best, lower, extra = self._refine_clearance(pa, unit, samples)
            n += extra
        elif not all_free:
            lower = 0.0
        return SegmentCheck(
            valid=True,
            first_invalid=None,
            min_distance=best,
            n_checks=n,
            last_valid_fraction=1.0,
            clearance_lower_bound=lower,
        )

    def _refine_clearance(
        self, a: np.ndarray, unit: np.ndarray, samples: list[tuple[float, float]]
    ) -> tuple[float, float, int]:
        """Piyavskii's 1-Lipschitz minimisation of the clearance along the segment.

        Returns (best sampled clearance, certified lower bound, extra queries)."""

        def bound(s0: float, d0: float, s1: float, d1: float) -> tuple[float, float]:
            lower = 0.5 * (d0 + d1 - (s1 - s0))
            x = min(max(0.5 * (s0 + s1) + 0.5 * (d0 - d1), s0), s1)
            return lower, x

        best = min(d for _, d in samples)
        heap: list[tuple[float, float, float, float, float, float]] = []
        for (s0, d0), (s1, d1) in zip(samples, samples[1:]):
            lower, x = bound(s0, d0, s1, d1)
            heapq.heappush(heap, (lower, s0, d0, s1, d1, x))
        extra = 0
        tols = self.tolerances
        while heap and extra < tols.clearance_budget:
            lower, s0, d0, s1, d1, x = heap[0]
            if best - lower <= max(tols.clearance_rtol * best, self.floor):
                break
            heapq.heappop(heap)
            if not (s0 < x < s1):
                x = 0.5 * (s0 + s1)
            d = self._free_distance(a + x * unit)
            extra += 1
            d = 0.0 if d is None else d
            best = min(best, d)
            for seg in ((s0, d0, x, d), (x, d, s1, d1)):
                lo, xm = bound(*seg)
                heapq.heappush(heap, (lo, *seg, xm))
        lower = min((h[0] for h in heap), default=best)
        return best, min(lower, best), extra

    def check_path(self, waypoints: ArrayLike, *, max_step: float | None = None) -> PathCheck:
        """Check every segment of a piecewise-linear path (never only the waypoints).

        Args:
            waypoints: ``(n, 3)`` translations, ``n >= 1``.
            max_step: passed to :meth:`check_segment`.

        Returns:
            :class:`PathCheck`; checking stops at the first invalid segment.
        """
        pts = np.asarray(waypoints, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
            raise InvalidParameterError(
                f"waypoints: expected an (n, 3) array with n >= 1, got shape {pts.shape}"
            )
        if len(pts) == 1:
            pts = np.vstack([pts, pts])
        n = 0
        min_clear = math.inf
        lower = math.inf
        for i, (a, b) in enumerate(zip(pts, pts[1:])):
            seg = self.check_segment(a, b, max_step=max_step)
            n += seg.n_checks
            min_clear = min(min_clear, seg.min_distance)
            if not seg.valid:
                return PathCheck(
                    valid=False,
                    first_bad_segment=i,
                    min_clearance=min_clear,
                    n_checks=n,
                    first_invalid=seg.first_invalid,
                    clearance_lower_bound=0.0,
                    obstacle=seg.obstacle,
                )
            lower = min(lower, seg.clearance_lower_bound)
        return PathCheck(
            valid=True,
            first_bad_segment=None,
            min_clearance=min_clear,
            n_checks=n,
            clearance_lower_bound=lower,
        )

    def check_motion(self, a: ArrayLike, b: ArrayLike) -> tuple[bool, float | None]:
        """:class:`~planner.roles.MotionValidator` interface: ``(True,
        None)`` when ``a -> b`` is valid, else ``(False, last valid fraction)``."""
        seg = self.check_segment(a, b)
        if seg.valid:
            self.n_valid_motions += 1
            return True, None
        self.n_invalid_motions += 1
        return False, seg.last_valid_fraction


def _unit_hints(hints: Sequence[ArrayLike]) -> list[np.ndarray]:
    """The distinct unit directions of ``hints`` (3-vectors; zero or non-finite ones
    dropped)."""
    unique: list[np.ndarray] = []
    for hint in hints:
        h = np.asarray(hint, dtype=np.float64)
        if h.shape != (3,):
            raise InvalidParameterError(f"escape_hints: a hint has shape {h.shape}, not (3,)")
        norm = float(np.linalg.norm(h))
        if not (math.isfinite(norm) and norm > 0.0):
            continue
        d = h / norm
        if not any(float(np.dot(d, u)) > 1.0 - 1e-9 for u in unique):
            unique.append(d)
    return unique
