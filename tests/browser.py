"""Headless Chromium for the tests: screenshot a page, count pixels of a colour.

WebGL needs a renderer; with no GPU (and ``--disable-gpu``) Chromium draws WebGL with
SwiftShader, its CPU implementation, when asked with ``--use-angle=swiftshader
--enable-unsafe-swiftshader``; without those flags the canvas stays blank. The network
is cut (any host name resolves to nothing, QUIC off, no background traffic), so a page
that needed the network would fail to draw.

- :func:`chromium` -- the browser's path; raises with the install command if missing.
- :func:`screenshot` -- render a file or URL at ``size`` and write a PNG.
- :func:`pixels_like` -- how many pixels of an image have a colour's hue.

Debian's package is ``chromium`` (``apt-get install -y chromium``); set
``MINKPLAN_CHROMIUM`` to use another binary.
"""

from __future__ import annotations

import colorsys
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["INSTALL_HINT", "Shot", "chromium", "hsv", "pixels_like", "screenshot"]

INSTALL_HINT = ("headless Chromium is needed to check the meshcat scenes in a real browser: "
                "install Debian's package with `apt-get install -y chromium` (or set "
                "MINKPLAN_CHROMIUM to a Chromium/Chrome binary)")

FLAGS = (
    "--headless",
    "--no-sandbox",  # tests run as root in containers
    "--disable-gpu",
    "--use-angle=swiftshader",  # WebGL on the CPU ...
    "--enable-unsafe-swiftshader",  # ... which Chromium >= 139 only allows when asked
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-extensions",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
    "--mute-audio",
    "--enable-logging=stderr",  # the page's console messages, e.g. uncaught errors
    "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE localhost, EXCLUDE 127.0.0.1",
)


def chromium() -> str:
    """Path of the Chromium binary; ``RuntimeError`` with :data:`INSTALL_HINT` if none."""
    candidates = [os.environ.get("MINKPLAN_CHROMIUM"), "chromium", "chromium-browser",
                  "google-chrome", "google-chrome-stable"]
    for name in candidates:
        if name and (found := shutil.which(name)):
            return found
    raise RuntimeError(INSTALL_HINT)


@dataclass
class Shot:
    """A screenshot: ``png`` path, ``rgb`` ``(h, w, 3)`` uint8 pixels and the page's
    ``console`` messages (e.g. ``Uncaught TypeError: ...``)."""

    png: Path
    rgb: np.ndarray
    console: list[str]

    @property
    def errors(self) -> list[str]:
        return [m for m in self.console if "Uncaught" in m or "Error" in m]


def screenshot(page: str | os.PathLike[str], png: str | os.PathLike[str], *,
               size: tuple[int, int] = (800, 600), budget_ms: int = 4000,
               timeout: float = 120.0, extra_flags: tuple[str, ...] = ()) -> Shot:
    """Render ``page`` (a local file or an ``http://`` URL) in headless Chromium and write
    a ``size`` PNG to ``png`` once ``budget_ms`` of virtual time has passed (enough for
    meshcat to decode the scene and draw a frame); ``extra_flags`` go last.

    Raises ``RuntimeError`` (with Chromium's stderr) if no screenshot was written.
    """
    url = str(page) if str(page).startswith(("http://", "https://", "file://")) \
        else Path(page).resolve().as_uri()
    png = Path(png).resolve()
    png.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="minkplan-chromium-") as profile:
        args = [chromium(), *FLAGS, f"--user-data-dir={profile}",
                f"--window-size={size[0]},{size[1]}", f"--virtual-time-budget={budget_ms}",
                f"--screenshot={png}", *extra_flags, url]
        run = subprocess.run(args, capture_output=True, text=True, timeout=timeout,
                             stdin=subprocess.DEVNULL)
    if not png.is_file():
        raise RuntimeError(f"chromium wrote no screenshot (exit {run.returncode}):\n"
                           f"{run.stderr[-3000:]}")
    console = [line.split("CONSOLE", 1)[1].lstrip(":0123456789] ")
               for line in run.stderr.splitlines() if ":CONSOLE" in line]
    return Shot(png, load_rgb(png), console)


def load_rgb(png: str | os.PathLike[str]) -> np.ndarray:
    """``(h, w, 3)`` uint8 pixels of a PNG."""
    from PIL import Image

    with Image.open(png) as image:
        return np.asarray(image.convert("RGB"))


def hsv(rgb: np.ndarray) -> np.ndarray:
    """``(..., 3)`` hue in degrees, saturation and value in 0..1 of uint8 RGB pixels."""
    x = rgb.astype(np.float64) / 255.0
    r, g, b = x[..., 0], x[..., 1], x[..., 2]
    v = x.max(axis=-1)
    c = v - x.min(axis=-1)
    s = np.where(v > 0, c / np.where(v > 0, v, 1), 0.0)
    safe = np.where(c > 0, c, 1.0)
    h = np.select([c == 0, v == r, v == g],
                  [0.0, ((g - b) / safe) % 6.0, (b - r) / safe + 2.0],
                  (r - g) / safe + 4.0) * 60.0
    return np.stack([h, s, v], axis=-1)


def pixels_like(image: np.ndarray, color: int, *, hue_tolerance: float = 10.0,
                min_saturation: float = 0.45, min_value: float = 0.25) -> int:
    """Number of pixels whose hue is within ``hue_tolerance`` degrees of ``color``'s
    (``0xRRGGBB``), saturated and bright enough to be that colour shaded by the lights
    (not the grey background or grid)."""
    target = colorsys.rgb_to_hsv(((color >> 16) & 255) / 255, ((color >> 8) & 255) / 255,
                                 (color & 255) / 255)[0] * 360.0
    p = hsv(image)
    dh = np.abs((p[..., 0] - target + 180.0) % 360.0 - 180.0)
    return int(np.count_nonzero((dh <= hue_tolerance) & (p[..., 1] >= min_saturation)
                                & (p[..., 2] >= min_value)))
