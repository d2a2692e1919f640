"""What ``pyproject.toml`` asks of an installer: OMPL only on the platforms it has wheels
for (its marker, evaluated as pip evaluates it, for each), and the extras."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from packaging.markers import default_environment
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def _requirement(name: str) -> Requirement:
    (found,) = [r for r in map(Requirement, PROJECT["dependencies"]) if r.name == name]
    return found


def _platform(system: str, release: str, machine: str, python: str) -> dict[str, str]:
    return {**default_environment(), "sys_platform": system, "platform_release": release,
            "platform_machine": machine, "python_version": python,
            "python_full_version": f"{python}.0"}


# ompl 2.0.1 ships wheels (no sdist) for CPython 3.10-3.13 on manylinux2014 x86_64 and
# aarch64 and on macosx_15_0 x86_64 and arm64 (Darwin 24 is macOS 15)
@pytest.mark.parametrize("where, wanted", [
    (_platform("linux", "6.8.0-1024-aws", "x86_64", "3.11"), True),
    (_platform("linux", "5.15.0", "aarch64", "3.13"), True),
    (_platform("darwin", "24.1.0", "arm64", "3.12"), True),
    (_platform("darwin", "25.0.0", "x86_64", "3.11"), True),
    (_platform("darwin", "23.6.0", "arm64", "3.12"), False),    # macOS 14: no wheel
    (_platform("win32", "10", "AMD64", "3.11"), False),
    (_platform("linux", "6.8.0", "ppc64le", "3.11"), False),
    (_platform("linux", "6.8.0", "x86_64", "3.14"), False),     # no cp314 wheel yet
])
def test_ompl_is_asked_for_only_where_it_has_wheels(where, wanted):
    marker = _requirement("ompl").marker
    assert marker is not None and marker.evaluate(where) is wanted


def test_this_machine_gets_ompl_when_it_can():
    marker = _requirement("ompl").marker
    assert marker is not None and marker.evaluate() is True  # CI: Linux x86_64, CPython 3.11


def test_the_notebooks_extra_brings_jupyter():
    extra = {Requirement(r).name for r in PROJECT["optional-dependencies"]["notebooks"]}
    assert {"jupyter", "ipykernel"} <= extra
