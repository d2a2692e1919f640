"""The planner in OMPL's roles: one status vocabulary for minkplan and the OMPL
baselines, the octree planner's setup and solve, the native C-space as a validity checker
and motion validator (OMPL's planners run on it), and the one loader of problem files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import planner
from planner.io import load_problem
from planner.planning import CSpaceChecker, OctreePlanner
from planner.roles import MotionValidator, PlanStatus, StateValidityChecker
from planner.validation import FclChecker, OmplPlanner

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def test_one_status_vocabulary_with_the_json_strings():
    assert [str(s) for s in PlanStatus] == ["found", "no_path", "not_found"]
    assert PlanStatus.NO_PATH == "no_path"  # path.json's strings, as before


def test_the_octree_planner_sets_up_once_and_solves():
    scenario = planner.load_scenario(SCENARIOS / "peg_in_hole.yaml")
    octree = OctreePlanner(scenario, progress=False)
    octree.setup()
    assert octree.cspace is not None and octree.source is not None
    outcome = octree.solve()
    assert outcome.status is PlanStatus.FOUND and outcome.reason == "path"
    assert outcome.source is octree.source
    sealed = OctreePlanner(planner.load_scenario(SCENARIOS / "sealed_chamber.yaml"),
                           progress=False).solve()  # solve sets up when needed
    assert sealed.status is PlanStatus.NO_PATH and sealed.certificate["verified"]


def test_the_native_cspace_is_a_validity_checker_and_motion_validator():
    scenario = planner.load_scenario(SCENARIOS / "peg_in_hole.yaml")
    octree = OctreePlanner(scenario, progress=False)
    octree.setup()
    checker = CSpaceChecker(octree.cspace)
    assert isinstance(checker, StateValidityChecker) and isinstance(checker, MotionValidator)
    fcl = FclChecker(scenario.robot.mesh, [b.mesh for b in scenario.obstacles])
    rng = np.random.default_rng(0)
    lo, hi = scenario.bounds
    for t in rng.uniform(lo, hi, size=(300, 3)):
        assert checker.is_valid(t) == fcl.is_valid(t), t
    start, goal = np.asarray(scenario.start), np.asarray(scenario.goal)
    ok, fraction = checker.check_motion(start, start + np.array([0.0, 0.0, 5.0]))
    assert ok and fraction is None
    ok, fraction = checker.check_motion(start, goal + np.array([30.0, 0.0, 0.0]))
    assert not ok and 0.0 <= fraction < 1.0
    last = start + fraction * (goal + np.array([30.0, 0.0, 0.0]) - start)
    assert checker.is_valid(last) and fcl.is_valid(last)
    # OMPL's planner on minkplan's C-space, every edge checked exactly by it
    result = OmplPlanner("RRTConnect", checker, np.stack(scenario.bounds),
                         motion_validator="checker").solve(start, goal, 10.0)
    assert result.status is PlanStatus.FOUND
    assert fcl.check_path(result.waypoints).valid


def test_load_problem_dispatches_on_the_file(tmp_path):
    scenario = load_problem(SCENARIOS / "peg_in_hole.yaml")
    assert isinstance(scenario, planner.Scenario)
    assembly = load_problem(SCENARIOS / "assemblies" / "peg_in_block.yaml")
    assert isinstance(assembly, planner.Assembly)
    (tmp_path / "p.txt").write_text("robot: {box: [1, 1, 1]}\n")
    with pytest.raises(planner.ScenarioError, match=r"p.txt: unknown problem file type '.txt'"):
        load_problem(tmp_path / "p.txt")


def test_a_cspace_over_budget_is_refused_naming_the_problem():
    """The core refuses an octree whose records would not fit (RecordLimit); the planner
    says which problem, which source and at what cell size, as one ResourceLimitError."""
    from planner.errors import ResourceLimitError
    from planner.sources import ExactSource, SourceSettings

    class OverBudget(ExactSource):  # isolates the planner's handling of the refusal
        def cspace(self, *args, **kwargs):
            raise ResourceLimitError("the octree's boundary cells would keep more than "
                                     "4.0 GiB of candidate records")

    path = SCENARIOS / "peg_in_hole.yaml"
    refusing = OverBudget(SourceSettings(exact="true"), "test")
    octree = OctreePlanner(planner.load_scenario(path), source=refusing, progress=False)
    with pytest.raises(ResourceLimitError) as refused:
        octree.setup()
    message = str(refused.value)
    assert message.startswith(str(path.resolve())) and "exact source" in message
    assert "--memory-limit" in message and "4.0 GiB" in message
    assert octree.cspace is None


def test_the_outcome_holds_the_cspace_its_answer_is_about():
    """A no-path found with the clearance margin is searched again without it; the
    certificate, and the C-space the outcome carries (the one the viz draws), are that
    second one's."""
    import dataclasses

    scenario = planner.load_scenario(SCENARIOS / "sealed_chamber.yaml")
    settings = dataclasses.replace(scenario.settings, clearance=0.5)
    octree = OctreePlanner(dataclasses.replace(scenario, settings=settings), progress=False)
    outcome = octree.solve()
    assert outcome.status is PlanStatus.NO_PATH and outcome.certificate["verified"]
    assert octree.cspace.margin > 0  # the first C-space, with the margin
    assert outcome.cspace is not octree.cspace and outcome.cspace.margin == 0
