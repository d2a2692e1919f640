"""`minkplan plan --html` writes a self-contained scene that a real browser draws, and
`minkplan view` refuses bad input with one line (it serves otherwise; the live server
itself is tested in test_viz.py)."""

import re
from pathlib import Path

import browser

from planner.cli import main

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
    shot = browser.screenshot(page, tmp_path / "shot.png", budget_ms=8000)
    assert not [m for m in shot.console if "Uncaught" in m], shot.console
    assert browser.pixels_like(shot.rgb, OBSTACLE) > 3000
    assert browser.pixels_like(shot.rgb, PATH) > 100
    assert "scene.html" in capsys.readouterr().out


def test_view_rejects_bad_input(tmp_path, capsys):
    assert main(["view", str(tmp_path / "nope.yaml")]) == 2
    assert "not found" in capsys.readouterr().err
    bad = tmp_path / "path.json"
    bad.write_text("[1, 2]")
    assert main(["view", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--path", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "path.json" in err
