"""Helpers shared by the benchmark scripts (next to them on ``sys.path`` when run)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def jsonable(x):
    """``x`` with numpy scalars and arrays, tuples and paths turned into JSON types."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, Path):
        return str(x)
    return x


def peak_mb() -> float:
    """This process's peak resident memory in MB (``VmHWM``: its own since its ``exec``,
    unlike ``ru_maxrss``, which keeps the forking parent's); NaN where there is no
    ``/proc``."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")
