"""The notebooks in notebooks/: committed without outputs, and they run.

Each notebook is executed in-process, cell by cell in one namespace (no Jupyter kernel
needed), with small settings: the values in ``SMALL`` replace the assignments of the
cell tagged ``parameters`` (papermill's convention). ``IPython.display.display`` is
captured, so the scenes a notebook shows are checked too: the first one is rendered in
headless Chromium (see tests/browser.py) and must show its parts in their colours.
"""

from __future__ import annotations

import json
from pathlib import Path

import browser
import numpy as np
import pytest

import planner.viz as viz

NOTEBOOKS = Path(__file__).resolve().parent.parent / "notebooks"
SMALL: dict[str, dict[str, object]] = {
    "01_minkowski_sum.ipynb": {"EPS": 0.1, "HEIGHT": 560},
    "02_peg_in_hole.ipynb": {"SCENARIOS": ["peg_in_hole.yaml", "sealed_chamber.yaml"],
                             "HEIGHT": 560},
    "03_assembly.ipynb": {"ASSEMBLIES": ["pegs_and_holes.yaml", "linked_rings.yaml"],
                          "HEIGHT": 560},
}
"""Parameter overrides per notebook (every notebook must be listed)."""

EXPECTED = ["01_minkowski_sum.ipynb", "02_peg_in_hole.ipynb", "03_assembly.ipynb"]


def notebooks() -> list[Path]:
    return sorted(NOTEBOOKS.glob("*.ipynb"))


def load(path: Path) -> dict:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def source(cell: dict) -> str:
    text = cell["source"]
    return text if isinstance(text, str) else "".join(text)


def test_the_notebooks_are_there():
    names = [p.name for p in notebooks()]
    assert set(EXPECTED) <= set(names), names
    assert set(names) <= set(SMALL), f"give small settings for {set(names) - set(SMALL)}"


@pytest.mark.parametrize("path", notebooks(), ids=lambda p: p.name)
def test_committed_without_outputs(path):
    nb = load(path)
    assert nb["nbformat"] == 4
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    assert code
    for cell in code:
        assert cell.get("outputs") == [], f"{path.name}: cell {cell.get('id')} has outputs"
        assert cell.get("execution_count") is None, f"{path.name}: cell {cell.get('id')}"
    tagged = [c for c in code if "parameters" in c.get("metadata", {}).get("tags", [])]
    assert len(tagged) == 1, f"{path.name}: tag exactly one cell 'parameters'"
    names = set(SMALL[path.name])
    assigned = {line.split("=")[0].strip() for line in source(tagged[0]).splitlines()
                if "=" in line and not line.lstrip().startswith("#")}
    assert names <= assigned, f"{path.name}: SMALL overrides {names - assigned}, not parameters"


def run_notebook(path: Path, monkeypatch) -> tuple[dict, list]:
    """Execute the code cells of ``path``; returns the namespace and what was displayed."""
    import IPython.display

    shown: list = []
    monkeypatch.setattr(IPython.display, "display", lambda *objs, **kw: shown.extend(objs))
    namespace: dict = {"__name__": "__main__"}
    for index, cell in enumerate(load(path)["cells"]):
        if cell["cell_type"] != "code":
            continue
        text = source(cell)
        assert not any(line.lstrip().startswith(("%", "!")) for line in text.splitlines()), \
            f"{path.name}: cell {index} uses IPython magics; keep notebooks plain Python"
        exec(compile(text, f"{path.name}[{index}]", "exec"), namespace)  # noqa: S102
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            namespace.update(SMALL[path.name])
    return namespace, shown


@pytest.mark.parametrize("path", notebooks(), ids=lambda p: p.name)
def test_notebook_runs_and_shows_its_scenes(path, monkeypatch, tmp_path):
    namespace, shown = run_notebook(path, monkeypatch)
    assert shown, f"{path.name} shows no scene"
    pages = [obj._repr_html_() for obj in shown]
    assert all("<iframe srcdoc=" in p and "MeshCat.Viewer" in p for p in pages)
    if path.name == "01_minkowski_sum.ipynb":
        result = namespace["result"]
        assert result.mesh.is_watertight and result.bound_guaranteed
        assert result.error_bound <= 2 * SMALL[path.name]["EPS"]
        assert np.all(namespace["inside"] == [True, False])
        assert len(pages) == 2
    # the colour the first scene must show beside the orange obstacles / fixed parts
    second, saturation = viz.COLORS["sum"], 0.2
    # how orange the obstacles are: opaque, but the peg's block encloses its goal (in the
    # hole) and is drawn translucent with its edges (test_viz checks that it shows through)
    orange_saturation, min_orange = 0.3, 5000
    if path.name == "02_peg_in_hole.ipynb":
        orange_saturation, min_orange = 0.2, 1500
    if path.name == "03_assembly.ipynb":
        from planner.viz.assembly import PART_COLORS

        results = namespace["results"]
        pegs, rings = results["pegs_and_holes.yaml"], results["linked_rings.yaml"]
        assert pegs.order == ["lower", "upper"] and pegs.removal[0].validation["valid"]
        assert not rings.found and rings.interlocked == ["ring_a", "ring_b"] and rings.proved
        assert rings.reuse["sums_computed"] == 2
        assert len(pages) == 1
        # the moving part ("upper", second in the file) in its colour, the base in orange
        second, saturation = PART_COLORS[1], 0.3

    # the first scene, as Jupyter would show it (the iframe), in a real browser
    page = tmp_path / "cell.html"
    page.write_text(f"<!DOCTYPE html><html><body style='margin:0'>{pages[0]}</body></html>",
                    encoding="utf-8")
    try:
        browser.chromium()
    except RuntimeError as err:
        pytest.fail(str(err))
    shot = browser.screenshot(page, tmp_path / "cell.png")
    # the operand (obstacle orange) seen through the translucent sum (blue): both hues,
    # paler than when drawn alone, but far from the grey background and grid
    orange = browser.pixels_like(shot.rgb, viz.COLORS["obstacle"],
                                 min_saturation=orange_saturation)
    blue = browser.pixels_like(shot.rgb, second, min_saturation=saturation)
    assert orange >= min_orange and blue >= 5000 and not shot.errors, (orange, blue, shot.errors,
                                                                  shot.png)
