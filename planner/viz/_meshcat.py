"""meshcat-python, imported once with its known import-time warning silenced.

``import meshcat`` imports ``zmq.eventloop.ioloop``, which pyzmq >= 17 deprecates with a
``DeprecationWarning`` at import (meshcat-python 0.3.2); under ``-W error`` (our test
suite) that would make ``import planner.viz`` fail. Every module of :mod:`planner.viz`
imports meshcat through here.
"""

from __future__ import annotations

import warnings

with warnings.catch_warnings():
    warnings.filterwarnings("ignore", message=r"zmq\.eventloop\.ioloop is deprecated",
                            category=DeprecationWarning)
    import meshcat
    from meshcat import geometry
    from meshcat.animation import Animation
    from meshcat.commands import Delete, SetAnimation, SetObject, SetProperty, SetTransform
    from meshcat.path import Path
    from meshcat.servers.zmqserver import ZMQWebSocketBridge
    from meshcat.visualizer import ViewerWindow, Visualizer

__all__ = [
    "Animation",
    "Delete",
    "Path",
    "SetAnimation",
    "SetObject",
    "SetProperty",
    "SetTransform",
    "ViewerWindow",
    "Visualizer",
    "ZMQWebSocketBridge",
    "geometry",
    "meshcat",
]
