"""The API reference (``docs/build_api.py``, pdoc): built from the docstrings, one entry
per public name of ``planner.__all__``, and failing on what it cannot document."""

from __future__ import annotations

import importlib.util
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import planner

BUILD = Path(__file__).resolve().parents[1] / "docs" / "build_api.py"
KEY_FUNCTIONS = ["minkowski_sum", "c_obstacle", "plan", "plan_assembly", "offset",
                 "penetration_depth", "decompose", "load_problem", "choose_source"]


def load_build():
    spec = importlib.util.spec_from_file_location("build_api", BUILD)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("api")
    problems = load_build().build(out)
    return out, problems


def test_the_build_reports_no_problem_and_writes_the_pages(reference):
    out, problems = reference
    assert problems == []
    assert {p.name for p in out.iterdir()} >= {"index.html", "planner.html", "search.js"}


def test_every_public_name_has_an_entry(reference):
    page = (reference[0] / "planner.html").read_text()
    ids = set(re.findall(r'<section id="([A-Za-z_]+)">', page))
    assert set(planner.__all__) <= ids


@pytest.mark.parametrize("name", KEY_FUNCTIONS)
def test_a_key_function_shows_its_signature_and_docstring(reference, name):
    page = (reference[0] / "planner.html").read_text()
    section = page.split(f'<section id="{name}">', 1)[1].split("</section>", 1)[0]
    function = getattr(planner, name)
    assert inspect.isfunction(function)
    first_line = inspect.getdoc(function).splitlines()[0]
    words = re.sub(r"[`*:]", "", first_line).split()[:4]   # pdoc renders the markup
    assert all(word in re.sub(r"<[^>]+>", "", section) for word in words), name
    for parameter in list(inspect.signature(function).parameters)[:2]:
        assert parameter in section, (name, parameter)


def test_a_public_name_without_a_docstring_fails_the_build(monkeypatch):
    build = load_build()

    def bare(mesh):
        return mesh

    monkeypatch.setattr(planner, "mirror", bare)
    assert build.undocumented(planner, ["mirror", "plan"]) == ["planner.mirror has no docstring"]


def test_the_script_exits_0_and_says_where_it_wrote(tmp_path):
    proc = subprocess.run([sys.executable, str(BUILD), "--out", str(tmp_path / "api")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"wrote the API reference to {tmp_path / 'api' / 'index.html'}"


def test_a_public_function_named_like_its_module_stays_the_function():
    """Importing ``planner.decompose`` (any sum does) made ``planner.decompose`` the
    module; the reference documents the function, and that is what the name gives."""
    import planner.decompose  # noqa: F401  (the submodule import that used to hide it)
    from planner.decompose import Decomposition

    assert inspect.isfunction(planner.decompose)
    assert planner.decompose is sys.modules["planner.decompose"].decompose
    assert Decomposition is planner.Decomposition


def test_the_subpackages_that_messages_name_are_reachable_after_import_planner():
    """Messages advise ``planner.meshes.repair_mesh``: after ``import planner`` alone that
    name works (imported when first used: ``import planner`` still loads no trimesh), and
    a name that is neither export nor submodule stays an AttributeError."""
    code = ("import sys, planner\n"
            "assert 'trimesh' not in sys.modules and 'planner.meshes' not in sys.modules\n"
            "assert planner.meshes.repair_mesh is planner.repair_mesh\n"
            "assert planner.meshes.load_obj.__module__ == 'planner.meshes.formats'\n"
            "assert not hasattr(planner, 'no_such_name')\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
