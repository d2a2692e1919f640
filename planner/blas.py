"""One BLAS thread while minkplan works: numpy's matrix products in minkplan are glue
(points against planes, inner dimension 3), where a threaded BLAS costs more than it
saves, and its threads spin on the cores the native core's workers need.

OpenBLAS, as numpy and scipy ship it, splits a product of a few thousand rows by a few
hundred columns over every core. On this project's 2-core machine, with another process
busy, the Factory round peg's offset (a few such products) took a median 13–42 ms with
that, 11–12 ms with one thread; the same 3456 × 3 by 3 × 722 product took 0.4 ms at best
and 12.5 ms at worst threaded, 0.9 ms and 5 ms on one thread.

:func:`one_blas_thread` sets every BLAS numpy has loaded (threadpoolctl finds OpenBLAS,
MKL or BLIS) to one thread for a block and puts it back after, so a user's own numpy
work keeps its threads; :func:`single_blas_thread` is that for a whole function. The
controller is made once, at import (about 5 ms: it reads the loaded libraries).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import ParamSpec, TypeVar

import numpy as np  # noqa: F401  (loaded first: its BLAS is what the controller finds)
from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread", "single_blas_thread"]

_CONTROLLER = ThreadpoolController()

P = ParamSpec("P")
R = TypeVar("R")


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Every loaded BLAS on one thread inside the block (nested blocks are fine)."""
    with _CONTROLLER.limit(limits=1, user_api="blas"):
        yield


def single_blas_thread(function: Callable[P, R]) -> Callable[P, R]:
    """``function`` run inside :func:`one_blas_thread`."""

    @functools.wraps(function)
    def wrapped(*args: P.args, **kwargs: P.kwargs) -> R:
        with one_blas_thread():
            return function(*args, **kwargs)

    return wrapped
