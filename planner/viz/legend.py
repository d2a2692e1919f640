"""The legend: what each colour of a scene stands for, and what of it is drawn.

:func:`legend` groups a :class:`~planner.viz.scene.Scene`'s layers into entries, one per
thing a reader tells apart (all obstacles together, the robot at its start, the
C-obstacles, EMPTY cells, the roadmap, a certificate's walls, each part of an
assembly...), with its colour, its meaning in words and the layers' notes on what is drawn
(how many cells, which of the roadmap's segments). The page (:mod:`planner.viz.html`)
shows it as a panel with one switch per entry.
"""

from __future__ import annotations

from dataclasses import dataclass

from .scene import (
    C_OBSTACLE,
    CELLS_EMPTY,
    CELLS_FULL,
    CELLS_MIXED,
    CERTIFICATE_COMPONENT,
    CERTIFICATE_WALLS,
    MINKOWSKI_A,
    MINKOWSKI_B,
    MINKOWSKI_SUM,
    OBSTACLES,
    PATH,
    ROADMAP,
    ROBOT_GOAL,
    ROBOT_MOVING,
    ROBOT_START,
    Scene,
)

__all__ = ["Entry", "legend"]

_MEANINGS: tuple[tuple[str, str, str], ...] = (
    (OBSTACLES, "Obstacles", "the workspace's fixed parts"),
    (ROBOT_START, "Robot at start", "ghosted"),
    (ROBOT_GOAL, "Robot at goal", "ghosted"),
    (ROBOT_MOVING, "Robot moving", ""),
    (C_OBSTACLE, "C-obstacle", "where the robot's origin must not go: O ⊕ (−R)"),
    (CELLS_EMPTY, "EMPTY cells", "exactly free octree leaves"),
    (CELLS_MIXED, "MIXED cells", "leaves the C-obstacle boundary may cross"),
    (CELLS_FULL, "FULL cells", "exactly blocked octree leaves"),
    (ROADMAP, "Roadmap", "free cells joined through their shared faces"),
    (PATH, "Path", "the robot's origin along the planned path"),
    (CERTIFICATE_WALLS, "Certificate: FULL walls",
     "blocked cells walling the start off the goal (the no-path proof)"),
    (CERTIFICATE_COMPONENT, "Certificate: walled-in cells", "the free cells they enclose"),
    (MINKOWSKI_A, "A", "first operand"),
    (MINKOWSKI_B, "B", "second operand"),
    (MINKOWSKI_SUM, "A ⊕ B", "the Minkowski sum's surface"),
)
"""``(node, label, meaning)`` of every layout path that has one (layers at or below the
node share its entry); other layers get an entry of their own, named after the path."""


@dataclass(frozen=True)
class Entry:
    """One row of the legend.

    Attributes:
        node: the scene path its switch shows or hides (a layer or a group of layers).
        label: what it is, e.g. ``"EMPTY cells"``.
        meaning: what that means, in words (may be empty).
        color: ``0xRRGGBB`` of its (first) layer.
        opacity: that layer's opacity.
        notes: what is drawn, from the layers' notes (e.g. ``"74,203, drawn as centre
            points"``).
        layers: the layer paths it covers.
        visible: whether it shows when the scene opens.
    """

    node: str
    label: str
    meaning: str
    color: int
    opacity: float
    notes: tuple[str, ...]
    layers: tuple[str, ...]
    visible: bool

    @property
    def css_color(self) -> str:
        """The colour as ``#rrggbb``."""
        return f"#{self.color:06x}"


def _meaning(path: str) -> tuple[str, str, str]:
    for node, label, meaning in _MEANINGS:
        if path == node or path.startswith(node + "/"):
            return node, label, meaning
    return path, path.rsplit("/", 1)[-1].replace("_", " "), ""


def legend(scene: Scene) -> list[Entry]:
    """The legend of ``scene``: one :class:`Entry` per group of its layers, in the order
    their first layers were added."""
    grouped: dict[str, list[str]] = {}
    named: dict[str, tuple[str, str]] = {}
    for path in scene.layers:
        node, label, meaning = _meaning(path)
        grouped.setdefault(node, []).append(path)
        named[node] = (label, meaning)
    entries = []
    for node, paths in grouped.items():
        first = scene.layers[paths[0]]
        notes = tuple(dict.fromkeys(n for p in paths if (n := scene.layers[p].note)))
        label, meaning = named[node]
        entries.append(Entry(node=node, label=label, meaning=meaning, color=first.color,
                             opacity=first.opacity, notes=notes, layers=tuple(paths),
                             visible=any(scene.is_visible(p) for p in paths)))
    return entries
