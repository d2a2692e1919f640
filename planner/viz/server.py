"""meshcat's server bound to one address: ``python -m planner.viz.server [--host H]``.

meshcat-python's ``ZMQWebSocketBridge`` binds its ZeroMQ socket to 127.0.0.1 but lets
tornado listen for browsers on every interface (``0.0.0.0`` and ``[::]``): anyone on the
network could watch the scene. This runs the same bridge with the web server listening on
``--host`` only (default 127.0.0.1) and prints the two lines meshcat's own server prints
(``zmq_url=...``, ``web_url=...``).

Entry point: :func:`start` (the server as a subprocess, its URLs).
"""

from __future__ import annotations

import argparse
import subprocess
import sys

__all__ = ["LOCALHOST", "start"]

LOCALHOST = "127.0.0.1"


def start(host: str = LOCALHOST) -> tuple[subprocess.Popen, str, str]:
    """Start the server; ``(process, zmq_url, web_url)`` once it listens.

    Raises:
        RuntimeError: the server exited before it listened (its last output said why).
    """
    process = subprocess.Popen([sys.executable, "-u", "-m", "planner.viz.server", "--host",
                                host], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               start_new_session=True)
    assert process.stdout is not None
    urls: dict[str, str] = {}
    while len(urls) < 2:
        line = process.stdout.readline().decode("utf-8", "replace").strip()
        if not line and process.poll() is not None:
            error = process.stderr.read().decode("utf-8", "replace").strip().splitlines() \
                if process.stderr is not None else []
            raise RuntimeError(f"the meshcat server exited with code {process.returncode}"
                               f"{': ' + error[-1] if error else ''}")
        key, _, value = line.partition("=")
        if key in ("zmq_url", "web_url"):
            urls[key] = value
    return process, urls["zmq_url"], urls["web_url"]


def _bridge(host: str):
    from ._meshcat import ZMQWebSocketBridge

    class BoundBridge(ZMQWebSocketBridge):
        """The bridge whose web server listens on ``host`` only."""

        def make_app(self):
            app = super().make_app()
            listen = app.listen
            app.listen = lambda port, **kw: listen(port, address=self.host, **kw)
            return app

    return BoundBridge(host=host)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default=LOCALHOST)
    bridge = _bridge(parser.parse_args().host)
    sys.stdout.write(f"zmq_url={bridge.zmq_url}\nweb_url={bridge.web_url}\n")
    sys.stdout.flush()
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
