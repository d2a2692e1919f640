"""planner.viz: the scene layout, its meshcat messages, the static page and the live
server, checked in a real browser (headless Chromium; see tests/browser.py).

The browser tests assert that the WebGL canvas shows the scene: enough pixels in the
obstacle colour and in the path colour. Negative controls (an empty scene, a broken
script, WebGL switched off) must fail that same check, so the check can fail.
"""

from __future__ import annotations

import base64
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

def _commands_in(page: str) -> list[dict]:
    block = page[page.index("var commands = ["):page.index("];", page.index("var commands"))]
    return [umsgpack.unpackb(base64.b64decode(x)) for x in re.findall(r'"([A-Za-z0-9+/=]+)"',
                                                                      block)]


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
    assert page.count("</script>") == 2  # the bundle cannot close its element early
    assert page == viz.to_html(plan_scene(scenario))  # stable uuids: reproducible files
    decoded = _commands_in(page)
    assert [c["type"] for c in decoded] == [c["type"] for c in lower.lowered(s)]
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
