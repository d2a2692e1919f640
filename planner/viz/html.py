"""Static transport: a scene as ONE self-contained HTML file, and inline in notebooks.

The page inlines meshcat's viewer bundle (``meshcat/viewer/dist/main.min.js``, three.js
included) and the scene's msgpack commands as base64 strings decoded synchronously
(meshcat's own ``static_html()`` needs a running server and ``fetch``es ``data:`` URLs;
this needs neither). Nothing is loaded from the network: no ``src``/``href`` attributes,
no URLs. When every command has been applied the page sets ``window.minkplanReady`` and
``<body data-minkplan-ready="N">`` (N commands), which tests wait for.

- :func:`to_html` -- the page as a string.
- :func:`write_html` -- write it atomically (a killed run never leaves half a file).
- :func:`notebook_html` / :func:`show` -- the page in an ``<iframe srcdoc>`` for Jupyter.
"""

from __future__ import annotations

import base64
import functools
import html as html_lib
import os
import tempfile
from pathlib import Path

from ._meshcat import meshcat
from .lower import packed
from .scene import Scene

__all__ = ["notebook_html", "show", "to_html", "viewer_js", "write_html"]


@functools.lru_cache(maxsize=1)
def viewer_js() -> str:
    """meshcat's viewer bundle, safe to inline in a ``<script>`` element."""
    path = Path(meshcat.__file__).resolve().parent / "viewer" / "dist" / "main.min.js"
    source = path.read_text(encoding="utf-8")
    # a literal "</script" would end the inline element early
    return source.replace("</script", "<\\/script").replace("<!--", "<\\!--")


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
body {{ margin: 0; overflow: hidden; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script>
{viewer}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
(function () {{
  var commands = [
{commands}
  ];
  for (var i = 0; i < commands.length; i++) {{
    var text = atob(commands[i]);
    var bytes = new Uint8Array(text.length);
    for (var j = 0; j < text.length; j++) bytes[j] = text.charCodeAt(j);
    viewer.handle_command_bytearray(bytes);
  }}
  window.minkplanReady = true;
  document.body.setAttribute("data-minkplan-ready", String(commands.length));
}})();
</script>
</body>
</html>
"""


def to_html(scene: Scene) -> str:
    """``scene`` as one self-contained HTML page (meshcat's viewer inlined; no network).

    The page is interactive: orbit/pan/zoom with the mouse, toggle every layer under
    "Open Controls" > Scene > meshcat, play the robot's motion under Animations.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"to_html: expected a planner.viz.Scene, got {type(scene).__name__} "
                        f"(planner.viz.as_scene converts results)")
    encoded = ",\n".join(f'    "{base64.b64encode(c).decode("ascii")}"' for c in packed(scene))
    return _PAGE.format(title=html_lib.escape(scene.title), viewer=viewer_js(),
                        commands=encoded)


def write_html(scene: Scene, path: str | os.PathLike[str]) -> Path:
    """Write :func:`to_html` of ``scene`` to ``path`` atomically; returns the path.

    The page goes to a temporary file in the same directory, is flushed to disk and then
    renamed over ``path``, so readers see the old file or the whole new one.
    """
    target = Path(path)
    text = to_html(scene)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return target


def notebook_html(scene: Scene, height: int = 480) -> str:
    """The page inside an ``<iframe srcdoc>`` of ``height`` pixels, for notebook output
    (works wherever the kernel runs: nothing is served)."""
    srcdoc = html_lib.escape(to_html(scene), quote=True)
    return (f'<div style="height: {int(height)}px; width: 100%; resize: both; '
            f'overflow: hidden"><iframe srcdoc="{srcdoc}" '
            f'style="width: 100%; height: 100%; border: none"></iframe></div>')


class _InlineScene:
    """What :func:`show` displays: renders as the scene's HTML in Jupyter."""

    def __init__(self, scene: Scene, height: int):
        self.scene = scene
        self.height = height

    def _repr_html_(self) -> str:
        return notebook_html(self.scene, self.height)

    def __repr__(self) -> str:
        return repr(self.scene)


def show(obj, *, height: int = 480, **kwargs) -> None:
    """Render ``obj`` inline in a Jupyter notebook (returns ``None``, so a trailing
    ``show(...)`` does not render twice; :func:`planner.viz.as_scene` gives the scene).

    ``obj`` is anything :func:`planner.viz.as_scene` accepts (a ``Scene``, a
    ``MinkowskiResult``, a mesh, a ``Scenario``, a ``PlanOutcome`` with
    ``scenario=...``); ``kwargs`` go to it. Outside IPython the scene's summary is
    displayed instead (IPython's plain-text fallback).
    """
    from IPython.display import display

    from .layout import as_scene

    display(_InlineScene(as_scene(obj, **kwargs), height))
