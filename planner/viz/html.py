"""Static transport: a scene as ONE self-contained HTML file, and inline in notebooks.

The page inlines meshcat's viewer bundle (``meshcat/viewer/dist/main.min.js``, three.js
included) and the scene's msgpack commands, deflated and base64-encoded
(:func:`encode_commands`), inflated by the browser's ``DecompressionStream`` (meshcat's own
``static_html()`` needs a running server and ``fetch``es ``data:`` URLs; this needs
neither). The layers created hidden (cells, roadmap: most of a scene's bytes) are separate
strings, inflated only when switched on in the legend, a panel saying what each colour is
and what of it is drawn (:mod:`planner.viz.legend`). Nothing is loaded from the network:
no ``src``/``href`` attributes, no URLs. When the scene is built the page sets
``window.minkplanReady`` and ``<body data-minkplan-ready="N">`` (N commands), which tests
wait for; on failure ``data-minkplan-error`` says why (and the legend shows it).

- :func:`to_html` -- the page as a string.
- :func:`write_html` -- write it atomically (a killed run never leaves half a file).
- :func:`notebook_html` / :func:`show` -- the page in an ``<iframe srcdoc>`` for Jupyter.
"""

from __future__ import annotations

import base64
import functools
import html as html_lib
import json
import os
import struct
import tempfile
import zlib
from pathlib import Path

import umsgpack

from ._meshcat import meshcat
from .legend import legend
from .lower import staged_commands
from .scene import Scene

__all__ = ["decode_commands", "encode_commands", "notebook_html", "show", "to_html",
           "viewer_js", "write_html"]


@functools.lru_cache(maxsize=1)
def viewer_js() -> str:
    """meshcat's viewer bundle, safe to inline in a ``<script>`` element."""
    path = Path(meshcat.__file__).resolve().parent / "viewer" / "dist" / "main.min.js"
    source = path.read_text(encoding="utf-8")
    # a literal "</script" would end the inline element early
    return source.replace("</script", "<\\/script").replace("<!--", "<\\!--")


_STYLE = """
body { margin: 0; overflow: hidden; font: 12px/1.35 system-ui, sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#minkplan-legend { position: fixed; left: 6px; top: 6px; max-width: 250px; max-height: 92vh;
  overflow: auto; background: rgba(255, 255, 255, 0.85); border-radius: 4px;
  padding: 2px 6px; box-shadow: 0 1px 3px rgba(0, 0, 0, 0.25); color: #222; font-size: 11px; }
#minkplan-legend summary { font-weight: 600; cursor: pointer; }
#minkplan-legend label { display: block; margin: 2px 0; cursor: pointer; }
#minkplan-legend input { margin: 0 2px 0 0; vertical-align: -2px; }
#minkplan-legend .swatch { display: inline-block; width: 10px; height: 10px;
  vertical-align: -1px; margin-right: 4px; border: 1px solid rgba(0, 0, 0, 0.35); }
#minkplan-legend .notes, #minkplan-legend .help { color: #555; font-size: 10px; }
#minkplan-legend .notes { margin-left: 30px; }
#minkplan-status:empty { display: none; }
#minkplan-status { color: #b00020; font-weight: 600; }
"""

_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>{style}</style>
</head>
<body>
<div id="meshcat-pane"></div>
{legend}
<script>
if (innerWidth < LEGEND_MIN_WIDTH || innerHeight < LEGEND_MIN_HEIGHT) {{
  document.querySelector("#minkplan-legend details").open = false;  // a small view
}}
</script>
<script>
{viewer}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var minkplan = (function () {{
  var atOnce = "{at_once}";
  var onDemand = {on_demand};
  var status = document.getElementById("minkplan-status");
  var loads = {{}};
  function fail(what, err) {{
    status.textContent = what;
    document.body.setAttribute("data-minkplan-error", what);
    console.error("minkplan: " + what + (err ? ": " + err : ""));
  }}
  function inflate(text64) {{
    var text = atob(text64), bytes = new Uint8Array(text.length);
    for (var j = 0; j < text.length; j++) bytes[j] = text.charCodeAt(j);
    var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    return new Response(stream).arrayBuffer();
  }}
  function run(buffer) {{  // [uint32 little-endian size, msgpack command] ...
    var view = new DataView(buffer), bytes = new Uint8Array(buffer), n = 0;
    for (var at = 0; at < bytes.length; n++) {{
      var size = view.getUint32(at, true);
      viewer.handle_command_bytearray(bytes.slice(at + 4, at + 4 + size));
      at += 4 + size;
    }}
    return n;
  }}
  function load(path) {{
    if (!(path in loads)) {{
      status.textContent = "loading " + path + " ...";
      loads[path] = inflate(onDemand[path]).then(run).then(function (n) {{
        status.textContent = "";
        return n;
      }});
    }}
    return loads[path];
  }}
  function show(node, visible) {{
    viewer.handle_command({{type: "set_property", path: "/meshcat/" + node,
                            property: "visible", value: visible}});
  }}
  function toggle(box) {{
    var needed = box.checked ? JSON.parse(box.getAttribute("data-load")) : [];
    return Promise.all(needed.map(load)).then(function () {{
      show(box.getAttribute("data-node"), box.checked);
    }}).catch(function (err) {{ fail("could not load " + box.getAttribute("data-node"), err); }});
  }}
  var boxes = document.querySelectorAll("#minkplan-legend input[data-node]");
  for (var i = 0; i < boxes.length; i++) {{
    boxes[i].addEventListener("change", function (event) {{ toggle(event.target); }});
  }}
  if (typeof DecompressionStream === "undefined") {{
    fail("this browser cannot decompress the scene (needs DecompressionStream: Chrome 80, " +
         "Firefox 113, Safari 16.4 or later)");
    return {{}};
  }}
  inflate(atOnce).then(run).then(function (n) {{
    window.minkplanReady = true;
    document.body.setAttribute("data-minkplan-ready", String(n));
  }}).catch(function (err) {{ fail("could not build the scene", err); }});
  return {{load: load, show: show, toggle: toggle}};
}})();
</script>
</body>
</html>
"""


COMPRESSION_LEVEL = 6
"""zlib's level for the page's commands: 9 is 4 times slower for 1% less."""

LEGEND_OPEN_AT = (900, 500)
"""The legend opens unfolded in a view at least this wide and high (CSS pixels); in a
smaller one (a notebook's cell) it starts folded, one line to click."""


def encode_commands(commands: list[bytes]) -> str:
    """msgpack-encoded ``commands`` as the page carries them: each prefixed by its size
    (uint32, little-endian), all deflated (zlib) and base64-encoded."""
    framed = b"".join(struct.pack("<I", len(c)) + c for c in commands)
    return base64.b64encode(zlib.compress(framed, COMPRESSION_LEVEL)).decode("ascii")


def decode_commands(text: str) -> list[bytes]:
    """The msgpack commands of one :func:`encode_commands` string."""
    framed = zlib.decompress(base64.b64decode(text))
    out, at = [], 0
    while at < len(framed):
        (size,) = struct.unpack_from("<I", framed, at)
        out.append(framed[at + 4:at + 4 + size])
        at += 4 + size
    return out


def _legend_html(scene: Scene, later: set[str]) -> str:
    rows = []
    for entry in legend(scene):
        load = [p for p in entry.layers if p in later]
        notes = list(entry.notes) + (["loaded when switched on"] if load else [])
        r, g, b = (entry.color >> 16) & 255, (entry.color >> 8) & 255, entry.color & 255
        swatch = f"rgba({r}, {g}, {b}, {max(entry.opacity, 0.35):.2f})"
        rows.append(
            f'<label title="{html_lib.escape(entry.meaning)}">'
            f'<input type="checkbox" data-node="{html_lib.escape(entry.node)}" '
            f"data-load='{html_lib.escape(json.dumps(load))}'"
            f'{" checked" if entry.visible else ""}>'
            f'<span class="swatch" style="background: {swatch}"></span>'
            f"{html_lib.escape(entry.label)}"
            + (f'<div class="notes">{html_lib.escape("; ".join(notes))}</div>' if notes else "")
            + "</label>")
    return ('<div id="minkplan-legend"><details open><summary>'
            f"Legend: {html_lib.escape(scene.title)}</summary>\n" + "\n".join(rows)
            + '\n<div class="help">hover a row for its meaning; drag: orbit, right-drag: '
            "pan, wheel: zoom; Open Controls: every layer, the animation</div>"
            '<div id="minkplan-status"></div></details></div>')


def to_html(scene: Scene) -> str:
    """``scene`` as one self-contained HTML page (meshcat's viewer inlined; no network).

    The page is interactive: orbit/pan/zoom with the mouse, switch layers in the legend
    (or under "Open Controls" > Scene > meshcat), play the robot's motion under
    Animations. The scene's commands are deflated; the hidden layers (cells, roadmap)
    are decoded only when switched on in the legend.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"to_html: expected a planner.viz.Scene, got {type(scene).__name__} "
                        f"(planner.viz.as_scene converts results)")
    at_once, later = staged_commands(scene)
    on_demand = {path: encode_commands([umsgpack.packb(c.lower()) for c in created])
                 for path, created in later.items()}
    page = _PAGE.replace("LEGEND_MIN_WIDTH", str(LEGEND_OPEN_AT[0]))
    page = page.replace("LEGEND_MIN_HEIGHT", str(LEGEND_OPEN_AT[1]))
    return page.format(title=html_lib.escape(scene.title), style=_STYLE,
                        legend=_legend_html(scene, set(later)), viewer=viewer_js(),
                        at_once=encode_commands([umsgpack.packb(c.lower()) for c in at_once]),
                        on_demand=json.dumps(on_demand))


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
