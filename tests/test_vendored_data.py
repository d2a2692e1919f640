"""The vendored subset of real inputs in ``tests/data``: small, licensed, listed in its
README, and the same bytes as the full set in ``../shared/assets`` when that is present."""

from __future__ import annotations

import hashlib

import pytest
from conftest import SHARED_ASSETS, VENDORED

LICENCES = {"geometric_peg_in_hole_2mm": "geometric_peg_in_hole_2mm/LICENSE",
            "assemblies": "assemblies/LICENSE"}
"""Each vendored third-party folder and its licence file."""

AUTHORED = "omplapp_format"
"""The one folder of files written here (OMPL.app's own problems may not be shared)."""


def vendored_files() -> list[str]:
    return sorted(str(p.relative_to(VENDORED)) for p in VENDORED.rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts)


def third_party_files() -> list[str]:
    return [f for f in vendored_files()
            if f.split("/")[0] in LICENCES and not f.endswith("LICENSE")]


def test_the_subset_is_small_and_every_folder_carries_its_licence():
    total = sum((VENDORED / f).stat().st_size for f in vendored_files())
    assert 100_000 < total < 500_000
    assert {f.split("/")[0] for f in vendored_files()} == {*LICENCES, AUTHORED, "README.md"}
    for folder, licence in LICENCES.items():
        text = (VENDORED / licence).read_text()
        assert "Permission is hereby granted" in text or "Redistribution and use" in text, folder


def test_the_readme_names_every_vendored_file():
    readme = (VENDORED / "README.md").read_text()
    for name in third_party_files():
        file = name.rsplit("/", 1)[-1]
        assert f"`{file}`" in readme or f"`meshes/{file}`" in readme, name


@pytest.mark.assets
@pytest.mark.parametrize("name", third_party_files())
def test_a_vendored_file_is_the_shared_one_byte_for_byte(name):
    def digest(path):
        return hashlib.sha256(path.read_bytes()).hexdigest()

    assert digest(VENDORED / name) == digest(SHARED_ASSETS / name)
