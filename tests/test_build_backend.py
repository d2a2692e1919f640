"""The build backend (``build_backend/minkplan_backend.py``): without cargo on PATH, a
build ends in one line that says what to install; with cargo, maturin's hooks run."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BACKEND = ROOT / "build_backend"
HOOKS = ["get_requires_for_build_wheel", "get_requires_for_build_editable",
         "get_requires_for_build_sdist", "prepare_metadata_for_build_wheel",
         "build_wheel", "build_editable", "build_sdist"]


def path_without_cargo() -> str:
    """This process's PATH less every folder that holds a ``cargo``."""
    folders = os.environ.get("PATH", "").split(os.pathsep)
    kept = [f for f in folders if f and not (Path(f) / "cargo").exists()]
    assert shutil.which("cargo", path=os.pathsep.join(kept)) is None
    return os.pathsep.join(kept)


def run_hook(name: str, tmp_path: Path, path: str) -> subprocess.CompletedProcess:
    """Call one hook of the backend as a build frontend would, in a child process."""
    arg = "" if name.startswith("get_requires") else repr(str(tmp_path))
    code = (f"import sys; sys.path.insert(0, {str(BACKEND)!r}); import minkplan_backend; "
            f"print(minkplan_backend.{name}({arg}))")
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, env={**os.environ, "PATH": path})


def no_cargo_line() -> str:
    sys.path.insert(0, str(BACKEND))
    try:
        import minkplan_backend
    finally:
        sys.path.remove(str(BACKEND))
    return minkplan_backend.NO_CARGO


@pytest.mark.parametrize("hook", HOOKS)
def test_without_cargo_every_hook_ends_in_one_line(tmp_path, hook):
    proc = run_hook(hook, tmp_path, path_without_cargo())
    assert proc.returncode == 1
    assert proc.stderr.splitlines() == [no_cargo_line()]
    assert "https://rustup.rs" in proc.stderr and proc.stdout == ""
    assert list(tmp_path.iterdir()) == []         # nothing written


def test_pip_without_cargo_shows_the_line_and_no_traceback(tmp_path):
    """pip, offline and without build isolation (maturin is in this environment), on
    this tree: its own framing around our one line, no download attempt, no traceback."""
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-index", "--no-build-isolation",
         "-w", str(tmp_path), str(ROOT)],
        capture_output=True, text=True, timeout=300, env={**os.environ,
                                                          "PATH": path_without_cargo()})
    output = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert no_cargo_line() in output
    assert "Traceback" not in output and "puccinialin" not in output
    assert list(tmp_path.iterdir()) == []


def test_with_cargo_the_hooks_are_maturins(tmp_path):
    """With cargo on PATH the backend asks for what maturin asks (nothing extra here) and
    maturin writes the metadata (the hook that runs ``cargo metadata``)."""
    if shutil.which("cargo") is None:
        pytest.fail("cargo is needed to build minkplan at all; it is not on PATH")
    proc = run_hook("get_requires_for_build_wheel", tmp_path, os.environ["PATH"])
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"
    proc = run_hook("prepare_metadata_for_build_wheel", tmp_path, os.environ["PATH"])
    assert proc.returncode == 0, proc.stderr
    dist_info = proc.stdout.strip().splitlines()[-1]
    assert dist_info == "minkplan-0.1.0.dist-info"
    assert "Name: minkplan" in (tmp_path / dist_info / "METADATA").read_text()


def test_the_sdist_carries_the_backend_and_the_vendored_inputs(tmp_path):
    """Built through the backend: a build from the sdist finds ``build_backend/`` (named by
    ``backend-path``), and its tests find ``tests/data``; a built API reference stays out;
    every file git tracks is in it (tests, benchmarks and their results, docs, scenarios,
    notebooks, LICENSE) but CI's script."""
    import tarfile

    if shutil.which("cargo") is None:
        pytest.fail("cargo is needed to build minkplan at all; it is not on PATH")
    proc = run_hook("build_sdist", tmp_path, os.environ["PATH"])
    assert proc.returncode == 0, proc.stderr
    name = proc.stdout.strip().splitlines()[-1]
    with tarfile.open(tmp_path / name) as sdist:
        members = {m.split("/", 1)[1] for m in sdist.getnames() if "/" in m}
    assert {"build_backend/minkplan_backend.py", "pyproject.toml", "docs/build_api.py",
            "tests/data/README.md", "tests/data/assemblies/LICENSE",
            "tests/data/omplapp_format/window.cfg", "LICENSE", "README.md",
            "docs/schemas/path.schema.json", "scenarios/peg_in_hole.yaml",
            "tests/test_build_backend.py",
            "tests/benchmarks/rust_libraries/Cargo.toml"} <= members
    assert not any(m.startswith("docs/api/") for m in members)
    tracked = _tracked_files()
    if tracked is None:
        pytest.skip("not a git checkout (an unpacked sdist?): every tracked file unchecked")
    missing = tracked - members - {".ci/run", ".gitignore"}
    assert not missing, sorted(missing)[:10]


def _tracked_files() -> set[str] | None:
    """The files git tracks in this tree, or ``None`` outside a git checkout."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    proc = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True,
                          timeout=60)
    if proc.returncode != 0:
        return None
    return {f for f in proc.stdout.decode().split("\0") if f}
