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


def test_a_plan_whose_whole_bounds_cspace_passes_the_limit_ends_near_it():
    # two dense spheres taken as surfaces (every triangle pair a boundary candidate): the
    # whole bounds' C-space takes seconds to build, and the plan's one clock (started
    # after loading) stops it from inside
    import planner
    from planner.planning import OctreeParams
    from planner.problem import Body, PlannerSettings, Robot, Scenario

    ball = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    small = trimesh.creation.icosphere(subdivisions=4, radius=0.4)
    scenario = Scenario(name="dense", units="m",
                        robot=Robot("ball", small, "test", solid=False, kind_reason="test"),
                        obstacles=[Body("sphere", ball, "test", solid=False, kind_reason="test")],
                        start=[-2.5, 0, 0], goal=[2.5, 0, 0], orientation=np.eye(3),
                        bounds=(BOUNDS[0], BOUNDS[1]), settings=PlannerSettings(time_limit=0.3))
    skip = OctreeParams(local_first_pairs=10**12, direct_first_pairs=10**12)
    t0 = time.perf_counter()
    outcome = planner.plan(scenario, params=skip, progress=False)
    seconds = time.perf_counter() - t0
    assert outcome.status == "not_found" and outcome.reason == "time_limit", outcome.message
    assert "while the C-space over the whole bounds was built" in outcome.message
    assert seconds < 20, seconds  # loading and the checker, not the build's own time


INTERRUPTED_OFFSET = """
import os, signal, sys, threading, time
import trimesh
import planner
# Python's own Ctrl+C handler, also where SIGINT came in ignored (a background job)
signal.signal(signal.SIGINT, signal.default_int_handler)
solid = trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=96,
                               minor_sections=48)
signal_at = []

def interrupt():
    signal_at.append(time.perf_counter())
    os.kill(os.getpid(), signal.SIGINT)

beside = []   # with a third argument: the same offset in another thread, started 1 s before

def offset_beside():
    try:
        planner.offset(solid, 0.2, eps=float(sys.argv[2]), method="cells")
        beside.append("finished")
    except KeyboardInterrupt as stop:
        beside.append("cancelled" if "cancelled" in str(stop) else "other")

companion = threading.Thread(target=offset_beside)
if len(sys.argv) > 3:
    companion.start()
    time.sleep(1.0)
timer = threading.Timer(float(sys.argv[1]), interrupt)
timer.daemon = True
timer.start()
start = time.perf_counter()
try:
    planner.offset(solid, 0.2, eps=float(sys.argv[2]), method="cells")
    print("finished", time.perf_counter() - start)
except KeyboardInterrupt:
    stopped = time.perf_counter()
    after = planner.offset(solid, 0.2, eps=0.2, method="cells")   # not left cancelled
    if len(sys.argv) > 3:
        companion.join()
    print("interrupted", stopped - signal_at[0], stopped - start, len(after.mesh.faces), *beside)
"""


def _offset_run(delay: float, eps: float, *, beside: bool = False) -> list[str]:
    import subprocess  # noqa: PLC0415
    import sys  # noqa: PLC0415

    args = [str(delay), str(eps)] + (["beside"] if beside else [])
    done = subprocess.run([sys.executable, "-c", INTERRUPTED_OFFSET, *args],
                          capture_output=True, text=True, timeout=300, check=True)
    return done.stdout.split()


def test_ctrl_c_stops_a_long_native_offset_and_the_next_one_runs():
    """Ctrl+C reaches the native work (the binding checks Python's signals while it runs
    and cancels it): the interrupt comes well before the offset would have finished, and
    a later offset in the same process runs to its end."""
    whole = _offset_run(1e6, 0.02)                     # no interrupt: how long it takes
    assert whole[0] == "finished"
    seconds = float(whole[1])
    assert seconds > 3.0, f"the offset takes {seconds:.1f} s: too short to interrupt"
    out = _offset_run(0.3, 0.02)
    assert out[0] == "interrupted", out
    assert float(out[2]) < 0.5 * seconds, f"stopped after {out[2]} s of {seconds:.1f} s"
    assert int(out[3]) > 0


def test_ctrl_c_in_one_call_fails_the_native_call_it_stopped_in_another_thread():
    """The cancel is one flag for the process: an offset running in another thread when
    Ctrl+C stops the main thread's stops too, and raises rather than return half a
    surface."""
    out = _offset_run(2.0, 0.02, beside=True)  # both in their native builds by then
    assert out[0] == "interrupted", out
    assert out[4:] == ["cancelled"], out
