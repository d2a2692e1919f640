"""The scene of an assembly result: the parts moving in one after another along their
insertion paths (or, without a sequence, assembled with the interlocked ones in red)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .scene import COLORS, Scene, node_name

if TYPE_CHECKING:
    from planner.assembly import AssemblyResult

__all__ = ["PART_COLORS", "scene_for_assembly"]


PART_COLORS = (0x2DA44E, 0x2F6FDE, 0xE6007E, 0x7E57C2, 0x00A3BF, 0xF2B705, 0x8D6E63,
               0xC62828)
"""Colours of the moving parts in the animation (cycled); fixed parts are orange."""


def scene_for_assembly(result: AssemblyResult, *, seconds_per_part: float = 3.0):
    """A meshcat :class:`~planner.viz.Scene` assembling the parts one after another.

    Every part is a layer ``assembly/<name>``. With a sequence, each part waits at the
    start of its insertion path (outside), then moves along it in its turn
    (``seconds_per_part`` each, in assembly order) and stays in place; the parts of a
    subassembly wait and move in together, already put together. Without one, the
    parts are shown assembled and the interlocked ones in red.
    """
    scene = Scene(f"{result.assembly.name}: {result.message}")
    steps = {name: s for s in result.removal for name in s.parts}
    turn = {label: i for i, label in enumerate(result.order)}
    for group in result.removal:  # a group's members move in its turn
        turn.update({name: turn.get(group.part, 0) for name in group.members})
    for k, part in enumerate(result.assembly.parts):
        step = steps.get(part.name)
        if part.name in result.interlocked:
            color = 0xD0021B
        elif step is None:
            color = COLORS["obstacle"]
        else:
            color = PART_COLORS[k % len(PART_COLORS)]
        path = f"assembly/{node_name(part.name)}"
        start = np.zeros(3) if step is None else step.insertion[0]
        transform = np.eye(4)
        transform[:3, 3] = start
        scene.add_mesh(path, part.mesh, color=color, transform=transform)
        if step is None or not result.found:
            continue
        waypoints = step.insertion
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(waypoints, axis=0),
                                                              axis=1))])
        t0 = turn[part.name] * seconds_per_part
        times = t0 + (arc / arc[-1] if arc[-1] > 0 else arc) * seconds_per_part
        scene.animate(path, np.concatenate([[0.0], times]),
                      np.vstack([waypoints[:1], waypoints]))
    scene.frame()
    return scene
