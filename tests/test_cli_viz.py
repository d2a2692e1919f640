"""`minkplan plan --html` writes a self-contained scene that a real browser draws, `plan`
and `assemble --glb` the same scene as binary glTF, and `minkplan view` refuses bad input
with one line (it serves otherwise; the live server itself is tested in test_viz.py)."""

import json
import re
from pathlib import Path

import browser
import trimesh
import umsgpack

from planner.cli import main
from planner.viz.html import decode_commands
from planner.viz.scene import ENCLOSING_OPACITY

ROOT = Path(__file__).resolve().parent.parent
OBSTACLE = 0xE8701A  # planner.viz's obstacle colour
PATH = 0xE6007E  # and the path's


def test_plan_html_is_drawn_in_a_browser(tmp_path, capsys):
    out = tmp_path / "peg"
    code = main(["plan", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--out", str(out),
                 "--html", "--no-progress"])
    assert code == 0
    page = out / "scene.html"
    assert page.is_file() and (out / "path.json").is_file()
    text = page.read_text()
    # nothing to fetch: the only URLs are XML namespace names inside the inlined viewer and
    # its websocket default, which the static page never connects to (see test_viz.py)
    urls = set(re.findall(r"(?:https?|wss?)://[^\s\"'<>)]*", text))
    assert urls <= {"http://www.w3.org/1999/xhtml", "http://www.w3.org/2000/svg",
                    "ws://${location.host}`"}, urls
    # the peg's goal lies in the block's hole: the block is drawn translucent, with its
    # edges, so the peg shows inside it (and its orange is paler than an opaque block's)
    block = _set_object(text, "/meshcat/workspace/obstacles/block")
    assert block["object"]["materials"][0]["opacity"] == ENCLOSING_OPACITY
    assert _set_object(text, "/meshcat/workspace/obstacles/block.edges")
    shot = browser.screenshot(page, tmp_path / "shot.png", budget_ms=8000)
    assert not [m for m in shot.console if "Uncaught" in m], shot.console
    assert browser.pixels_like(shot.rgb, OBSTACLE, min_saturation=0.2) > 1500
    assert browser.pixels_like(shot.rgb, PATH) > 100
    assert "scene.html" in capsys.readouterr().out


def _set_object(page: str, path: str) -> dict:
    """The page's command creating ``path`` (run at once or on demand)."""
    texts = [re.search(r'var atOnce = "([A-Za-z0-9+/=]*)";', page).group(1),
             *json.loads(re.search(r"var onDemand = (\{.*?\});", page).group(1)).values()]
    commands = [umsgpack.unpackb(c) for t in texts for c in decode_commands(t)]
    (created,) = [c for c in commands if c["type"] == "set_object" and c["path"] == path]
    return created


def test_plan_and_assemble_write_glb(tmp_path, capsys):
    scenario = ROOT / "scenarios" / "peg_in_hole.yaml"
    target = tmp_path / "views" / "peg.glb"
    code = main(["plan", str(scenario), "--out", str(tmp_path / "peg"), "--glb", str(target),
                 "--no-progress"])
    assert code == 0 and f"wrote {target}" in capsys.readouterr().out
    back = trimesh.load(target)
    from planner.io import load_scenario

    loaded = load_scenario(scenario)
    (block,) = loaded.obstacles
    block_mesh = back.geometry[back.graph["workspace/obstacles/block"][1]]
    assert len(block_mesh.faces) == len(block.mesh.faces)
    assert {"workspace/robot/start", "workspace/robot/goal", "cspace/c_obstacle/block",
            "path/line", "path/tube", "workspace/obstacles/block.edges"} \
        <= set(back.graph.nodes_geometry)
    assert not (tmp_path / "peg" / "scene.html").exists()  # --glb alone: no page

    parts = ROOT / "scenarios" / "assemblies" / "pegs_and_holes.yaml"
    code = main(["assemble", str(parts), "--out", str(tmp_path / "asm"), "--glb",
                 str(tmp_path / "asm.glb"), "--no-progress"])
    assert code == 0
    back = trimesh.load(tmp_path / "asm.glb")
    assert set(back.graph.nodes_geometry) == {"assembly/lower", "assembly/upper"}


def test_glb_names_are_checked_before_any_work(tmp_path, capsys):
    scenario = str(ROOT / "scenarios" / "peg_in_hole.yaml")
    for bad, reason in ((tmp_path / "scene.gltf", "ending in .glb"),
                        (tmp_path / "a_file" / "x.glb", "is a file")):
        (tmp_path / "a_file").write_text("")
        out = tmp_path / "out"
        assert main(["plan", scenario, "--out", str(out), "--glb", str(bad)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and "--glb" in err and reason in err, err
        assert not out.exists() or not any(out.iterdir())  # nothing written
    assemble = ["assemble", str(ROOT / "scenarios" / "assemblies" / "pegs_and_holes.yaml"),
                "--out", str(tmp_path / "asm"), "--glb", str(tmp_path / "x.obj")]
    assert main(assemble) == 2 and "ending in .glb" in capsys.readouterr().err


def test_view_rejects_bad_input(tmp_path, capsys):
    assert main(["view", str(tmp_path / "nope.yaml")]) == 2
    assert "not found" in capsys.readouterr().err
    bad = tmp_path / "path.json"
    bad.write_text("[1, 2]")
    assert main(["view", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--path", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "path.json" in err
    # a host that is no address (a try-out: an internal error about free ports, exit 3)
    assert main(["view", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--host",
                 "999.1.1.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--host '999.1.1.1'" in err


def test_view_stopped_by_ctrl_c_exits_130(monkeypatch, capsys):
    """A try-out: view exited 0 when stopped; every command exits 130 after Ctrl+C (the
    server is served until then: here a stand-in returns at once, as serve does after
    one)."""
    import planner.viz

    served: list[str] = []
    monkeypatch.setattr(planner.viz, "serve", lambda scene, out, host: served.append(host))
    assert main(["view", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--no-c-obstacle",
                 "--no-progress"]) == 130
    assert served == ["127.0.0.1"]


def test_view_refuses_a_path_of_another_scenario_or_another_document(tmp_path, monkeypatch,
                                                                     capsys):
    """A try-out: view drew a path.json of another scenario, and an assembly's
    sequence.json, and did not take a plan's folder."""
    import json

    import planner.viz

    monkeypatch.setattr(planner.viz, "serve", lambda scene, out, host: None)
    peg = ROOT / "scenarios" / "peg_in_hole.yaml"
    found = {"schema": "minkplan/path/1", "status": "found",
             "waypoints": [[45.0, 10.0, 10.0], [0.0, 0.0, 10.0], [0.0, 0.0, -15.0]]}
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "path.json").write_text(json.dumps(found))
    view = ["view", str(peg), "--no-c-obstacle", "--no-progress", "--path"]
    assert main([*view, str(folder)]) == 130  # its folder: taken, served, stopped
    capsys.readouterr()
    other = dict(found, waypoints=[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    (tmp_path / "other.json").write_text(json.dumps(other))
    assert main([*view, str(tmp_path / "other.json")]) == 2
    assert "not from this scenario's start [45.0, 10.0, 10.0]" in capsys.readouterr().err
    (tmp_path / "sequence.json").write_text(json.dumps({"schema": "minkplan/sequence/1",
                                                        "status": "sequence"}))
    assert main([*view, str(tmp_path / "sequence.json")]) == 2
    assert "its schema is 'minkplan/sequence/1'" in capsys.readouterr().err
