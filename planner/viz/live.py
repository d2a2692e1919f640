"""Live transport: meshcat's server on localhost, fed the scene's commands.

- :func:`open_live` -- start meshcat's server (a subprocess: tornado + ZeroMQ, both
  listening on 127.0.0.1 only unless ``host`` says otherwise; :mod:`.server`), send it a
  scene, return a :class:`LiveView` (URL, ``update``, ``close``).
- :func:`serve` -- the same, print the URL and keep serving until interrupted (Ctrl+C)
  or until ``stop`` is set; then stop the server.

Browsers opening the URL get the whole scene (the server replays its scene tree to every
new connection); :meth:`LiveView.update` replaces the scene in every open browser.
"""

from __future__ import annotations

import collections
import contextlib
import sys
import threading
import time
from typing import TextIO

import zmq

from . import server
from ._meshcat import Delete, ViewerWindow, Visualizer
from ._meshcat import Path as MeshcatPath
from .lower import ROOT, commands
from .scene import Scene

__all__ = ["LiveView", "open_live", "serve"]

SEND_TIMEOUT_MS = 30_000


class LiveView:
    """A running meshcat server showing a scene.

    Attributes:
        url: the viewer's address (``http://127.0.0.1:<port>/static/``).
        zmq_url: the server's command socket.
        visualizer: meshcat-python's ``Visualizer`` connected to it.

    Not thread-safe: use it from one thread. A context manager: leaving it stops the
    server.
    """

    def __init__(self, visualizer: Visualizer, process) -> None:
        self.visualizer = visualizer
        self.process = process
        self.url: str = visualizer.url()
        self.zmq_url: str = visualizer.window.zmq_url
        # the server logs every connection to pipes nobody else reads: drain them (a
        # full pipe would block the server), keeping the last lines for error messages
        self.log: collections.deque[str] = collections.deque(maxlen=50)
        self._drains = [threading.Thread(target=self._drain, args=(stream,), daemon=True)
                        for stream in (process.stdout, process.stderr) if stream is not None]
        for thread in self._drains:
            thread.start()

    def _drain(self, stream) -> None:
        with contextlib.suppress(ValueError, OSError):
            for line in iter(stream.readline, b""):
                self.log.append(line.decode("utf-8", "replace").rstrip())

    def update(self, scene: Scene) -> None:
        """Replace the shown scene by ``scene``."""
        window = self.visualizer.window
        window.send(Delete(MeshcatPath((ROOT,))))
        window.send(Delete(MeshcatPath(("Lights", "Key"))))
        for command in commands(scene):
            window.send(command)

    @property
    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def close(self) -> None:
        """Stop the server (the subprocess this view started) and close the socket."""
        with contextlib.suppress(Exception):
            self.visualizer.window.zmq_socket.close(linger=0)
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        for thread in self._drains:  # they end at the pipes' EOF
            thread.join(timeout=5.0)
        for stream in (self.process.stdout, self.process.stderr):
            if stream is not None:
                stream.close()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<LiveView {self.url} {'running' if self.running else 'stopped'}>"


def _window(process, zmq_url: str, web_url: str) -> ViewerWindow:
    """meshcat's ``ViewerWindow`` for a server we started (its constructor would print
    the URL and leave a socket open)."""
    window = ViewerWindow.__new__(ViewerWindow)
    window.server_proc = process
    window.zmq_url = zmq_url
    window.web_url = web_url
    window.connect_zmq()
    # a dead server must raise (zmq.Again), not hang every later send
    window.zmq_socket.setsockopt(zmq.RCVTIMEO, SEND_TIMEOUT_MS)
    return window


def open_live(scene: Scene | None = None, *, host: str = server.LOCALHOST) -> LiveView:
    """Start meshcat's server, listening on ``host`` only (default 127.0.0.1: this
    machine), and show ``scene`` (if given) in it."""
    process, zmq_url, web_url = server.start(host)
    try:
        view = LiveView(Visualizer(window=_window(process, zmq_url, web_url)), process)
    except BaseException:
        process.kill()
        process.wait()
        raise
    if scene is not None:
        try:
            view.update(scene)
        except BaseException:
            view.close()
            raise
    return view


def serve(scene: Scene, *, out: TextIO | None = None, stop: threading.Event | None = None,
          poll: float = 0.5, host: str = server.LOCALHOST) -> str:
    """Serve ``scene`` live on localhost until interrupted; returns the URL it served.

    Prints ``minkplan: serving <title> at <url> (Ctrl+C to stop)`` to ``out`` (default
    stdout), then blocks until KeyboardInterrupt or until ``stop`` is set, and stops
    the server either way. Raises ``RuntimeError`` if the server dies meanwhile.
    """
    out = sys.stdout if out is None else out
    view = open_live(scene, host=host)
    try:
        out.write(f"minkplan: serving {scene.title!r} at {view.url} (Ctrl+C to stop)\n")
        out.flush()
        while stop is None or not stop.is_set():
            if not view.running:
                log = "\n".join(view.log)
                raise RuntimeError(f"the meshcat server exited (code {view.process.returncode})"
                                   f"{': ' + log if log else ''}")
            time.sleep(poll)
    except KeyboardInterrupt:
        pass
    finally:
        view.close()
    return view.url
