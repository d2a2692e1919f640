"""Shared test setup for tests that read files from public projects.

The full set lives in ``../shared/assets`` (beside the repository, as CI has it); a small
subset of it is vendored in ``tests/data`` with its licences (see tests/data/README.md).
:func:`asset` finds a file in the full set when it is there, else in the subset, else
skips the test, saying so. Tests marked ``assets`` need the full set and are skipped,
saying so, when ``../shared/assets`` is absent. A file missing from a folder that is
there fails."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_ASSETS = Path(__file__).resolve().parents[2] / "shared" / "assets"
"""The shared assets folder (see its README): OMPL.app problems, peg-in-hole pairs,
NVIDIA's Factory and IndustReal assemblies."""

VENDORED = Path(__file__).resolve().parent / "data"
"""The vendored subset of :data:`SHARED_ASSETS`, same relative paths, with licences."""


def asset(relative: str) -> Path:
    """The asset at ``relative`` (e.g. ``"geometric_peg_in_hole_2mm/U_cube_cap.obj"``):
    from the full set when ``../shared/assets`` is present, else from the vendored subset;
    skips the calling test when neither has it."""
    if SHARED_ASSETS.is_dir():
        return SHARED_ASSETS / relative
    vendored = VENDORED / relative
    if vendored.exists():
        return vendored
    pytest.skip(f"{relative} is not in the vendored subset tests/data and the shared assets "
                f"folder {SHARED_ASSETS} is absent in this clone (CI has it)")


def pytest_runtest_setup(item: pytest.Item) -> None:
    if item.get_closest_marker("assets") is not None and not SHARED_ASSETS.is_dir():
        pytest.skip(f"needs the shared assets folder {SHARED_ASSETS}, which is absent in "
                    f"this clone (CI has it beside the repository)")
