"""Shared test setup: tests marked ``assets`` read files from public projects in
``../shared/assets`` (beside the repository, as CI has it); in a clone without that
folder they are skipped, saying so. A file missing from a folder that is there fails."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_ASSETS = Path(__file__).resolve().parents[2] / "shared" / "assets"
"""The shared assets folder (see its README): OMPL.app problems, peg-in-hole pairs,
NVIDIA's Factory and IndustReal assemblies."""


def pytest_runtest_setup(item: pytest.Item) -> None:
    if item.get_closest_marker("assets") is not None and not SHARED_ASSETS.is_dir():
        pytest.skip(f"needs the shared assets folder {SHARED_ASSETS}, which is absent in "
                    f"this clone (CI has it beside the repository)")
