"""The plan's time limit inside the native core: builds and refinements of a C-space stop
at it with TimeLimitError and change nothing (planner.deadline)."""

from __future__ import annotations

import time

import numpy as np
import pytest
import trimesh

from planner._minkowski_core import CSpace
from planner.deadline import Deadline, native_deadline
from planner.errors import TimeLimitError

BOUNDS = np.array([[-3.0, -3, -3], [3.0, 3, 3]])


def arrays(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)


def torus_space() -> CSpace:
    torus = trimesh.creation.torus(major_radius=1.5, minor_radius=0.5)
    cube = trimesh.creation.box(extents=[0.3, 0.3, 0.3])
    return CSpace.exact([arrays(torus)], arrays(cube), BOUNDS, 6 / 256, 6 / 16)


def test_a_build_started_after_the_deadline_stops_and_one_after_it_runs():
    with native_deadline(time.perf_counter()), pytest.raises(TimeLimitError,
                                                            match="during the octree build"):
        torus_space()
    assert len(torus_space()) > 0  # cleared on leaving


def test_a_stopped_refinement_changes_nothing():
    cs = torus_space()
    leaves = cs.leaves()
    mixed = np.flatnonzero(leaves["label"] == 2)
    assert len(mixed) > 0
    with native_deadline(time.perf_counter() - 1.0), pytest.raises(TimeLimitError,
                                                                   match="refinement"):
        cs.refine(mixed.tolist(), ring=False, levels=1)
    after = cs.leaves()
    assert len(cs) == len(leaves["label"])
    np.testing.assert_array_equal(after["label"], leaves["label"])
    stats = cs.refine(mixed.tolist(), ring=False, levels=1)  # no deadline: it runs
    assert stats["refined"] == len(mixed)


def test_the_deadline_is_cleared_even_when_the_step_fails():
    with pytest.raises(RuntimeError), Deadline(time.perf_counter() - 1.0).native():
        raise RuntimeError("a failing step")
    assert len(torus_space()) > 0


def test_an_inner_block_keeps_the_earlier_deadline_and_gives_back_the_outer_one():
    far = time.perf_counter() + 3600
    with native_deadline(time.perf_counter() - 1.0):
        with native_deadline(far), pytest.raises(TimeLimitError):
            torus_space()  # the outer, earlier deadline holds inside
        with pytest.raises(TimeLimitError):
            torus_space()  # and again after the inner block
    with native_deadline(far):
        with native_deadline(time.perf_counter() - 1.0), pytest.raises(TimeLimitError):
            torus_space()
        assert len(torus_space()) > 0  # the outer, far deadline is back
