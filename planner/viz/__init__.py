"""Visualisation in meshcat: one scene layout for every entry point.

Build a :class:`Scene` (plain data: layers at paths of meshcat's scene tree), then show
it one of three ways:

- :func:`to_html` / :func:`write_html` -- one self-contained HTML file that renders with
  no network (meshcat's viewer is inlined);
- :func:`show` -- inline in a Jupyter notebook (the same page in an iframe);
- :func:`serve` -- meshcat's live server on localhost, URL printed, serving until
  interrupted (:func:`open_live` for a handle that does not block);
- :func:`write_glb` -- binary glTF of the same layers, for any 3D viewer
  (:mod:`planner.viz.glb`).

The page's legend (:func:`legend`) says what each colour is and what of it is drawn.

Scenes for minkplan's results: :func:`scene_for_minkowski`, :func:`scene_for_plan`
(scenario + plan + C-space + C-obstacles), :func:`scene_for_assembly` (the parts moving
in), :func:`as_scene` (anything :func:`show` accepts). The layout and its colours are
documented in :mod:`planner.viz.scene`; geometry-to-message conversion is
:mod:`planner.viz.lower`, kept apart from transport (:mod:`planner.viz.html`,
:mod:`planner.viz.live`).

Example::

    import planner, planner.viz
    result = planner.minkowski_sum(a, b)
    planner.viz.show(result, a=a, b=b)                       # notebook
    planner.viz.write_html(planner.viz.scene_for_minkowski(result, a, b), "sum.html")
"""

from .assembly import scene_for_assembly
from .glb import write_glb
from .html import notebook_html, show, to_html, write_html
from .layout import (
    as_scene,
    cells_from_cspace,
    compute_c_obstacles,
    plan_parts,
    roadmap_from_cspace,
    scene_for_minkowski,
    scene_for_plan,
)
from .legend import Entry, legend
from .live import LiveView, open_live, serve
from .lower import commands
from .scene import COLORS, Camera, Layer, Scene, Track

__all__ = [
    "COLORS",
    "Camera",
    "Entry",
    "Layer",
    "LiveView",
    "Scene",
    "Track",
    "as_scene",
    "cells_from_cspace",
    "commands",
    "compute_c_obstacles",
    "legend",
    "notebook_html",
    "open_live",
    "plan_parts",
    "roadmap_from_cspace",
    "scene_for_assembly",
    "scene_for_minkowski",
    "scene_for_plan",
    "serve",
    "show",
    "to_html",
    "write_glb",
    "write_html",
]
