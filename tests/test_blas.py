"""One BLAS thread while minkplan works (planner/blas.py), and the user's setting back
after."""

import numpy as np
import pytest
import trimesh
from threadpoolctl import ThreadpoolController, threadpool_info

import planner
from planner.blas import one_blas_thread, single_blas_thread


def _numpy_blas_threads() -> list[int]:
    """Threads of every BLAS loaded (numpy's among them)."""
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


@pytest.fixture
def two_blas_threads():
    """Every loaded BLAS on two threads for the test (this machine may have fewer cores,
    which OpenBLAS allows), put back after."""
    controller = ThreadpoolController()
    with controller.limit(limits=2, user_api="blas"):
        yield


def test_numpy_has_a_blas_the_controller_can_set():
    assert _numpy_blas_threads(), "numpy's BLAS is not visible to threadpoolctl"


def test_one_thread_inside_the_block_and_the_users_setting_after(two_blas_threads):
    assert set(_numpy_blas_threads()) == {2}
    with one_blas_thread():
        assert set(_numpy_blas_threads()) == {1}
        with one_blas_thread():
            assert set(_numpy_blas_threads()) == {1}
        assert set(_numpy_blas_threads()) == {1}
    assert set(_numpy_blas_threads()) == {2}


def test_a_wrapped_function_runs_on_one_thread_and_raises_through(two_blas_threads):
    seen: list[list[int]] = []

    @single_blas_thread
    def work(fail: bool) -> int:
        seen.append(_numpy_blas_threads())
        if fail:
            raise ValueError("boom")
        return 7

    assert work(False) == 7
    with pytest.raises(ValueError, match="boom"):
        work(True)
    assert [set(s) for s in seen] == [{1}, {1}]
    assert set(_numpy_blas_threads()) == {2}


@pytest.mark.parametrize("name", ["offset", "opening", "closing", "penetration_depth",
                                  "minkowski_sum", "c_obstacle", "plan", "plan_assembly",
                                  "validate_solid", "repair_mesh", "decompose"])
def test_the_public_functions_that_compute_are_wrapped(name):
    assert getattr(getattr(planner, name), "__wrapped__", None) is not None


def test_an_offset_computes_on_one_thread(two_blas_threads, monkeypatch):
    import planner.offsets

    seen: list[list[int]] = []
    inner = planner.offsets._offset_unwarned

    def spying(*args, **kwargs):
        seen.append(_numpy_blas_threads())
        return inner(*args, **kwargs)

    monkeypatch.setattr(planner.offsets, "_offset_unwarned", spying)
    planner.offset(trimesh.creation.box((1.0, 0.6, 0.4)), 0.1, eps=0.02)
    assert [set(s) for s in seen] == [{1}]


def test_an_offset_leaves_the_users_blas_threads_as_they_were(two_blas_threads):
    grown = planner.offset(trimesh.creation.box((1.0, 0.6, 0.4)), 0.1, eps=0.02)
    assert len(grown.mesh.faces) > 0
    assert set(_numpy_blas_threads()) == {2}
    np.ones((200, 3)) @ np.ones((3, 200))  # numpy still works with them
