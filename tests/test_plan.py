"""The planner on every bundled scenario: expected answers, every found path re-checked by
an independent FCL checker, the no-path certificate re-checked cell by cell, collisions
named, determinism, clearance, OMPL baselines."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from planner._minkowski_core import CSpace, Primitives
from planner.decompose import decompose
from planner.io import load_scenario
from planner.planning import FOUND, NO_PATH, NOT_FOUND, OctreeParams, plan
from planner.validation import FclChecker

try:  # tests/ as a package or as a plain directory on sys.path
    from . import oracle
except ImportError:
    import oracle

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"

EXPECTED = {
    "peg_in_hole": FOUND,
    "peg_in_hole_0.1": FOUND,
    "peg_in_hole_0.01": FOUND,
    "sealed_chamber": NO_PATH,
    "sealed_chamber_open": FOUND,
    "bug_trap": FOUND,
    "three_floor_maze": FOUND,
    "start_in_collision": NO_PATH,
}


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("decompositions")


@pytest.fixture(scope="module")
def outcomes(cache_dir):
    """Plan each scenario once per module, on first use."""
    done = {}

    def get(name):
        if name not in done:
            done[name] = plan(load_scenario(SCENARIOS / f"{name}.yaml"), cache_dir=cache_dir,
                              progress=False)
        return done[name]

    return get


def test_every_bundled_scenario_is_covered():
    bundled = {p.stem for p in SCENARIOS.glob("*.yaml")}
    assert bundled == set(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bundled_scenario_gets_its_expected_answer(outcomes, name):
    outcome = outcomes(name)
    assert outcome.status == EXPECTED[name], outcome.message
    assert outcome.timings["total"] > 0
    doc = outcome.path_json()
    assert {"status", "waypoints", "length", "clearance", "timings", "validation"} <= set(doc)
    report = outcome.report_json()
    assert report["status"] == outcome.status
    if outcome.status == FOUND:
        assert report["cells"]["leaves"] > 0 and report["graph"]["nodes"] > 0
        assert report["cells"]["total"]["empty"] > 0


@pytest.mark.parametrize("name", sorted(n for n, s in EXPECTED.items() if s == FOUND))
def test_found_path_is_free_on_the_original_meshes(outcomes, name):
    scenario = load_scenario(SCENARIOS / f"{name}.yaml")
    outcome = outcomes(name)
    wp = outcome.waypoints
    assert wp.ndim == 2 and wp.shape[1] == 3 and len(wp) >= 2
    np.testing.assert_array_equal(wp[0], scenario.start)
    np.testing.assert_array_equal(wp[-1], scenario.goal)
    lo, hi = scenario.bounds
    assert np.all(wp >= lo) and np.all(wp <= hi)
    # an independent checker, exact contact (no tolerance)
    checker = FclChecker(scenario.robot.mesh, [b.mesh for b in scenario.obstacles])
    check = checker.check_path(wp)
    assert check.valid, (check.first_bad_segment, check.obstacle)
    assert check.min_clearance > 0
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]
    assert outcome.clearance == pytest.approx(outcome.validation["fcl"]["min_clearance"])
    assert outcome.length == pytest.approx(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum())
    # shortcutting: far fewer waypoints than roadmap cells
    assert len(wp) <= outcome.report["path"]["roadmap_waypoints"]


def test_tight_peg_needs_refinement_and_stays_local(outcomes):
    outcome = outcomes("peg_in_hole_0.01")
    rounds = outcome.report["refinement"]["rounds"]
    assert rounds >= 3
    reached = outcome.report["resolution"]["reached"]
    assert reached <= 0.01  # an EMPTY cell fits in the 0.02-wide C-space slot
    assert reached >= outcome.report["resolution"]["floor"]
    # local refinement: nowhere near a uniform grid at the reached size
    assert outcome.report["cells"]["leaves"] < 2_000_000
    assert outcome.clearance < 0.01 + 1e-9


def test_no_path_certificate_really_separates_start_and_goal(outcomes, cache_dir):
    scenario = load_scenario(SCENARIOS / "sealed_chamber.yaml")
    outcome = outcomes("sealed_chamber")
    cert = outcome.certificate
    assert outcome.reason == "certificate"
    assert cert["exact"] is True
    assert cert["wall_cells"] == len(cert["walls"]) > 0
    assert cert["wall_cells_without_primitive"] == 0
    assert set(cert["wall_cells_by_obstacle"]) <= {"chamber", "bounds"}

    # 1. every wall cell lies inside one primitive: its 8 corners satisfy that primitive's
    #    planes (hull recomputed here with scipy from independently built primitives)
    robot = decompose(scenario.robot.mesh, cache_dir=cache_dir)
    pieces = [p for b in scenario.obstacles for p in decompose(b.mesh, cache_dir=cache_dir).pieces]
    prims = Primitives.pairwise_sums(pieces, robot.pieces, subtract=True)
    lo, hi = scenario.bounds
    corners = np.array([[(k >> a) & 1 for a in range(3)] for k in range(8)], dtype=float)
    for wall in cert["walls"]:
        box = np.asarray(wall["box"])
        pts = box[0] + corners * (box[1] - box[0])
        if wall["obstacle"] == "bounds":
            assert np.all(np.any((pts <= lo) | (pts >= hi), axis=1))
            continue
        verts, _ = prims.polytope(wall["primitive"])
        eq = ConvexHull(verts).equations
        scale = np.abs(verts).max()
        assert np.all(pts @ eq[:, :3].T + eq[:, 3] <= 1e-9 * scale), wall

    # 2. the walled component is closed: every face of every component cell is covered by
    #    component cells and wall cells (exact integer lattice arithmetic)
    floor = cert["floor"]
    comp = np.asarray(cert["component"]["boxes"])
    oracle.assert_component_closed(cert, comp[:, 0].min(axis=0) - 1000 * floor)

    # 3. the walled point is in the component, the other point is not
    walled = np.asarray(cert["walled_point"])
    other = scenario.goal if cert["walled"] == "start" else scenario.start
    inside = lambda p: np.any(np.all((comp[:, 0] <= p) & (p <= comp[:, 1]), axis=1))  # noqa: E731
    assert inside(walled) and not inside(other)
    # and the component cells are free or undecided, never FULL: none lies in a primitive
    assert not prims.contains(comp.mean(axis=1)).all()


def test_start_in_collision_names_obstacle_and_depth(outcomes):
    outcome = outcomes("start_in_collision")
    assert outcome.reason == "start_in_collision"
    assert outcome.collision["obstacle"] == "block"
    # the peg's bottom is 5 below the block's top: depth 5 (upper bound from FCL)
    assert outcome.collision["depth_lower_bound"] == pytest.approx(5.0, abs=1e-6)
    assert outcome.collision["depth_upper_bound"] == pytest.approx(5.0, rel=1e-3)
    assert "block" in outcome.message
    assert len(outcome.waypoints) == 0


def test_same_seed_gives_the_same_path(outcomes, cache_dir):
    first = outcomes("bug_trap")
    again = plan(load_scenario(SCENARIOS / "bug_trap.yaml"), cache_dir=cache_dir, progress=False)
    np.testing.assert_array_equal(first.waypoints, again.waypoints)
    assert first.report["cells"] == again.report["cells"]


def test_clearance_margin_is_kept_or_refused(cache_dir):
    scenario = load_scenario(SCENARIOS / "peg_in_hole_0.1.yaml")
    wide = dataclasses.replace(scenario.settings, clearance=0.05)
    outcome = plan(dataclasses.replace(scenario, settings=wide), cache_dir=cache_dir,
                   progress=False)
    assert outcome.status == FOUND
    assert outcome.clearance >= 0.05
    # the goal sits in the 0.1 gap: it cannot have clearance 0.2
    tight = dataclasses.replace(scenario.settings, clearance=0.2)
    outcome = plan(dataclasses.replace(scenario, settings=tight), cache_dir=cache_dir,
                   progress=False)
    assert outcome.status == NOT_FOUND and outcome.reason == "goal_in_margin", outcome.message
    # clearance 3 does not fit through the 14-wide hole (2 per side): refused, but not
    # "no path", since a path with less clearance exists
    scenario = load_scenario(SCENARIOS / "sealed_chamber_open.yaml")
    tight = dataclasses.replace(scenario.settings, clearance=3.0)
    outcome = plan(dataclasses.replace(scenario, settings=tight), cache_dir=cache_dir,
                   progress=False)
    assert outcome.status == NOT_FOUND and outcome.reason == "clearance", outcome.message


def test_floor_reached_is_not_found(cache_dir):
    # a floor coarser than the 0.02-wide slot: nothing proved, nothing found
    scenario = load_scenario(SCENARIOS / "peg_in_hole_0.01.yaml")
    coarse = dataclasses.replace(scenario.settings, resolution=0.05)
    outcome = plan(dataclasses.replace(scenario, settings=coarse), cache_dir=cache_dir,
                   progress=False)
    assert outcome.status == NOT_FOUND and outcome.reason == "floor", outcome.message
    assert outcome.report["resolution"]["floor"] == pytest.approx(0.05)


def test_cspace_components_and_locate_agree_with_the_certificate(cache_dir):
    scenario = load_scenario(SCENARIOS / "sealed_chamber.yaml")
    robot = decompose(scenario.robot.mesh, cache_dir=cache_dir)
    pieces = decompose(scenario.obstacles[0].mesh, cache_dir=cache_dir).pieces
    prims = Primitives.pairwise_sums(pieces, robot.pieces, subtract=True)
    cs = CSpace(prims, np.stack(scenario.bounds), 0.01, 2.0)
    s, g = cs.locate(scenario.start.tolist()), cs.locate(scenario.goal.tolist())
    labels = cs.leaves()["label"]
    assert labels[s] == labels[g] == 0  # both in EMPTY cells
    comp = cs.components([0, 2])
    assert comp[s] >= 0 and comp[g] >= 0 and comp[s] != comp[g]
    assert np.all(comp[labels == 1] == -1)
    assert cs.free_path(scenario.start.tolist(), scenario.goal.tolist()) is None
    assert cs.channel(scenario.start.tolist(), scenario.goal.tolist(), refinable_only=False) is None
    cert = cs.certificate(scenario.start.tolist(), scenario.goal.tolist())
    assert cert is not None and len(cert["wall_leaves"]) == len(cert["wall_prims"])
    pairs, portals = cs.adjacency([0])
    assert pairs.shape[1] == 2 and len(portals) == len(pairs)
    for (a, b), p in zip(pairs[:50], portals[:50]):
        ba, bb = cs.cell_box(int(a)), cs.cell_box(int(b))
        # the portal lies on both closed boxes
        assert np.all(ba[0] - 1e-9 <= p) and np.all(p <= ba[1] + 1e-9)
        assert np.all(bb[0] - 1e-9 <= p) and np.all(p <= bb[1] + 1e-9)


def test_small_coarse_grid_still_finds_paths(cache_dir):
    # coarser first grid: more refinement rounds, same answer
    scenario = load_scenario(SCENARIOS / "bug_trap.yaml")
    outcome = plan(scenario, cache_dir=cache_dir, progress=False,
                   params=OctreeParams(coarse_divisions=8))
    assert outcome.status == FOUND
    assert outcome.report["refinement"]["rounds"] > 0


def test_ompl_baseline_same_outputs(cache_dir):
    scenario = load_scenario(SCENARIOS / "peg_in_hole.yaml")
    # RRTConnect stops at its first solution (a few seconds here); the limit only bounds a
    # loaded machine's wait, so it is generous
    settings = dataclasses.replace(scenario.settings, time_limit=60.0, seed=3)
    outcome = plan(dataclasses.replace(scenario, settings=settings), planner="ompl:RRTConnect")
    assert outcome.planner == "ompl:RRTConnect"
    assert outcome.status == FOUND, outcome.message
    assert outcome.validation["fcl"]["valid"] and outcome.validation["ompl"]["valid"]
    np.testing.assert_allclose(outcome.waypoints[0], scenario.start)
    blocked = plan(load_scenario(SCENARIOS / "start_in_collision.yaml"), planner="ompl:PRM")
    assert blocked.status == NO_PATH and blocked.reason == "start_in_collision"
    assert blocked.collision["obstacle"] == "block"


def test_unknown_planner_is_an_error():
    from planner.errors import InvalidParameterError

    scenario = load_scenario(SCENARIOS / "bug_trap.yaml")
    with pytest.raises(InvalidParameterError, match="planner"):
        plan(scenario, planner="astar")
    with pytest.raises(InvalidParameterError, match="unknown OMPL planner"):
        plan(scenario, planner="ompl:Nope")


def test_the_html_scene_draws_the_c_obstacle_that_was_planned():
    """With a non-default source setting (exact: true on convex boxes, where auto would
    take the decomposition), the scene's C-obstacle comes from the plan's own source, not
    from a second computation with default settings."""
    import dataclasses

    import planner.viz as viz
    from planner import c_obstacle

    scenario = load_scenario(SCENARIOS / "sealed_chamber_open.yaml")
    asked = dataclasses.replace(scenario, settings=dataclasses.replace(
        scenario.settings, exact=True))
    outcome = plan(asked, progress=False)
    assert outcome.found and outcome.source.kind == "exact"
    scene = viz.scene_for_plan(asked, outcome, c_obstacle=True)
    for body in asked.obstacles:
        drawn = scene.layers[f"cspace/c_obstacle/{viz.scene.node_name(body.name)}"]
        planned = c_obstacle(body, asked.robot, source=outcome.source, max_refinements=0,
                             eps=viz.layout.display_eps(asked),
                             max_cells=viz.layout.DISPLAY_MAX_CELLS).mesh
        np.testing.assert_array_equal(drawn.vertices, planned.vertices)
        np.testing.assert_array_equal(drawn.faces, planned.faces)
        default = c_obstacle(body.mesh, asked.robot.mesh, eps=viz.layout.display_eps(asked),
                             max_refinements=0).mesh  # auto: the decomposition
        assert len(default.faces) != len(planned.faces) or not np.array_equal(
            default.vertices, planned.vertices)
