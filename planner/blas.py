"""One BLAS thread while minkplan works: numpy's matrix products in minkplan are glue
(points against planes, inner dimension 3), where a threaded BLAS costs more than it
saves, and its threads spin on the cores the native core's workers need.

OpenBLAS, as numpy and scipy ship it, splits a product of a few thousand rows by a few
hundred columns over every core. On this project's 2-core machine, with another process
busy, the Factory round peg's offset (a few such products) took a median 13–42 ms with
that, 11–12 ms with one thread; the same 3456 × 3 by 3 × 722 product took 0.4 ms at best
and 12.5 ms at worst threaded, 0.9 ms and 5 ms on one thread.

:func:`one_blas_thread` sets every BLAS numpy and scipy load (threadpoolctl finds OpenBLAS,
MKL or BLIS) to one thread for a block and puts it back after, so a user's own numpy
work keeps its threads; :func:`single_blas_thread` is that for a whole function. Blocks
nest: the first to enter sets one thread, the last to leave puts the setting back (a count
under a lock, so nested calls cost nothing more). Calls on several threads at once share
that count, which is right for a process-wide setting; OpenBLAS's, set from a thread other
than the main one, does not always take there (measured), so such calls may run
threaded: run them in processes, as ``minkplan batch`` does. The controller is made once,
at import, after scipy's BLAS is loaded (about 5 ms: it reads the loaded libraries).
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, ParamSpec, TypeVar

import numpy as np  # noqa: F401  (loaded first: their BLAS is what the controller finds)
import scipy.linalg  # noqa: F401  (scipy ships a BLAS of its own)
from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread", "single_blas_thread"]

_CONTROLLER = ThreadpoolController()

_LOCK = threading.Lock()
_inside = 0
"""Blocks entered and not yet left, on any thread."""
_limiter: Any = None
"""The limit the first of them set (it restores the setting before it)."""

P = ParamSpec("P")
R = TypeVar("R")


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Every loaded BLAS on one thread inside the block (see the module documentation)."""
    global _inside, _limiter
    with _LOCK:
        if _inside == 0:
            _limiter = _CONTROLLER.limit(limits=1, user_api="blas")
        _inside += 1
    try:
        yield
    finally:
        with _LOCK:
            _inside -= 1
            if _inside == 0:
                _limiter.restore_original_limits()
                _limiter = None


def single_blas_thread(function: Callable[P, R]) -> Callable[P, R]:
    """``function`` run inside :func:`one_blas_thread`."""

    @functools.wraps(function)
    def wrapped(*args: P.args, **kwargs: P.kwargs) -> R:
        with one_blas_thread():
            return function(*args, **kwargs)

    return wrapped
