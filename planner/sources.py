"""The C-obstacle source: the geometry C-obstacles ``O ⊕ (−R)`` are computed from, chosen
once per problem and taken by every consumer.

- :class:`DecompositionSource`: convex pieces of every part (exact for convex bodies, CoACD
  for the others, cached on disk) and their pairwise sums ``M_ij = P_i ⊕ (−Q_j)``.
- :class:`ExactSource`: the meshes as given: reduced-convolution facets where both parts
  are solids, every triangle-pair piece where one is a surface (the native core's exact
  source); no decomposition, nothing approximated.

:func:`parse_exact` is the one rule for the ``exact`` setting (API, CLI and YAML);
:func:`choose` decides ``auto`` once for a set of parts. The planner builds its C-space
with :meth:`Source.cspace`, sums and the viz take one pair's C-obstacle from
:meth:`Source.pair`, the assembly pair cache too; :meth:`Source.describe` says what was
used for ``report.json`` and certificates. A source remembers the decompositions and
checked meshes of the parts it has seen, so what is drawn is what was planned and nothing
is computed twice.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .errors import InvalidParameterError, ScenarioError
from .tolerances import tol
from .values import describe_value

if TYPE_CHECKING:  # only for annotations: the problem types import this module
    from ._minkowski_core import CSpace
    from .decompose import Decomposition
    from .problem import Part, PlannerSettings

__all__ = [
    "DecompositionSource",
    "ExactSetting",
    "ExactSource",
    "PairCObstacle",
    "CheckedParts",
    "Source",
    "SourceSettings",
    "check_exact",
    "choose",
    "choose_for",
    "parse_exact",
]

log = logging.getLogger(__name__)

ExactSetting = bool | Literal["auto"]
"""``True`` (the exact source), ``False`` (the decomposition) or ``"auto"``."""


def check_exact(value: Any) -> ExactSetting:
    """The ``exact`` setting: ``True``, ``False`` or ``"auto"``, also written as the strings
    ``"true"``, ``"false"``, ``"auto"`` (any case). ``ValueError`` otherwise."""
    word = value.strip().lower() if isinstance(value, str) else None
    if word == "auto":
        return "auto"
    if word in ("true", "false"):
        return word == "true"
    if isinstance(value, bool):
        return value
    raise ValueError(f"expected auto, true or false, got {describe_value(value)}")


def parse_exact(value: Any, field: str = "exact") -> ExactSetting:
    """:func:`check_exact` for the API: an :class:`InvalidParameterError` naming ``field``."""
    try:
        return check_exact(value)
    except ValueError as error:
        raise InvalidParameterError(f"{field} = {value!r}: {error}") from None


@dataclass(frozen=True)
class SourceSettings:
    """What a source is built with.

    Attributes:
        exact: see :data:`ExactSetting`.
        threshold: CoACD concavity threshold for non-convex bodies (decomposition).
        seed: CoACD seed.
        cache_dir: decomposition cache (default: :func:`planner.decompose.default_cache_dir`).
        progress: progress bars of decompositions (``None``: on a terminal).
    """

    exact: ExactSetting = "auto"
    threshold: float = tol.coacd_threshold
    seed: int = 0
    cache_dir: str | Path | None = None
    progress: bool | None = False


def choose_for(parts: Sequence[Part], settings: PlannerSettings, *, cache_dir=None,
               progress: bool | None = False, field: str = "planner.exact") -> Source:
    """:func:`choose` with a problem's planner settings (``planner.exact``,
    ``planner.decomposition_threshold``, ``planner.seed``); ``field`` names where the
    ``exact`` setting was given (``"--exact"``: the command line's option)."""
    return choose(parts, SourceSettings(exact=settings.exact,
                                        threshold=settings.decomposition_threshold,
                                        seed=settings.seed, cache_dir=cache_dir,
                                        progress=progress), field=field)


def _setting_text(field: str, value: str) -> str:
    """A setting as its user wrote it: ``"--exact false"`` for a command-line option
    (``field`` starts with ``--``), ``"planner.exact: false"`` for a YAML field or a
    keyword."""
    return f"{field} {value}" if field.startswith("--") else f"{field}: {value}"


def choose(parts: Sequence[Part], settings: SourceSettings | None = None, *,
           field: str = "exact") -> Source:
    """The source for these parts: ``exact: true`` the exact source, ``false`` the
    decomposition (refused when a part is a surface, which it cannot represent), ``auto``
    the decomposition when every body of every part is convex (exact then, and fastest),
    else the exact source (CoACD's hulls would over-approximate). ``field`` names the
    setting in messages and in the reason the source gives (:func:`_setting_text`)."""
    settings = settings or SourceSettings()
    setting = parse_exact(settings.exact, field)
    surfaces = [p.name for p in parts if not p.solid]
    if setting is True:
        return ExactSource(settings, _setting_text(field, "true"))
    if setting is False:
        if surfaces:
            raise ScenarioError(
                f"{_setting_text(field, 'false')}: {', '.join(surfaces)} "
                f"{'is a surface' if len(surfaces) == 1 else 'are surfaces'} (not closed "
                f"solids), which the convex decomposition cannot represent; use "
                f"{_setting_text(field, 'auto')}", field=field)
        return DecompositionSource(settings, _setting_text(field, "false"))
    if surfaces:
        return ExactSource(settings, f"auto: {', '.join(surfaces)} not solid (surfaces)")
    checked = CheckedParts()
    nonconvex = [p.name for p in parts if not checked.convex(p)]
    if nonconvex:
        return ExactSource(settings, f"auto: {', '.join(nonconvex)} not convex", parts=checked)
    return DecompositionSource(settings, "auto: every body is convex (the decomposition is "
                                         "exact)", parts=checked)


class PairCObstacle:
    """One pair's C-obstacle ``O ⊕ (−R)`` (or plain sum ``A ⊕ B``) from a source: point,
    segment and distance queries and the surface, on the native object ``native``
    (``Primitives`` or ``ExactSum``).

    Attributes:
        native: the core's object.
        exact: the geometry is exact for the meshes as given (no hull excess).
        excess: how far it may stick out of the true sum (the decompositions' measured
            excess, ``0`` when exact).
        stats: what it was built from (pieces or triangles and facets).
    """

    def __init__(self, native, *, exact: bool, excess: float, stats: dict[str, Any]) -> None:
        self.native = native
        self.exact = exact
        self.excess = excess
        self.stats = stats

    def contains(self, points: np.ndarray) -> np.ndarray:
        """``(n,)`` membership of ``(n, 3)`` points (closed set)."""
        return self.native.contains(np.ascontiguousarray(points, dtype=np.float64))

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """``(n,)`` signed distance bounds: outside, a lower bound on the distance;
        inside, minus a lower bound on the depth."""
        return self.native.signed_distance(np.ascontiguousarray(points, dtype=np.float64))

    def segment_intervals(self, a: np.ndarray, b: np.ndarray) -> list[tuple[float, float]]:
        """The parameter intervals of ``a → b`` inside the C-obstacle, sorted."""
        return self.native.segment_intervals(np.asarray(a, dtype=np.float64),
                                             np.asarray(b, dtype=np.float64))


class CheckedParts:
    """Each part's checked arrays, computed once: a solid checked and cleaned by
    :func:`planner.meshes.validate_solid` (unless a reader has done it already), a
    surface's triangles as they are; the core's mesh of them (checked once, for every
    pair it is in); and whether a solid's bodies are all convex."""

    def __init__(self) -> None:
        self._arrays: dict[int, tuple[Part, Any, tuple[np.ndarray, np.ndarray]]] = {}
        self._native: dict[int, Any] = {}
        self._convex: dict[int, bool] = {}

    def arrays(self, part: Part) -> tuple[np.ndarray, np.ndarray]:
        """Vertices ``(n, 3)`` float64 and faces ``(m, 3)`` int64 of the part."""
        return self._checked(part)[2]

    def _checked(self, part: Part) -> tuple[Part, Any, tuple[np.ndarray, np.ndarray]]:
        """``(part, its checked trimesh, its arrays)``, computed once (the part kept
        alive: its id stays its own)."""
        key = id(part)
        if key not in self._arrays:
            mesh = part.mesh
            if part.solid and not part.checked:
                from .meshes import validate_solid  # noqa: PLC0415

                mesh = validate_solid(mesh, name=part.name)
            arrays = (np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                      np.ascontiguousarray(mesh.faces, dtype=np.int64))
            self._arrays[key] = (part, mesh, arrays)
        return self._arrays[key]

    def native(self, part: Part):
        """The core's :class:`CheckedMesh` of the part's mesh (built once; the one its
        check made when it was validated here or by a reader: :mod:`.meshes.checked`)."""
        key = id(part)
        if key not in self._native:
            from .meshes.checked import core_mesh  # noqa: PLC0415

            self._native[key] = core_mesh(self._checked(part)[1], solid=part.solid,
                                          name=part.name)
        return self._native[key]

    def convex(self, part: Part) -> bool:
        """Whether every body of a solid part is convex (its decomposition is exact and
        cheap), by the test :func:`planner.decompose.decompose` uses."""
        if not part.solid:
            return False
        key = id(part)
        if key not in self._convex:
            import trimesh  # noqa: PLC0415

            from .decompose import is_convex_body  # noqa: PLC0415
            from .meshes import split_solid  # noqa: PLC0415

            mesh = trimesh.Trimesh(*self.arrays(part), process=False)
            self._convex[key] = all(is_convex_body(body) for body in split_solid(mesh))
        return self._convex[key]


class Source:
    """Base of the sources (see the module documentation).

    Attributes:
        kind: ``"exact"`` or ``"decomposition"``.
        why: why it was chosen (for reports).
        settings: :class:`SourceSettings`.
        parts: the :class:`CheckedParts` it works from.
    """

    kind = ""

    def __init__(self, settings: SourceSettings, why: str, *,
                 parts: CheckedParts | None = None) -> None:
        self.settings = settings
        self.why = why
        self.parts = parts or CheckedParts()

    def arrays(self, part: Part) -> tuple[np.ndarray, np.ndarray]:
        """The part's checked arrays (see :class:`CheckedParts`)."""
        return self.parts.arrays(part)

    @property
    def decomposed(self) -> int:
        """How many parts this source has decomposed (CoACD or convex bodies)."""
        return 0

    # ---- what subclasses provide

    @property
    def exact(self) -> bool:
        """Whether C-obstacles (hence certificates and bounds) are exact for the meshes."""
        raise NotImplementedError

    def margin_deficit(self, parts: Sequence[Part]) -> float:
        """How much the pieces may fall short of the parts: the planner grows its
        C-obstacles by it (0 when exact)."""
        raise NotImplementedError

    def excess(self, parts: Sequence[Part]) -> float:
        """How far the C-obstacles may stick out (0 when exact)."""
        raise NotImplementedError

    def cspace(self, obstacles: Sequence[Part], robot: Part, bounds: np.ndarray,
               floor: float, coarse: float, *, margin: float = 0.0,
               max_leaves: int | None = None) -> CSpace:
        """The planner's native C-space of ``robot`` among ``obstacles`` (``max_leaves``:
        default from the memory limit, :func:`planner.budget.leaves`)."""
        raise NotImplementedError

    def owners(self, obstacles: Sequence[Part], robot: Part) -> np.ndarray:
        """For each obstacle primitive of :meth:`cspace`, the index of its obstacle."""
        raise NotImplementedError

    def pair(self, a: Part, b: Part, *, mirror_b: bool = True) -> PairCObstacle:
        """The C-obstacle ``a ⊕ (−b)`` of obstacle ``a`` for robot ``b`` (``mirror_b``),
        or the plain sum ``a ⊕ b``."""
        raise NotImplementedError

    def describe(self, obstacles: Sequence[Part], robot: Part) -> dict[str, Any]:
        """``{"used", "why", ...}`` for ``report.json``."""
        raise NotImplementedError

    def relative_to(self, parts: Sequence[Part]) -> str:
        """What a certificate on this source's C-obstacles of ``parts`` (obstacles, then
        the robot) speaks of."""
        raise NotImplementedError


class ExactSource(Source):
    """The meshes as given, no decomposition (see the module documentation).

    The pair sums it builds (:meth:`pair`, e.g. for an assembly's pair cache) are kept, and
    a C-space over the same parts takes each obstacle's reduced convolution from its pair
    sum instead of computing it again (``pairs_reused`` counts them).
    """

    kind = "exact"

    def __init__(self, settings: SourceSettings, why: str, *,
                 parts: CheckedParts | None = None) -> None:
        super().__init__(settings, why, parts=parts)
        self._mirrored: dict[tuple[int, int], tuple[Part, Part, Any]] = {}
        self.pairs_reused = 0

    @property
    def exact(self) -> bool:
        return True

    def margin_deficit(self, parts: Sequence[Part]) -> float:
        return 0.0

    def excess(self, parts: Sequence[Part]) -> float:
        return 0.0

    def cspace(self, obstacles, robot, bounds, floor, coarse, *, margin=0.0,
               max_leaves=None):
        from . import budget  # noqa: PLC0415
        from ._minkowski_core import CSpace  # noqa: PLC0415

        native = self.parts.native
        reuse = [self._mirrored.get((id(o), id(robot)), (None, None, None))[2]
                 for o in obstacles]
        cs = CSpace.exact([native(o) for o in obstacles], native(robot),
                          np.asarray(bounds, dtype=np.float64), floor, coarse,
                          margin=margin,
                          max_leaves=budget.leaves() if max_leaves is None else max_leaves,
                          solid=[o.solid for o in obstacles], robot_solid=robot.solid,
                          max_facets=budget.facets(), reuse=reuse)
        self.pairs_reused += sum(cs.reused)
        return cs

    def owners(self, obstacles, robot):
        return np.arange(len(obstacles), dtype=np.int64)

    def pair(self, a, b, *, mirror_b=True):
        from . import _minkowski_core as core  # noqa: PLC0415

        mesh_b = self.parts.native(b)
        if mirror_b:  # −B: negated vertices, triangles reversed so that normals stay outward
            mesh_b = mesh_b.negated()
        from . import budget  # noqa: PLC0415

        native = core.ExactSum(self.parts.native(a), mesh_b, a.solid, b.solid,
                               max_facets=budget.facets())
        if mirror_b:  # kept for the C-spaces of the same parts (the parts kept alive too)
            self._mirrored[(id(a), id(b))] = (a, b, native)
        stats = _exact_pair_stats(native)
        return PairCObstacle(native, exact=True, excess=0.0, stats=stats)

    def depth_pair(self, a: Part, b: Part, point: np.ndarray, tolerance: float
                   ) -> PairCObstacle:
        """The C-obstacle ``a ⊕ (−b)`` for one depth query only (its ``native.depth`` at
        ``point`` to within ``tolerance``): the reduced convolution's facets beyond the
        cube that query's search can reach are left out (two parts that overlap a little
        have few there, where the whole convolution of two gears would not fit in
        memory). Not kept for C-spaces; a query it cannot answer (a point outside whose
        nearest facet lies beyond the cube) is refused with an ``InvalidParameterError``
        naming the ``depth region``."""
        from . import _minkowski_core as core  # noqa: PLC0415
        from . import budget  # noqa: PLC0415

        native = core.ExactSum(self.parts.native(a), self.parts.native(b).negated(), True, True,
                               max_facets=budget.facets(),
                               depth_near=(np.asarray(point, dtype=np.float64).tolist(),
                                           float(tolerance)))
        stats = _exact_pair_stats(native)
        return PairCObstacle(native, exact=True, excess=0.0, stats=stats)

    def describe(self, obstacles, robot):
        return {"used": self.kind, "why": self.why,
                "triangles": {"robot": int(len(self.arrays(robot)[1])),
                              "obstacles": [int(len(self.arrays(o)[1])) for o in obstacles]},
                "decomposition": {"method": "none (exact boundary-convolution source)",
                                  "exact": True, "excess": 0.0, "deficit": 0.0}}

    def relative_to(self, parts):
        return "the meshes as given (exact boundary-convolution source)"


def _exact_pair_stats(native) -> dict[str, int]:
    """What an exact pair sum (``ExactSum``) was built from: triangles and facets."""
    return {"triangles_a": int(native.triangles[0]), "triangles_b": int(native.triangles[1]),
            "facets": int(native.facets)}


class DecompositionSource(Source):
    """Convex pieces of every part and their pairwise sums (see the module doc)."""

    kind = "decomposition"

    def __init__(self, settings: SourceSettings, why: str, *,
                 parts: CheckedParts | None = None) -> None:
        super().__init__(settings, why, parts=parts)
        self._decompositions: dict[int, Decomposition] = {}

    def decomposition(self, part: Part) -> Decomposition:
        """The part's convex decomposition (once per part; CoACD results cached on disk)."""
        key = id(part)
        if key not in self._decompositions:
            import trimesh  # noqa: PLC0415

            from .decompose import decompose  # noqa: PLC0415

            vertices, faces = self.arrays(part)
            s = self.settings
            self._decompositions[key] = decompose(
                trimesh.Trimesh(vertices, faces, process=False), name=part.name,
                threshold=s.threshold, seed=s.seed, cache_dir=s.cache_dir,
                progress=s.progress, checked=True)
        return self._decompositions[key]

    @property
    def decomposed(self) -> int:
        return len(self._decompositions)

    def _pieces(self, part: Part) -> list[np.ndarray]:
        return [np.ascontiguousarray(p, dtype=np.float64)
                for p in self.decomposition(part).pieces]

    @property
    def exact(self) -> bool:
        return all(d.exact for d in self._decompositions.values())

    def margin_deficit(self, parts):
        return self._worst_pair(parts, "deficit")

    def excess(self, parts):
        return self._worst_pair(parts, "excess")

    def _worst_pair(self, parts, which: str) -> float:
        """The robot's ``which`` (deficit or excess) plus the largest of the obstacles'."""
        *obstacles, robot = parts
        return getattr(self.decomposition(robot), which) + max(
            (getattr(self.decomposition(o), which) for o in obstacles), default=0.0)

    def cspace(self, obstacles, robot, bounds, floor, coarse, *, margin=0.0,
               max_leaves=None):
        from . import budget  # noqa: PLC0415
        from ._minkowski_core import CSpace, Primitives  # noqa: PLC0415

        if max_leaves is None:
            max_leaves = budget.leaves()
        pieces = [p for o in obstacles for p in self._pieces(o)]
        prims = (Primitives.pairwise_sums(pieces, self._pieces(robot), subtract=True)
                 if pieces else None)
        return CSpace(prims, np.asarray(bounds, dtype=np.float64), floor, coarse,
                      margin=margin, max_leaves=max_leaves)

    def owners(self, obstacles, robot):
        counts = [len(self.decomposition(o).pieces) for o in obstacles]
        per_obstacle = np.repeat(np.arange(len(obstacles), dtype=np.int64), counts)
        return np.repeat(per_obstacle, len(self.decomposition(robot).pieces))

    def pair(self, a, b, *, mirror_b=True):
        from ._minkowski_core import Primitives  # noqa: PLC0415

        dec_a, dec_b = self.decomposition(a), self.decomposition(b)
        native = Primitives.pairwise_sums(self._pieces(a), self._pieces(b), subtract=mirror_b)
        stats = {"pieces_a": len(dec_a.pieces), "pieces_b": len(dec_b.pieces),
                 "primitives": len(native)}
        excess = max(dec_a.excess, dec_a.deficit) + max(dec_b.excess, dec_b.deficit)
        return PairCObstacle(native, exact=dec_a.exact and dec_b.exact, excess=excess,
                             stats=stats)

    def describe(self, obstacles, robot):
        def one(part: Part) -> dict[str, Any]:
            d = self.decomposition(part)
            return {"name": part.name, "pieces": len(d.pieces), "exact": d.exact,
                    "method": d.method, "excess": d.excess, "deficit": d.deficit,
                    "cache_hit": d.cache_hit, "seconds": d.seconds}

        parts = [*obstacles, robot]
        return {"used": self.kind, "why": self.why, "triangles": None,
                "decomposition": {"robot": one(robot), "obstacles": [one(o) for o in obstacles],
                                  "exact": all(self.decomposition(p).exact for p in parts),
                                  "excess": self.excess(parts),
                                  "deficit": self.margin_deficit(parts)}}

    def relative_to(self, parts):
        if all(self.decomposition(p).exact for p in parts):
            return "the obstacles (exact convex decomposition)"
        return (f"the convex hulls of CoACD's decomposition (excess about "
                f"{self.excess(parts):.3g})")
