"""Per-pair data of an assembly, computed once and reused by every removal step: each
ordered pair's C-obstacle (from the assembly's source) and whether one part alone blocks
a straight removal of another along a direction."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from planner.errors import MinkplanError
from planner.problem import Assembly
from planner.sources import PairCObstacle, Source, choose_for
from planner.validation import FclChecker

from .geometry import ESCAPE_MARGIN_REL, exit_box, exit_point

__all__ = ["RAY_SAMPLES", "PairCache", "RayVerdict"]

log = logging.getLogger(__name__)


RAY_SAMPLES = 7
"""Interior points per interval at which a ray's depth in a pair's C-obstacle is read."""


@dataclass
class RayVerdict:
    """Whether obstacle part ``obstacle`` alone blocks the straight removal of ``part``
    along a direction (the ray from ``0`` past the whole assembly's exit box).

    Attributes:
        blocked: the ray enters the pair's C-obstacle deeper than the contact tolerance.
        how: ``"primitives"`` (decided by the pair's cached C-obstacle: a sampled depth
            beyond the tolerance proves ``blocked``; a ray that misses an exact
            C-obstacle is free) or ``"fcl"`` (a grazing ray, sliding along touching
            faces: decided by ``FclChecker.check_segment`` on the two parts alone).
        depth: deepest sampled penetration of the ray into the pair's C-obstacle (a
            lower bound of the penetration depth there), ``0`` when the ray misses it or
            only grazes it.
    """

    blocked: bool
    how: str
    depth: float


class PairCache:
    """Per-pair data of one assembly, computed once and reused across removal steps.

    The C-obstacle of part ``j`` for moving part ``i``, ``CO_ij = O_j ⊕ (−R_i)``, taken
    from the assembly's source (:meth:`planner.sources.Source.pair`: the exact source's
    boundary convolution of the two meshes, or the pairwise sums of their convex pieces),
    depends on the two parts only: it does not change when other parts leave. So does
    whether ``j`` blocks a straight removal of ``i`` along a direction (the ray is taken
    past the exit box of the whole assembly; while ``j`` is present, the exit box contains
    ``j``'s box, so the shorter ray of a later step meets ``j`` exactly where the long one
    does). The search asks the cache; every answer is computed at most once.

    Attributes:
        source: the C-obstacle source of every pair (and of the planned removals).
        stats: ``sums_computed`` (pairs whose C-obstacles were built), ``sums_reused``
            (later requests served from the cache), ``primitives`` (total primitives
            built, decomposition source), ``verdicts_computed`` / ``verdicts_reused`` (ray
            verdicts), ``fcl_pair_checks`` (grazing rays decided by FCL),
            ``decompositions`` (parts decomposed, decomposition source).
        computed: the ``(moving, obstacle)`` pairs in the order their sums were built.
        step: the search's current step (a counter over all its runs, set by the search).
        uses: per pair, the steps that asked for its primitives or verdicts.
    """

    def __init__(self, assembly: Assembly, cache_dir=None, source: Source | None = None) -> None:
        self.assembly = assembly
        self.parts = {p.name: p for p in assembly.parts}
        self.delta = assembly.tolerance  # contact (+ interference) tolerance
        self.margin = ESCAPE_MARGIN_REL * assembly.diagonal
        self.source = source or choose_for(assembly.parts, assembly.settings,
                                           cache_dir=cache_dir)
        self._sums: dict[tuple[str, str], PairCObstacle | None] = {}
        self._verdicts: dict[tuple[str, str, str], RayVerdict] = {}
        self._rays: dict[tuple[str, str, str], tuple[bool, float]] = {}
        self._samples: dict[tuple[str, str, str], tuple[bool, np.ndarray]] = {}
        self._detours: dict[tuple[str, str, str], float] = {}
        self._runs: dict[tuple[str, str, str], float] = {}
        self._plane_cache: dict[tuple[str, str], list[tuple[np.ndarray, np.ndarray]]] = {}
        self._far: dict[tuple[str, str], np.ndarray] = {}
        self._contacts: dict[tuple[str, str], list[np.ndarray]] = {}
        self._checkers: dict[tuple[str, str], FclChecker] = {}
        self.computed: list[tuple[str, str]] = []
        self.step = 0
        self.uses: dict[tuple[str, str], set[int]] = {}
        self.stats = {"decompositions": 0, "sums_computed": 0, "sums_reused": 0,
                      "sums_failed": 0, "primitives": 0, "verdicts_computed": 0,
                      "verdicts_reused": 0, "fcl_pair_checks": 0}

    def primitives(self, moving: str, obstacle: str) -> PairCObstacle | None:
        """``CO_ij`` of the obstacle part for the moving one (built once per ordered
        pair); ``None`` when the core cannot build it (FCL decides for that pair)."""
        key = (moving, obstacle)
        self._use(moving, obstacle)
        if key in self._sums:
            self.stats["sums_reused"] += 1
            return self._sums[key]
        pair: PairCObstacle | None
        try:
            pair = self.source.pair(self.parts[obstacle], self.parts[moving], mirror_b=True)
        except MinkplanError as error:
            # e.g. a degenerate sum of nearly parallel pieces: FCL decides for this pair
            log.warning("C-obstacle of %s for %s: %s; using FCL only for this pair",
                        obstacle, moving, error)
            pair = None
            self.stats["sums_failed"] += 1
        self._sums[key] = pair
        self.computed.append(key)
        self.stats["sums_computed"] += 1
        self.stats["primitives"] += 0 if pair is None else pair.stats.get("primitives", 0)
        self.stats["decompositions"] = self.source.decomposed
        return pair

    def checker(self, moving: str, obstacle: str) -> FclChecker:
        """FCL checker of the moving part against the obstacle part alone."""
        key = (moving, obstacle)
        if key not in self._checkers:
            self._checkers[key] = FclChecker.for_parts(
                self.parts[moving], [self.parts[obstacle]], contact_tolerance=self.delta)
        return self._checkers[key]

    def contact_directions(self, moving: str, obstacle: str) -> list[np.ndarray]:
        """Escape directions of FCL's contact normals between the two parts at the
        assembled pose that are not axis directions (those are tried anyway)."""
        key = (moving, obstacle)
        if key not in self._contacts:
            checker = self.checker(moving, obstacle)
            found = []
            for d in checker.escape_directions(np.zeros(3)):
                if np.max(np.abs(d)) <= 1.0 - 1e-9:
                    found.append(d)
            self._contacts[key] = found
        return self._contacts[key]

    def _use(self, moving: str, obstacle: str) -> None:
        self.uses.setdefault((moving, obstacle), set()).add(self.step)

    def far_point(self, moving: str, dname: str, vec: np.ndarray) -> np.ndarray:
        """End of the ray along ``vec``: just outside the whole assembly's exit box."""
        key = (moving, dname)
        if key not in self._far:
            part = self.parts[moving]
            others = [p for p in self.assembly.parts if p.name != moving]
            self._far[key] = exit_point(vec, exit_box(part, others, self.margin),
                                         self.margin)
        return self._far[key]

    def ray(self, moving: str, obstacle: str, dname: str,
            vec: np.ndarray) -> tuple[bool, float]:
        """``(touches, depth)`` of the ray along ``vec`` in ``CO_ij``, from the cached
        primitives: whether it meets any primitive (touching included) and the deepest
        sampled penetration (inside one primitive: a lower bound of the true depth)."""
        key = (moving, obstacle, dname)
        if key not in self._rays:
            prims = self.primitives(moving, obstacle)
            if prims is None:  # no primitives: undecided (FCL)
                self._rays[key] = (True, 0.0)
                return self._rays[key]
            touches, points = self._ray_samples(prims, moving, obstacle, dname, vec)
            depth = 0.0
            if len(points):
                depth = max(0.0, -float(np.min(prims.signed_distance(points))))
            self._rays[key] = (touches, depth)
        return self._rays[key]

    def _ray_samples(self, prims: PairCObstacle, moving: str, obstacle: str, dname: str,
                     vec: np.ndarray) -> tuple[bool, np.ndarray]:
        """Whether the ray along ``vec`` meets ``CO_ij`` (its primitives ``prims``;
        touching included) and ``RAY_SAMPLES`` points inside each of its intervals there.
        Computed once for :meth:`ray` and :meth:`detour`."""
        key = (moving, obstacle, dname)
        if key not in self._samples:
            far = self.far_point(moving, dname, vec)
            intervals = prims.segment_intervals(np.zeros(3), far)
            ts = [a + (b - a) * np.linspace(0.0, 1.0, RAY_SAMPLES + 2)[1:-1]
                  for a, b in intervals if b > a]
            points = np.concatenate(ts or [np.zeros(0)])[:, None] * far[None, :]
            self._samples[key] = (bool(intervals), np.ascontiguousarray(points))
        return self._samples[key]

    def detour(self, moving: str, obstacle: str, dname: str, vec: np.ndarray) -> float:
        """How far the part must step aside, across the ray along ``vec``, to pass
        ``obstacle``: the largest distance, over sampled points of the ray inside a
        primitive of ``CO_ij``, to that primitive's boundary within the plane through
        the point perpendicular to the ray (``0`` when the ray misses ``CO_ij``). A thin
        wall across the ray is a long detour; a low stop a short one."""
        key = (moving, obstacle, dname)
        if key in self._detours:
            return self._detours[key]
        touches, depth = self.ray(moving, obstacle, dname, vec)
        best = 0.0
        pair = self.primitives(moving, obstacle)
        if touches and pair is not None and not hasattr(pair.native, "polytope"):
            best = depth  # no facet planes (exact source): the depth, a lower bound
        elif touches and pair is not None:
            _, points = self._ray_samples(pair, moving, obstacle, dname, vec)
            if len(points):
                for normals, offsets in self._planes(moving, obstacle):
                    slack = offsets[None, :] - points @ normals.T
                    inside = np.all(slack >= -1e-12 * (1.0 + np.abs(offsets)), axis=1)
                    if not inside.any():
                        continue
                    across = np.linalg.norm(normals - np.outer(normals @ vec, vec), axis=1)
                    keep = across > 1e-9
                    if not keep.any():
                        continue
                    side = np.min(slack[inside][:, keep] / across[keep], axis=1)
                    best = max(best, float(np.max(side)))
        self._detours[key] = best
        return best

    def _planes(self, moving: str, obstacle: str) -> list[tuple[np.ndarray, np.ndarray]]:
        """Facet planes ``(normals, offsets)`` (inside: ``n·x <= d``) of each primitive
        of ``CO_ij``, from its boundary triangles."""
        key = (moving, obstacle)
        if key not in self._plane_cache:
            pair = self.primitives(moving, obstacle)
            assert pair is not None
            prims = pair.native
            planes = []
            for i in range(len(prims)):
                vertices, faces = prims.polytope(i)
                tri = vertices[faces]
                normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                length = np.linalg.norm(normals, axis=1)
                ok = length > 0
                normals = normals[ok] / length[ok, None]
                offsets = np.einsum("ij,ij->i", normals, tri[ok, 0])
                # outward: the centroid is inside
                flip = normals @ vertices.mean(axis=0) > offsets
                normals[flip] *= -1.0
                offsets[flip] *= -1.0
                planes.append((normals, offsets))
            self._plane_cache[key] = planes
        return self._plane_cache[key]

    def verdict(self, moving: str, obstacle: str, dname: str, vec: np.ndarray, *,
                fcl: bool = True) -> RayVerdict | None:
        """Whether ``obstacle`` alone blocks the straight removal of ``moving`` along
        ``vec`` (see :class:`RayVerdict`). With ``fcl=False``, ``None`` instead of an
        FCL check when the primitives cannot decide (a grazing ray)."""
        key = (moving, obstacle, dname)
        self._use(moving, obstacle)
        if key in self._verdicts:
            self.stats["verdicts_reused"] += 1
            return self._verdicts[key]
        touches, depth = self.ray(moving, obstacle, dname, vec)
        pair = self.primitives(moving, obstacle)
        excess = 0.0 if pair is None else pair.excess
        # a depth inside the C-obstacle is a lower bound of the penetration depth (up to
        # the decompositions' excess), so beyond the tolerance it proves a collision
        if depth > self.delta + excess:
            result = RayVerdict(True, "primitives", depth)
        elif not touches and pair is not None and pair.exact:
            result = RayVerdict(False, "primitives", 0.0)
        elif not fcl:
            return None
        else:
            far = self.far_point(moving, dname, vec)
            seg = self.checker(moving, obstacle).check_segment(np.zeros(3), far)
            self.stats["fcl_pair_checks"] += 1
            result = RayVerdict(not seg.valid, "fcl", depth)
        self._verdicts[key] = result
        self.stats["verdicts_computed"] += 1
        return result

    def record_blocked(self, moving: str, obstacle: str, dname: str, vec: np.ndarray) -> None:
        """Record that FCL found the straight removal of ``moving`` along ``vec`` blocked
        with ``obstacle`` alone present (a prefix of the ray: the ray is blocked too), so
        that :meth:`verdict` does not check it again."""
        key = (moving, obstacle, dname)
        if key not in self._verdicts:
            _, depth = self.ray(moving, obstacle, dname, vec)
            self._verdicts[key] = RayVerdict(True, "fcl", depth)
            self.stats["verdicts_computed"] += 1

    def free_run(self, moving: str, obstacle: str, dname: str, vec: np.ndarray) -> float:
        """How far ``moving`` translates along ``vec`` before it meets ``CO_ij`` (``inf``
        when it never does, ``0`` when it starts in contact); ``0`` when the pair has no
        C-obstacle (undecided)."""
        key = (moving, obstacle, dname)
        if key not in self._runs:
            prims = self.primitives(moving, obstacle)
            run = 0.0
            if prims is not None:
                far = self.far_point(moving, dname, vec)
                intervals = prims.segment_intervals(np.zeros(3), far)
                run = (float(intervals[0][0]) * float(np.linalg.norm(far)) if intervals
                       else float("inf"))
            self._runs[key] = run
        return self._runs[key]
