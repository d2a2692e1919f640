"""planner.viz: the scene layout, its meshcat messages, the static page and the live
server, checked in a real browser (headless Chromium; see tests/browser.py).

The browser tests assert that the WebGL canvas shows the scene: enough pixels in the
obstacle colour and in the path colour. Negative controls (an empty scene, a broken
script, WebGL switched off) must fail that same check, so the check can fail.
"""

from __future__ import annotations

import html as html_lib
import io
import json
import re
import threading
import time
import urllib.request
from pathlib import Path

import browser
import numpy as np
import pytest
import trimesh
import umsgpack

import planner
import planner.viz as viz
from planner import _minkowski_core as core
from planner.io import parse_scenario
from planner.viz import lower, scene, shapes

SCENARIO = """
name: viz_test
units: mm
robot: {name: peg, box: [10, 10, 30]}
obstacles:
  - {name: left wall, box: [20, 60, 20], position: [-25, 0, 0]}
  - {name: right, box: [20, 60, 20], position: [25, 0, 0]}
start: [0, -50, 0]
goal: [0, 50, 0]
"""
WAYPOINTS = [[0, -50, 0], [0, -40, 25], [0, 40, 25], [0, 50, 0]]

# what "the canvas shows the scene" means at 800 x 600
MIN_OBSTACLE_PIXELS = 5000  # ~1% of the image in the obstacle's hue
MIN_PATH_PIXELS = 300  # the path tube in its hue


@pytest.fixture(scope="module")
def scenario():
    return parse_scenario(SCENARIO)


@pytest.fixture(scope="module")
def cspace(scenario):
    """A small native C-space of the scenario (the core's octree)."""
    pieces = [np.asarray(b.mesh.vertices) for b in scenario.obstacles]
    prims = core.Primitives.pairwise_sums(pieces, [np.asarray(scenario.robot.mesh.vertices)],
                                          subtract=True)
    bounds = np.array(scenario.bounds)
    return core.CSpace(prims, bounds, 4.0, 16.0)


@pytest.fixture(scope="module")
def c_obstacles(scenario):
    """The scenario's C-obstacle surfaces from the core, coarse (eps 1 mm)."""
    return viz.compute_c_obstacles(scenario, eps=1.0)


@pytest.fixture(scope="module")
def chromium():
    try:
        return browser.chromium()
    except RuntimeError as err:
        pytest.fail(str(err))


def shows_scene(shot: browser.Shot) -> tuple[bool, dict]:
    """The check every browser test makes: obstacle and path visible, no script error."""
    counts = {"obstacle": browser.pixels_like(shot.rgb, viz.COLORS["obstacle"]),
              "path": browser.pixels_like(shot.rgb, viz.COLORS["path"]),
              "errors": shot.errors}
    ok = (counts["obstacle"] >= MIN_OBSTACLE_PIXELS and counts["path"] >= MIN_PATH_PIXELS
          and not shot.errors)
    return ok, counts


def plan_scene(scenario, **kwargs):
    return viz.scene_for_plan(scenario, {"status": "found", "waypoints": WAYPOINTS}, **kwargs)


# ---- merged geometry -------------------------------------------------------------------

def test_box_edges_and_faces():
    boxes = np.array([[[0, 0, 0], [1, 2, 3]], [[5, 5, 5], [6, 6, 6]]], dtype=float)
    edges = shapes.box_edges(boxes)
    assert edges.shape == (24, 2, 3)
    d = np.abs(edges[:, 1] - edges[:, 0])
    assert np.all(np.count_nonzero(d, axis=1) == 1)  # axis-aligned
    assert sorted(d[:12].sum(axis=1)) == sorted([1] * 4 + [2] * 4 + [3] * 4)
    vertices, faces = shapes.box_faces(boxes)
    mesh = trimesh.Trimesh(vertices, faces, process=True)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(6.0 + 1.0)  # positive: outward


def test_tube_faces_point_away_from_the_polyline():
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 1, 1]], dtype=float)
    vertices, faces = shapes.tube(points, 0.05, sides=8)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    segments = shapes.polyline_segments(points)
    a, b = segments[:, 0], segments[:, 1]

    def nearest(p):
        ab = b - a
        t = np.clip(((p - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0, 1)
        q = a + t[:, None] * ab
        return q[np.argmin(np.linalg.norm(q - p, axis=1))]

    centroids = mesh.triangles_center
    outward = np.array([n @ (c - nearest(c)) for n, c in zip(mesh.face_normals, centroids)])
    assert np.all(outward > 0)
    distance = np.array([np.linalg.norm(v - nearest(v)) for v in vertices])
    assert np.all(distance <= 0.05 * (1 + 1e-9))
    with pytest.raises(ValueError):
        shapes.tube(points, 0.0)


# ---- the layout ------------------------------------------------------------------------

def test_plan_scene_has_every_layer_as_one_object(scenario, cspace):
    outcome = {"status": "found", "waypoints": WAYPOINTS}
    s = viz.scene_for_plan(scenario, outcome, cspace, c_obstacle=True)
    paths = set(s.layers)
    assert {"workspace/obstacles/left_wall", "workspace/obstacles/right",
            "workspace/robot/start", "workspace/robot/goal", "workspace/robot/moving",
            "cspace/c_obstacle/left_wall", "cspace/c_obstacle/right", "cspace/cells/empty",
            "cspace/cells/mixed", "cspace/cells/full", "cspace/roadmap", "path/line",
            "path/tube"} <= paths
    boxes, labels = viz.cells_from_cspace(cspace)
    assert len(boxes) == len(cspace) > 50
    for i in (0, len(boxes) // 2, len(boxes) - 1):
        np.testing.assert_allclose(boxes[i], cspace.cell_box(i))
    assert s.layers["cspace/cells/mixed"].count == np.count_nonzero(labels == scene.MIXED)
    assert s.layers["cspace/roadmap"].count == 2 * len(cspace.adjacency([0])[0])

    # one set_object per layer: the cells of a label and the roadmap are one buffer each
    set_objects = [c for c in lower.lowered(s) if c["type"] == "set_object"]
    layer_objects = [c for c in set_objects if c["path"].startswith("/meshcat/")]
    assert sorted(c["path"] for c in layer_objects) == sorted(f"/meshcat/{p}" for p in paths)
    kinds = {c["path"]: c["object"]["object"]["type"] for c in layer_objects}
    assert kinds["/meshcat/cspace/cells/mixed"] == "LineSegments"
    assert kinds["/meshcat/cspace/roadmap"] == "LineSegments"
    assert kinds["/meshcat/path/line"] == "Line"
    assert kinds["/meshcat/workspace/obstacles/right"] == "Mesh"

    # dense layers start hidden, the rest visible
    hidden = {c["path"] for c in lower.lowered(s)
              if c["type"] == "set_property" and c["property"] == "visible"
              and c["value"] is False and c["path"].startswith("/meshcat/")}
    assert hidden == {f"/meshcat/{p}" for p in scene.HIDDEN_BY_DEFAULT} - {
        "/meshcat/certificate/component"}
    assert s.is_visible("path/tube") and not s.is_visible("cspace/roadmap")


def test_many_cells_become_points_not_objects():
    rng = np.random.default_rng(0)
    lo = rng.uniform(0, 10, (66_000, 3))  # over MAX_CELL_EDGES per label
    boxes = np.stack([lo, lo + 0.1], axis=1)
    labels = rng.integers(0, 3, len(boxes))
    s = viz.Scene()
    layers = s.add_cells(boxes, labels)
    assert [layer.kind for layer in layers] == ["points"] * 3
    assert sum(layer.count for layer in layers) == 66_000
    assert len([c for c in lower.lowered(s) if c["type"] == "set_object"]) == 1 + 3  # + light
    few = viz.Scene()
    assert [layer.kind for layer in few.add_cells(boxes[:10], labels[:10], style="faces")] \
        == ["mesh"] * len(set(labels[:10]))
    with pytest.raises(ValueError, match="labels"):
        s.add_cells(boxes[:3], [0, 1, 7])
    with pytest.raises(ValueError, match="shape"):
        s.add_cells(boxes[:, 0], labels)


def test_animation_moves_the_robot_along_the_path(scenario):
    s = plan_scene(scenario)
    (anim,) = [c for c in lower.lowered(s) if c["type"] == "set_animation"]
    (clip,) = anim["animations"]
    assert clip["path"] == "/meshcat/workspace/robot/moving"
    (track,) = clip["clip"]["tracks"]
    assert track["name"] == ".position"
    np.testing.assert_allclose([k["value"] for k in track["keys"]], WAYPOINTS)
    times = [k["time"] for k in track["keys"]]
    assert times[0] == 0 and np.all(np.diff(times) > 0)
    # times follow arc length (constant speed)
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(WAYPOINTS, axis=0), axis=1))])
    np.testing.assert_allclose(np.array(times) / times[-1], arc / arc[-1])
    assert anim["options"]["play"] is True


def test_camera_frames_the_visible_scene(scenario):
    s = plan_scene(scenario)
    bounds = s.bounds()
    commands = lower.lowered(s)
    root = next(c for c in commands if c["type"] == "set_transform" and c["path"] == "/meshcat")
    shift = np.array(root["matrix"]).reshape(4, 4).T[:3, 3]
    np.testing.assert_allclose(shift, -bounds.mean(axis=0))  # meshcat orbits the origin
    cam = {c["property"]: c["value"] for c in commands
           if c["type"] == "set_property" and c["path"] == "/Cameras/default/rotated/<object>"}
    distance = np.linalg.norm(cam["position"])
    radius = np.linalg.norm(bounds[1] - bounds[0]) / 2
    assert radius < distance < 4 * radius
    assert cam["near"] < distance - radius and cam["far"] > distance + radius
    # hidden layers do not count: the C-space walls reach far beyond the scene
    s.set_visible("workspace", False)
    np.testing.assert_allclose(s.bounds(), s.bounds(visible_only=True))
    assert not np.allclose(s.bounds(), bounds)


def test_plan_inputs_are_tolerant(scenario, tmp_path):
    # no plan, a plan without waypoints, a not_found dict, a path.json + certificate.json
    assert "path/tube" not in viz.scene_for_plan(scenario).layers
    assert "path/tube" not in viz.scene_for_plan(scenario, {"status": "not_found"}).layers
    assert "path/tube" not in viz.scene_for_plan(
        scenario, {"status": "no_path", "waypoints": []}).layers
    walls = [{"leaf": 3, "box": [[-5, -5, -5], [5, 5, 5]], "primitive": 0, "obstacle": "right"},
             {"leaf": 4, "box": [[5, -5, -5], [15, 5, 5]], "primitive": 1, "obstacle": "right"}]
    (tmp_path / "path.json").write_text(json.dumps({"status": "no_path", "waypoints": []}))
    (tmp_path / "certificate.json").write_text(json.dumps({
        "walls": walls, "component": {"leaves": [1], "boxes": [[[0, 0, 0], [1, 1, 1]]]}}))
    s = viz.scene_for_plan(scenario, tmp_path / "path.json")
    assert s.layers["certificate/walls"].count == 2
    assert s.layers["certificate/walls"].kind == "mesh"
    assert not s.is_visible("certificate/component")
    assert s.title == "viz_test: no_path"
    # the core's own certificate form (wall_boxes), and a collision at the start
    s = viz.scene_for_plan(scenario, {"status": "no_path", "reason": "start_in_collision",
                                      "certificate": {"wall_boxes": np.zeros((1, 2, 3))}})
    assert s.layers["certificate/walls"].count == 1
    assert s.layers["workspace/robot/start"].color == viz.COLORS["robot_collision"]
    with pytest.raises(ValueError, match="waypoints"):
        viz.scene_for_plan(scenario, {"waypoints": [[1, 2]]})


def test_plan_outcome_objects_are_read(scenario, cspace):
    # anything shaped like planner.planning.PlanOutcome: path_json() (the path.json
    # contract), .certificate and, when the planner keeps it, .cspace
    class Outcome:
        certificate = None

        def __init__(self, with_cspace):
            if with_cspace:
                self.cspace = cspace

        def path_json(self):
            return {"status": "found", "waypoints": WAYPOINTS, "length": 1.0,
                    "clearance": None, "timings": {}, "validation": {"fcl": {}, "ompl": {}}}

    s = viz.scene_for_plan(scenario, Outcome(with_cspace=True))
    assert {"path/tube", "workspace/robot/moving", "cspace/cells/empty",
            "cspace/roadmap"} <= set(s.layers)
    assert "cspace/roadmap" not in viz.scene_for_plan(scenario, Outcome(False)).layers
    assert set(viz.as_scene(Outcome(False), scenario=scenario).layers) == set(
        viz.scene_for_plan(scenario, Outcome(False)).layers)
    with pytest.raises(TypeError, match="scenario"):
        viz.as_scene({"status": "found"})


def test_minkowski_scene_and_show(monkeypatch):
    import IPython.display

    a = trimesh.creation.box([1, 1, 1])
    b = trimesh.creation.icosphere(subdivisions=1, radius=0.2)
    result = planner.minkowski_sum(a, b, eps=0.1, progress=False)
    s = viz.scene_for_minkowski(result, a, b)
    assert list(s.layers) == ["minkowski/a", "minkowski/b", "minkowski/sum"]
    c = viz.scene_for_minkowski(result, a, b, c_obstacle=True)
    assert {"workspace/obstacles/obstacle", "workspace/robot/start",
            "cspace/c_obstacle"} == set(c.layers)
    shown = []
    monkeypatch.setattr(IPython.display, "display", lambda *objs, **kw: shown.extend(objs))
    assert viz.show(result, a=a, b=b) is None  # a trailing show() must not render twice
    (obj,) = shown
    page = obj._repr_html_()
    assert page.startswith("<div") and "<iframe srcdoc=" in page and "MeshCat.Viewer" in page
    assert "minkowski/sum" in repr(obj)
    assert s._repr_html_().count("<iframe") == 1


# ---- the static page -------------------------------------------------------------------

def _commands_in(page: str) -> tuple[list[dict], dict[str, list[dict]]]:
    """The page's commands: those run at once, and per layer those loaded on demand."""
    at_once = re.search(r'var atOnce = "([A-Za-z0-9+/=]*)";', page).group(1)
    on_demand = json.loads(re.search(r"var onDemand = (\{.*?\});", page).group(1))

    def decoded(text):
        return [umsgpack.unpackb(c) for c in viz.html.decode_commands(text)]

    return decoded(at_once), {path: decoded(text) for path, text in on_demand.items()}


def test_html_is_self_contained_and_deterministic(scenario):
    s = plan_scene(scenario)
    page = viz.to_html(s)
    # nothing fetched: no src/href attributes, no URL but XML namespace names and the
    # viewer's websocket default (ws://<this page's host>, used only by connect(), which
    # the static page never calls)
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)\s*=", page, re.I)
    urls = set(re.findall(r"(?:https?|wss?)://[^\s\"'<>)]*", page))
    assert urls <= {"http://www.w3.org/1999/xhtml", "http://www.w3.org/2000/svg",
                    "ws://${location.host}`"}, urls
    assert "connect(" not in page.split("var viewer = new MeshCat.Viewer")[1]
    assert "fetch(" not in page.split("var viewer = new MeshCat.Viewer")[1]
    # the bundle cannot close its element early
    assert page.count("</script>") == page.count("<script>") == 3
    assert page == viz.to_html(plan_scene(scenario))  # stable uuids: reproducible files
    at_once, on_demand = _commands_in(page)
    hidden = [{"type": "set_property", "path": f"/meshcat/{path}", "property": "visible",
               "value": False} for path in on_demand]
    # the page's commands are the scene's, the hidden layers' created when switched on
    assert at_once + [c for path, h in zip(on_demand, hidden) for c in [*on_demand[path], h]] \
        == lower.lowered(s)
    with pytest.raises(TypeError, match="as_scene"):
        viz.to_html(scenario)


def test_write_html_is_atomic(scenario, tmp_path, monkeypatch):
    target = tmp_path / "out" / "scene.html"
    assert viz.write_html(plan_scene(scenario), target) == target
    first = target.read_text()
    assert "data-minkplan-ready" in first
    assert [p.name for p in target.parent.iterdir()] == ["scene.html"]

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("os.replace", broken)
    with pytest.raises(OSError, match="disk full"):
        viz.write_html(viz.Scene("other"), target)
    assert target.read_text() == first  # the old file survives, no temporary left
    assert [p.name for p in target.parent.iterdir()] == ["scene.html"]


# ---- in a real browser -----------------------------------------------------------------

def test_missing_chromium_fails_loudly(monkeypatch):
    monkeypatch.delenv("MINKPLAN_CHROMIUM", raising=False)
    monkeypatch.setattr(browser.shutil, "which", lambda name: None)
    with pytest.raises(RuntimeError, match="apt-get install -y chromium"):
        browser.chromium()


def test_html_renders_in_chromium(chromium, scenario, cspace, c_obstacles, tmp_path):
    s = plan_scene(scenario, cspace=cspace, c_obstacle=c_obstacles)
    path = viz.write_html(s, tmp_path / "scene.html")
    shot = browser.screenshot(path, tmp_path / "scene.png")
    ok, counts = shows_scene(shot)
    assert ok, f"the scene is not on the canvas: {counts} (see {shot.png})"


def test_no_path_scene_shows_walls_and_toggled_cells(chromium, scenario, cspace, tmp_path):
    # wall cells of a certificate: a cage of boxes around the start
    start = np.asarray(scenario.start)
    offsets = np.array([[dx, dy, dz] for dx in (-1, 0, 1) for dy in (-1, 0, 1)
                        for dz in (-1, 0, 1) if (dx, dy, dz) != (0, 0, 0)], dtype=float)
    lo = start + 16.0 * offsets - 8.0
    walls = [{"box": [a.tolist(), (a + 16.0).tolist()]} for a in lo]
    s = viz.scene_for_plan(scenario, {"status": "no_path", "waypoints": [],
                                      "certificate": {"walls": walls}}, cspace)
    s.set_visible("cspace/cells/mixed", True)  # as the checkbox in meshcat's controls
    shot = browser.screenshot(viz.write_html(s, tmp_path / "walls.html"), tmp_path / "w.png")
    red = browser.pixels_like(shot.rgb, viz.COLORS["walls"], min_saturation=0.3)
    amber = browser.pixels_like(shot.rgb, viz.COLORS["cells_mixed"], hue_tolerance=8)
    path = browser.pixels_like(shot.rgb, viz.COLORS["path"])
    assert red >= 5000 and amber >= 500 and path < MIN_PATH_PIXELS and not shot.errors, (
        red, amber, path, shot.errors, shot.png)


def test_negative_controls_fail_the_same_check(chromium, scenario, tmp_path):
    # an empty scene: the viewer draws, but neither obstacle nor path
    empty = viz.write_html(viz.Scene("empty"), tmp_path / "empty.html")
    ok, counts = shows_scene(browser.screenshot(empty, tmp_path / "empty.png"))
    assert not ok and counts["obstacle"] == 0 and counts["path"] == 0, counts

    # a broken script: the right scene, but the viewer never starts
    page = viz.to_html(plan_scene(scenario))
    broken = tmp_path / "broken.html"
    broken.write_text(page.replace("new MeshCat.Viewer(", "new MeshCat.Viewerr(", 1))
    shot = browser.screenshot(broken, tmp_path / "broken.png")
    ok, counts = shows_scene(shot)
    assert not ok and counts["obstacle"] == 0 and shot.errors, counts

    # the right page with WebGL unavailable: a blank canvas fails too
    good = tmp_path / "good.html"
    good.write_text(page)
    shot = browser.screenshot(good, tmp_path / "nogl.png",
                              extra_flags=("--disable-software-rasterizer",))
    ok, counts = shows_scene(shot)
    assert not ok and counts["obstacle"] == 0, counts


def test_live_server_renders_in_chromium(chromium, scenario, tmp_path):
    with viz.open_live(plan_scene(scenario)) as view:
        assert view.running and view.url.startswith("http://127.0.0.1:")
        # the scene comes over a websocket, which virtual time does not wait for: on a
        # busy machine give it a second, longer chance
        for budget in (4000, 12000):
            shot = browser.screenshot(view.url, tmp_path / "live.png", budget_ms=budget)
            ok, counts = shows_scene(shot)
            if ok:
                break
        assert ok, f"live scene not on the canvas: {counts} (see {shot.png})"
        view.update(viz.Scene("empty"))  # replaced in every browser opened afterwards
        ok, counts = shows_scene(browser.screenshot(view.url, tmp_path / "live-empty.png"))
        assert not ok and counts["obstacle"] == 0, counts
    assert not view.running


def test_serve_prints_the_url_and_stops(scenario):
    out, stop = io.StringIO(), threading.Event()
    result = {}
    thread = threading.Thread(
        target=lambda: result.setdefault("url", viz.serve(plan_scene(scenario), out=out,
                                                          stop=stop, poll=0.05)))
    thread.start()
    try:
        deadline = time.monotonic() + 30
        while "http" not in out.getvalue() and time.monotonic() < deadline:
            time.sleep(0.05)
        line = out.getvalue()
        url = re.search(r"at (http://127\.0\.0\.1:\d+/static/) \(Ctrl\+C to stop\)", line)
        assert url, line
        with urllib.request.urlopen(url.group(1), timeout=10) as response:
            assert b"MeshCat.Viewer" in response.read()
    finally:
        stop.set()
        thread.join(timeout=30)
    assert not thread.is_alive() and result["url"] == url.group(1)


def _listening_addresses(port: int) -> set[str]:
    """The local addresses with a socket listening on ``port`` (``/proc/net/tcp*``)."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for row in Path(table).read_text().splitlines()[1:]:
            local, state = row.split()[1], row.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
                found.add(address)
    return found


def test_the_live_viewer_listens_on_this_machine_only(scenario):
    with viz.open_live(plan_scene(scenario)) as view:
        port = int(re.search(r":(\d+)/static/", view.url).group(1))
        assert _listening_addresses(port) == {"0100007F"}  # 127.0.0.1, nothing else


def test_a_large_roadmap_is_drawn_nearest_the_path_and_counted_whole():
    from planner.viz.layout import MAX_ROADMAP_SEGMENTS, shown_roadmap

    rng = np.random.default_rng(0)
    starts = rng.uniform(-10, 10, (3 * MAX_ROADMAP_SEGMENTS, 3))
    segments = np.stack([starts, starts + 0.01], axis=1)
    near = np.array([[0.0, 0.0, 0.0]])
    shown = shown_roadmap(segments, near)
    assert len(shown) == MAX_ROADMAP_SEGMENTS
    kept = np.linalg.norm(shown.mean(axis=1), axis=1)
    dropped_floor = np.sort(np.linalg.norm(segments.mean(axis=1), axis=1))[MAX_ROADMAP_SEGMENTS]
    assert kept.max() <= dropped_floor  # the nearest ones, none farther than one left out
    small = segments[:10]
    np.testing.assert_array_equal(shown_roadmap(small, near), small)


# ---- compact pages, layers on demand ---------------------------------------------------

ROOT = Path(__file__).resolve().parent.parent
PAGE_LIMIT_MB = 5.0  # issue 19: every bundled scenario's page under 5 MB


def _switch_on(page: str, node: str) -> str:
    """``page`` with a script that ticks the legend's box for ``node`` once the scene is
    built, as a user's click would (the ``change`` event)."""
    script = ("<script>(function wait() { if (!window.minkplanReady) return setTimeout(wait, 50);"
              f" var box = document.querySelector('input[data-node=\"{node}\"]');"
              " box.checked = true; box.dispatchEvent(new Event('change')); })();</script>")
    return page.replace("</body>", script + "</body>")


def test_hidden_layers_are_loaded_on_demand(scenario, cspace):
    s = plan_scene(scenario, cspace=cspace)
    page = viz.to_html(s)
    at_once, on_demand = _commands_in(page)
    dense = {"cspace/cells/empty", "cspace/cells/mixed", "cspace/cells/full", "cspace/roadmap"}
    assert set(on_demand) == dense
    created_at_once = {c["path"] for c in at_once if c["type"] == "set_object"}
    assert not {f"/meshcat/{p}" for p in dense} & created_at_once
    assert "/meshcat/path/tube" in created_at_once
    for path, created in on_demand.items():
        assert [c["path"] for c in created if c["type"] == "set_object"] == [f"/meshcat/{path}"]
        # the legend's switch for it names what it loads
        assert f"data-node=\"{path}\" data-load='[&quot;{path}&quot;]'" in page
    # a layer shown at the start is not deferred
    s.set_visible("cspace/roadmap", True)
    assert "cspace/roadmap" not in _commands_in(viz.to_html(s))[1]


def test_a_switched_on_layer_is_drawn_in_chromium(chromium, scenario, cspace, tmp_path):
    page = viz.to_html(viz.scene_for_plan(scenario, {"status": "not_found"}, cspace))
    amber = {}
    for name, text in (("off", page), ("on", _switch_on(page, "cspace/cells/mixed"))):
        (tmp_path / f"{name}.html").write_text(text)
        shot = browser.screenshot(tmp_path / f"{name}.html", tmp_path / f"{name}.png")
        assert not shot.errors, shot.errors
        amber[name] = browser.pixels_like(shot.rgb, viz.COLORS["cells_mixed"], hue_tolerance=8)
    # (off: only where the green start ghost tints an obstacle)
    assert amber["on"] >= 5000 and amber["on"] > 10 * amber["off"], amber


@pytest.mark.parametrize("yaml", sorted((ROOT / "scenarios").glob("*.yaml")),
                         ids=lambda p: p.stem)
def test_bundled_scenario_pages_are_small(yaml, tmp_path):
    from planner.io import load_scenario
    from planner.planning import plan

    scenario = load_scenario(yaml)
    outcome = plan(scenario, progress=False)
    s = viz.scene_for_plan(scenario, outcome, c_obstacle=True)
    page = viz.write_html(s, tmp_path / "scene.html")
    size_mb = page.stat().st_size / 1e6
    assert size_mb < PAGE_LIMIT_MB, f"{yaml.name}: {size_mb:.2f} MB"
    at_once, on_demand = _commands_in(page.read_text())
    assert set(on_demand) == {p for p in s.layers if not s.is_visible(p)}
    # nothing dropped: every layer's geometry is in the page, whole
    created = {c["path"]: c for c in at_once + [c for cs in on_demand.values() for c in cs]
               if c["type"] == "set_object"}
    for path, layer in s.layers.items():
        geometry = created[f"/meshcat/{path}"]["object"]["geometries"][0]["data"]
        position = geometry["attributes"]["position"]
        assert len(position["array"].data) == 4 * 3 * len(layer.vertices), path


# ---- see-through obstacles -------------------------------------------------------------

def _opacity(scene_, path: str) -> float:
    (command,) = [c for c in lower.lowered(scene_) if c["type"] == "set_object"
                  and c["path"] == f"/meshcat/{path}"]
    return command["object"]["materials"][0]["opacity"]


def test_obstacles_enclosing_the_path_are_see_through(scenario):
    from planner.io import load_scenario

    # beside the path, not around it: opaque
    beside = plan_scene(scenario)
    assert _opacity(beside, "workspace/obstacles/left_wall") == 1.0
    assert not [p for p in beside.layers if p.endswith(".edges")]
    # the sealed chamber holds the start and the goal: translucent, with its edges drawn
    chamber = load_scenario(ROOT / "scenarios" / "sealed_chamber.yaml")
    s = viz.scene_for_plan(chamber, {"status": "no_path", "waypoints": []})
    (name,) = [b.name for b in chamber.obstacles]
    path = f"workspace/obstacles/{scene.node_name(name)}"
    lo, hi = s.layers[path].world_bounds()
    assert np.all((lo < chamber.start) & (chamber.start < hi))
    assert _opacity(s, path) == scene.ENCLOSING_OPACITY < 1.0
    edges = s.layers[f"{path}.edges"]
    assert edges.kind == "segments" and edges.opacity == 1.0 and edges.count >= 12
    # its edges lie on the chamber's surface
    mesh = chamber.obstacles[0].mesh
    _, distance, _ = trimesh.proximity.closest_point(mesh, edges.vertices)
    assert np.max(distance) < 1e-9 * mesh.scale
    assert "translucent" in " ".join(e.notes[0] for e in viz.legend(s)
                                     if e.label == "Obstacles")


def test_the_certificate_shows_through_the_chamber_in_chromium(chromium, tmp_path):
    import dataclasses

    from planner.io import load_scenario
    from planner.planning import plan

    chamber = load_scenario(ROOT / "scenarios" / "sealed_chamber.yaml")
    outcome = plan(chamber, progress=False)
    assert outcome.status == "no_path"
    s = viz.scene_for_plan(chamber, outcome)
    red = {}
    for name in ("see-through", "opaque"):
        if name == "opaque":  # the negative control: the chamber as it was drawn before
            for path in [p for p in s.layers if p.startswith("workspace/obstacles/")]:
                s.layers[path] = dataclasses.replace(s.layers[path], opacity=1.0)
        shot = browser.screenshot(viz.write_html(s, tmp_path / f"{name}.html"),
                                  tmp_path / f"{name}.png")
        assert not shot.errors, shot.errors
        red[name] = browser.pixels_like(shot.rgb, viz.COLORS["walls"], min_saturation=0.3)
    assert red["see-through"] >= 5000 and red["opaque"] < red["see-through"] / 5, red


# ---- the legend ------------------------------------------------------------------------

def test_the_legend_names_every_colour_and_what_is_drawn(scenario, cspace, c_obstacles):
    s = plan_scene(scenario, cspace=cspace, c_obstacle=c_obstacles)
    entries = {e.label: e for e in viz.legend(s)}
    assert set(entries) == {"Obstacles", "Robot at start", "Robot at goal", "Robot moving",
                            "C-obstacle", "EMPTY cells", "MIXED cells", "FULL cells",
                            "Roadmap", "Path"}
    expected = {"Obstacles": "obstacle", "Robot at start": "robot_start",
                "Robot at goal": "robot_goal", "C-obstacle": "c_obstacle",
                "EMPTY cells": "cells_empty", "Roadmap": "roadmap", "Path": "path"}
    for label, key in expected.items():
        assert entries[label].color == viz.COLORS[key], label
    assert entries["Obstacles"].layers == ("workspace/obstacles/left_wall",
                                           "workspace/obstacles/right")
    boxes, labels = viz.cells_from_cspace(cspace)
    n_mixed = int(np.count_nonzero(labels == scene.MIXED))
    assert entries["MIXED cells"].notes == (f"{n_mixed:,}, drawn as box edges",)
    assert not entries["MIXED cells"].visible and entries["Path"].visible
    assert entries["Roadmap"].notes[0].startswith("all ")
    # the page shows it: a row per entry with its colour and its notes
    page = viz.to_html(s)
    legend_html = page[page.index('<div id="minkplan-legend">'):page.index("<script>")]
    for entry in entries.values():
        assert f"</span>{entry.label}<" in legend_html
        assert "rgba({}, {}, {}".format(*bytes.fromhex(entry.css_color[1:])) in legend_html
        for note in entry.notes:
            assert html_lib.escape(note) in legend_html
    # a roadmap cut to the nearest segments says so
    many = np.stack([np.zeros((scene_max := 41_000, 3)), np.ones((scene_max, 3))], axis=1)
    cut = viz.scene_for_plan(scenario, {"status": "found", "waypoints": WAYPOINTS},
                             {"roadmap": many})
    (roadmap,) = [e for e in viz.legend(cut) if e.label == "Roadmap"]
    assert roadmap.notes == ("the 40,000 segments nearest the path, of 41,000",)


def test_assembly_legend_has_a_row_per_part():
    from planner.assembly import plan_assembly
    from planner.io import load_assembly

    result = plan_assembly(load_assembly(ROOT / "scenarios/assemblies/pegs_and_holes.yaml"),
                           progress=False)
    entries = viz.legend(viz.scene_for_assembly(result))
    assert [e.label for e in entries] == [p.name for p in result.assembly.parts]
    assert len({e.color for e in entries}) == len(entries)


# ---- GLB -------------------------------------------------------------------------------

def _world(glb_scene, node: str) -> np.ndarray:
    """``node``'s vertices in minkplan's z-up world, from a GLB read back by trimesh."""
    from planner.viz.glb import Z_UP_TO_Y_UP

    transform, geometry = glb_scene.graph[node]
    vertices = np.asarray(glb_scene.geometry[geometry].vertices, dtype=np.float64)
    to_world = np.linalg.inv(Z_UP_TO_Y_UP) @ transform
    return vertices @ to_world[:3, :3].T + to_world[:3, 3]


def test_glb_holds_the_scene(scenario, cspace, c_obstacles, tmp_path):
    s = plan_scene(scenario, cspace=cspace, c_obstacle=c_obstacles)
    target = viz.write_glb(s, tmp_path / "scene.glb")
    back = trimesh.load(target)
    assert isinstance(back, trimesh.Scene)
    shown = {"workspace/obstacles/left_wall", "workspace/obstacles/right",
             "workspace/robot/start", "workspace/robot/goal", "cspace/c_obstacle/left_wall",
             "cspace/c_obstacle/right", "path/line", "path/tube"}
    assert set(back.graph.nodes_geometry) == shown
    kinds = {n: type(back.geometry[back.graph[n][1]]).__name__ for n in shown}
    assert kinds["path/line"] == "Path3D" and kinds["workspace/robot/goal"] == "Trimesh"
    # where it is: the goal ghost at the goal, the obstacles as posed, the path's waypoints
    robot = scenario.robot.mesh
    np.testing.assert_allclose(_world(back, "workspace/robot/goal"),
                               np.asarray(robot.vertices) + scenario.goal, atol=1e-4)
    wall = scenario.obstacles[0].mesh
    np.testing.assert_allclose(np.sort(_world(back, "workspace/obstacles/left_wall"), axis=0),
                               np.sort(np.asarray(wall.vertices), axis=0), atol=1e-4)
    # (the polyline as glTF line segments: consecutive pairs of waypoints)
    np.testing.assert_allclose(_world(back, "path/line").reshape(-1, 2, 3),
                               shapes.polyline_segments(WAYPOINTS), atol=1e-4)
    # colours and opacities as the page's
    goal = back.geometry[back.graph["workspace/robot/goal"][1]].visual.material
    np.testing.assert_array_equal(goal.baseColorFactor,
                                  [0x2F, 0x6F, 0xDE, round(255 * scene.GHOST_OPACITY)])
    assert goal.alphaMode == "BLEND"
    obstacle = back.geometry[back.graph["workspace/obstacles/right"][1]].visual.material
    assert obstacle.alphaMode == "OPAQUE" and obstacle.baseColorFactor[3] == 255
    # what glTF leaves out, said in the file
    info = back.metadata["minkplan"]
    assert set(info["left_out"]) == {"cspace/cells/empty", "cspace/cells/mixed",
                                     "cspace/cells/full", "cspace/roadmap",
                                     "workspace/robot/moving"}
    assert set(info["layers"]) == shown and info["title"] == s.title
    # and the hidden layers on request, as many cells as the scene has
    every = trimesh.load(viz.write_glb(s, tmp_path / "all.glb", include_hidden=True))
    mixed = every.geometry[every.graph["cspace/cells/mixed"][1]]
    assert len(mixed.vertices) == len(s.layers["cspace/cells/mixed"].vertices)


def test_the_legend_is_drawn_and_folds_in_small_views(chromium, scenario, cspace, tmp_path):
    # the roadmap is hidden at first: its colour on screen is the legend's swatch alone
    page = viz.write_html(plan_scene(scenario, cspace=cspace), tmp_path / "scene.html")
    swatch = {}
    for size in ((1200, 820), (800, 600)):  # viewports of about 1200 x 680 and 800 x 460
        shot = browser.screenshot(page, tmp_path / f"{size[0]}.png", size=size)
        assert not shot.errors, shot.errors
        swatch[size] = browser.pixels_like(shot.rgb[:, :300], viz.COLORS["roadmap"])
    assert swatch[(1200, 820)] >= 50 and swatch[(800, 600)] == 0, swatch
