"""OMPL planners as baselines: exact, re-validated paths; reproducible seeds; honest
statuses on impossible problems."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
import trimesh

from planner.validation import FclChecker, OmplPlanner, PlanStatus, available_planners

BOUNDS = [[-5.0, -5.0, -5.0], [5.0, 5.0, 5.0]]
START, GOAL = (-3.0, 0.0, 0.0), (3.0, 0.0, 0.0)


def box(extents, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return mesh


@pytest.fixture(scope="module")
def easy_checker() -> FclChecker:
    """A 2 x 2 x 2 block between start and goal: the straight line is blocked."""
    return FclChecker(box([1, 1, 1]), [box([2, 2, 2])], names=["block"])


@pytest.fixture(scope="module")
def sealed_checker() -> FclChecker:
    """The robot sealed in a box: a closed shell around a cavity."""
    cavity = box([2, 2, 2])
    cavity.invert()
    shell = trimesh.util.concatenate([box([4, 4, 4]), cavity])
    return FclChecker(box([1, 1, 1]), [shell], names=["shell"])


@pytest.mark.parametrize("name", ["RRTConnect", "prm", "BITSTAR"])
def test_planner_solves_easy_scene_with_revalidated_path(easy_checker, name):
    assert not easy_checker.check_path([START, GOAL]).valid
    planner = OmplPlanner(name, easy_checker, BOUNDS, seed=1)
    result = planner.solve(START, GOAL, time_limit=2.0)
    assert result.status is PlanStatus.FOUND and result.reason == "path", result.message
    assert result.solved
    wp = result.waypoints
    assert wp.ndim == 2 and wp.shape[1] == 3 and len(wp) >= 3
    np.testing.assert_allclose(wp[0], START)
    np.testing.assert_allclose(wp[-1], GOAL)
    check = easy_checker.check_path(wp)
    assert check.valid and check.min_clearance > 0
    assert result.length == pytest.approx(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum())
    assert result.length >= 6.0
    assert result.n_valid_checks > 0
    assert result.seconds < 10.0
    assert result.planner == planner.name


def test_rrtconnect_same_seed_same_path(easy_checker):
    def plan(seed):
        return OmplPlanner("RRTConnect", easy_checker, BOUNDS, seed=seed, simplify=False).solve(
            START, GOAL, 2.0
        )

    a, b, c = plan(7), plan(7), plan(8)
    assert a.solved and b.solved and c.solved
    np.testing.assert_array_equal(a.waypoints, b.waypoints)
    assert a.n_valid_checks == b.n_valid_checks
    assert a.waypoints.shape != c.waypoints.shape or not np.array_equal(a.waypoints, c.waypoints)


def test_checker_motion_validator_gives_exact_edges(easy_checker):
    planner = OmplPlanner("RRTConnect", easy_checker, BOUNDS, motion_validator="checker")
    result = planner.solve(START, GOAL, 2.0)
    assert result.solved
    assert easy_checker.check_path(result.waypoints).valid


@pytest.mark.parametrize("name", ["RRTConnect", "PRM", "BITstar"])
def test_sealed_robot_never_gets_a_path(sealed_checker, name):
    start, goal = (0.0, 0.0, 0.0), (4.0, 0.0, 0.0)
    assert sealed_checker.is_valid(start) and sealed_checker.is_valid(goal)
    result = OmplPlanner(name, sealed_checker, BOUNDS).solve(start, goal, time_limit=0.3)
    assert result.status is PlanStatus.NOT_FOUND  # OMPL proves nothing
    assert result.reason in ("time_limit", "approximate_solution", "planner_status")
    assert not result.solved
    assert result.waypoints.shape == (0, 3)
    assert result.seconds >= 0.25


def test_invalid_start_and_goal_are_statuses(easy_checker):
    planner = OmplPlanner("RRTConnect", easy_checker, BOUNDS)
    def answer(start, goal):
        result = planner.solve(start, goal, 1.0)
        return result.status, result.reason

    assert answer((0, 0, 0), GOAL) == (PlanStatus.NO_PATH, "start_in_collision")
    assert answer(START, (0.5, 0, 0)) == (PlanStatus.NO_PATH, "goal_in_collision")
    assert answer(START, (9, 0, 0)) == (PlanStatus.NOT_FOUND, "goal_out_of_bounds")


def test_unknown_planner_lists_available(easy_checker):
    with pytest.raises(ValueError) as err:
        OmplPlanner("NoSuchPlanner", easy_checker, BOUNDS)
    for name in ("RRTConnect", "PRM", "BITstar"):
        assert name in available_planners()
        assert name in str(err.value)


def test_bad_arguments_raise(easy_checker):
    with pytest.raises(ValueError):
        OmplPlanner("RRTConnect", easy_checker, BOUNDS, seed=-1)
    with pytest.raises(ValueError):
        OmplPlanner("RRTConnect", easy_checker, [[0, 0, 0], [-1, 1, 1]])
    with pytest.raises(ValueError):
        OmplPlanner("RRTConnect", easy_checker, BOUNDS).solve(START, GOAL, 0.0)


def test_no_nanobind_leak_warnings_at_exit():
    """OMPL objects must not outlive a call: nanobind would print leak warnings at exit
    (ompl 2.0.1 offers no switch for them)."""
    code = textwrap.dedent(
        """
        import trimesh
        from planner.validation import FclChecker, OmplPlanner, ompl_check_path
        robot = trimesh.creation.box(extents=[1, 1, 1])
        block = trimesh.creation.box(extents=[2, 2, 2])
        checker = FclChecker(robot, [block])
        bounds = [[-5, -5, -5], [5, 5, 5]]
        planner = OmplPlanner("RRTConnect", checker, bounds, motion_validator="checker")
        result = planner.solve((-3, 0, 0), (3, 0, 0), 1.0)
        assert result.solved, result
        assert ompl_check_path(result.waypoints, checker, bounds, simplify=True).valid
        print("done")
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "done"
    assert "leaked" not in proc.stderr, proc.stderr
    assert proc.stderr.strip() == "", proc.stderr
