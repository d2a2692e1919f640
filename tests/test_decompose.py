"""Tests for planner.decompose: exact convex bodies, CoACD, the on-disk cache."""

from __future__ import annotations

import logging
import os
import shutil
import sys
from pathlib import Path

import manifold3d
import numpy as np
import platformdirs
import pytest
import trimesh
from scipy.spatial import ConvexHull

from planner.decompose import CACHE_ENV, Decomposition, decompose, default_cache_dir
from planner.errors import InvalidMeshError, InvalidParameterError
from planner.meshes import winding_numbers
from planner.tolerances import scale_of


def l_bracket() -> trimesh.Trimesh:
    """Union of a 3x1x1 and a 1x1x3 box: an L of volume 5, one watertight mesh."""
    union = manifold3d.Manifold.cube([3, 1, 1]) + manifold3d.Manifold.cube([1, 1, 3])
    mesh = union.to_mesh()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts))


def covered(points: np.ndarray, pieces: list[np.ndarray], slack: float) -> np.ndarray:
    """Which points lie inside (within slack of) at least one piece hull."""
    inside = np.zeros(len(points), dtype=bool)
    for piece in pieces:
        eq = ConvexHull(piece).equations
        inside |= (points @ eq[:, :3].T + eq[:, 3]).max(axis=1) <= slack
    return inside


def entry_of(directory) -> list:
    return sorted(p for p in directory.iterdir() if p.suffix == ".mkdec")


@pytest.fixture(scope="module")
def bracket_cache(tmp_path_factory):
    """One CoACD run of the L-bracket, cached; tests copy the cache directory."""
    directory = tmp_path_factory.mktemp("bracket-cache")
    result = decompose(l_bracket(), cache_dir=directory, name="bracket", progress=False)
    return directory, result


# ----------------------------------------------------------------------- exact


def test_box_is_exact(tmp_path):
    box = trimesh.creation.box([1, 2, 3])
    result = decompose(box, cache_dir=tmp_path, name="box")
    assert isinstance(result, Decomposition)
    assert result.exact and result.method == "convex"
    assert result.excess == 0.0 and result.deficit == 0.0
    assert result.bodies == 1 and len(result.pieces) == 1
    piece = result.pieces[0]
    assert piece.shape == (8, 3) and piece.dtype == np.float64
    def rows(a):
        return a[np.lexsort(a.T[::-1])]

    np.testing.assert_array_equal(rows(piece), rows(np.asarray(box.vertices)))


def test_two_disjoint_boxes_are_two_exact_pieces(tmp_path):
    pair = trimesh.util.concatenate(
        [trimesh.creation.box([1, 1, 1]), trimesh.creation.box([2, 2, 2]).apply_translation(
            [5, 0, 0])]
    )
    result = decompose(pair, cache_dir=tmp_path)
    assert result.exact and result.method == "convex"
    assert result.bodies == 2 and len(result.pieces) == 2
    volumes = sorted(ConvexHull(p).volume for p in result.pieces)
    assert volumes == pytest.approx([1.0, 8.0])


# ----------------------------------------------------------------------- CoACD


def test_l_bracket_goes_through_coacd(bracket_cache):
    _, result = bracket_cache
    mesh = l_bracket()
    diagonal = scale_of(mesh)
    assert not result.exact and result.method == "coacd" and result.bodies == 1
    assert len(result.pieces) >= 2
    # CoACD places the cut within ~0.2% of the bracket's size of the true corner plane
    # (measured: excess 0.0024 on a diagonal of 4.36, i.e. 0.05%); a hull bridging
    # the concave corner would stick out ~0.7. Allow 10x the measured value.
    assert 0.0 <= result.excess < 0.005 * diagonal
    assert result.deficit < 1e-3 * diagonal
    # hulls of the pieces cover the solid: interior sample points are all inside some hull
    rng = np.random.default_rng(1)
    points = rng.uniform(mesh.bounds[0], mesh.bounds[1], size=(4000, 3))
    points = points[winding_numbers(points, mesh.triangles) > 0.5]
    assert len(points) > 1000
    assert covered(points, result.pieces, 1e-9 * diagonal).all()
    # and the pieces stay close to the solid: their total volume is ~5
    total = sum(ConvexHull(p).volume for p in result.pieces)
    assert 5.0 <= total < 5.0 * 1.01


def test_coacd_is_deterministic(bracket_cache, tmp_path):
    _, first = bracket_cache
    second = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert not second.cache_hit
    assert len(second.pieces) == len(first.pieces)
    for a, b in zip(first.pieces, second.pieces, strict=True):
        np.testing.assert_array_equal(a, b)
    assert second.excess == first.excess and second.deficit == first.deficit


def test_mixed_bodies(tmp_path):
    bracket = l_bracket()
    box = trimesh.creation.box([1, 1, 1]).apply_translation([10, 0, 0])
    result = decompose(trimesh.util.concatenate([bracket, box]), cache_dir=tmp_path)
    assert result.method == "mixed" and result.bodies == 2 and not result.exact
    assert len(result.pieces) >= 3


# ----------------------------------------------------------------------- cache


def test_second_call_hits_cache_with_identical_arrays(bracket_cache, tmp_path):
    directory, first = bracket_cache
    shutil.copytree(directory, tmp_path, dirs_exist_ok=True)
    again = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert again.cache_hit and not first.cache_hit
    assert len(again.pieces) == len(first.pieces)
    for a, b in zip(first.pieces, again.pieces, strict=True):
        assert a.dtype == np.float64
        np.testing.assert_array_equal(a, b)
    assert (again.excess, again.deficit, again.method, again.bodies) == (
        first.excess, first.deficit, first.method, first.bodies)


def test_parameters_are_part_of_the_key(tmp_path):
    box = trimesh.creation.box([1, 1, 1])
    decompose(box, cache_dir=tmp_path)
    assert decompose(box, cache_dir=tmp_path).cache_hit
    assert not decompose(box, cache_dir=tmp_path, threshold=0.1).cache_hit
    assert not decompose(box, cache_dir=tmp_path, seed=3).cache_hit
    assert not decompose(box.copy().apply_translation([1e-6, 0, 0]), cache_dir=tmp_path).cache_hit
    assert len(entry_of(tmp_path)) == 4


@pytest.mark.parametrize("damage", ["truncate", "flip", "empty", "garbage"])
def test_corrupt_entry_is_detected_and_recomputed(bracket_cache, tmp_path, caplog, damage):
    directory, first = bracket_cache
    shutil.copytree(directory, tmp_path, dirs_exist_ok=True)
    (entry,) = entry_of(tmp_path)
    data = bytearray(entry.read_bytes())
    if damage == "truncate":
        data = data[: len(data) * 2 // 3]
    elif damage == "flip":
        for offset in (len(data) // 2, len(data) - 10):
            data[offset] ^= 0xFF
    elif damage == "empty":
        data = bytearray()
    else:
        data = bytearray(b"\x93NUMPY not really" * 40)
    entry.write_bytes(bytes(data))
    with caplog.at_level(logging.WARNING, logger="planner.decompose"):
        result = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert not result.cache_hit
    assert any("corrupt" in r.getMessage() for r in caplog.records)
    for a, b in zip(first.pieces, result.pieces, strict=True):
        np.testing.assert_array_equal(a, b)
    # the recomputed entry replaced the corrupt one
    assert decompose(l_bracket(), cache_dir=tmp_path, name="bracket").cache_hit


def test_env_var_sets_cache_dir(monkeypatch, tmp_path):
    monkeypatch.setenv(CACHE_ENV, str(tmp_path / "from-env"))
    assert default_cache_dir() == tmp_path / "from-env"
    box = trimesh.creation.box([1, 1, 1])
    assert not decompose(box).cache_hit
    assert len(entry_of(tmp_path / "from-env")) == 1
    assert decompose(box).cache_hit
    monkeypatch.delenv(CACHE_ENV)
    assert default_cache_dir().parts[-2:] == ("minkplan", "decompositions")


def test_default_cache_dir_is_the_platforms_user_cache(monkeypatch, tmp_path):
    """Without the variable, the cache lives where the platform keeps user caches
    (platformdirs): on Linux under ``$XDG_CACHE_HOME``, else ``~/.cache``."""
    monkeypatch.delenv(CACHE_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    expected = platformdirs.user_cache_path("minkplan", appauthor=False) / "decompositions"
    assert default_cache_dir() == expected
    if sys.platform.startswith("linux"):
        assert expected == tmp_path / "xdg" / "minkplan" / "decompositions"
        monkeypatch.delenv("XDG_CACHE_HOME")
        assert default_cache_dir() == Path.home() / ".cache" / "minkplan" / "decompositions"


def test_leftover_temp_file_of_killed_writer_is_ignored(bracket_cache, tmp_path):
    directory, first = bracket_cache
    (entry,) = entry_of(directory)
    # a writer killed mid-write leaves only its temp file (os.replace never ran)
    partial = entry.read_bytes()[:100]
    (tmp_path / f".{entry.stem[:16]}.abcd1234.tmp").write_bytes(partial)
    result = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert not result.cache_hit
    assert len(entry_of(tmp_path)) == 1
    for a, b in zip(first.pieces, result.pieces, strict=True):
        np.testing.assert_array_equal(a, b)
    assert decompose(l_bracket(), cache_dir=tmp_path, name="bracket").cache_hit


def test_unwritable_cache_dir_only_warns(tmp_path, caplog):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with caplog.at_level(logging.WARNING, logger="planner.decompose"):
        result = decompose(trimesh.creation.box([1, 1, 1]), cache_dir=blocker / "sub")
    assert result.exact
    assert any("cannot write" in r.getMessage() for r in caplog.records)


# ----------------------------------------------------------------------- inputs


@pytest.mark.parametrize("threshold", [0.0, -0.1, 1.5, float("nan"), "x"])
def test_bad_threshold(tmp_path, threshold):
    with pytest.raises(InvalidParameterError, match="threshold"):
        decompose(trimesh.creation.box(), threshold=threshold, cache_dir=tmp_path)


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, True])
def test_bad_seed(tmp_path, seed):
    with pytest.raises(InvalidParameterError, match="seed"):
        decompose(trimesh.creation.box(), seed=seed, cache_dir=tmp_path)


def test_invalid_mesh_is_rejected_by_name(tmp_path):
    box = trimesh.creation.box()
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-1], process=False)
    with pytest.raises(InvalidMeshError, match="mesh 'lid'"):
        decompose(open_box, cache_dir=tmp_path, name="lid")


def test_checksum_catches_a_well_formed_but_altered_payload(bracket_cache, tmp_path, caplog):
    from planner.decompose_cache import _HEADER, _MAGIC, _encode

    directory, first = bracket_cache
    shutil.copytree(directory, tmp_path, dirs_exist_ok=True)
    (entry,) = entry_of(tmp_path)
    original = entry.read_bytes()
    # a readable archive (zip CRCs fine) with other numbers, under the original digest
    meta = {"key": entry.stem, "exact": False, "excess": 0.0, "deficit": 0.0,
            "method": "coacd", "bodies": 1}
    forged = _encode([p + 1.0 for p in first.pieces], meta)
    payload = forged[_HEADER:]
    header = original[: len(_MAGIC) + 32] + len(payload).to_bytes(8, "little")
    entry.write_bytes(header + payload)
    with caplog.at_level(logging.WARNING, logger="planner.decompose"):
        result = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert not result.cache_hit
    assert any("checksum" in r.getMessage() for r in caplog.records)
    for a, b in zip(first.pieces, result.pieces, strict=True):
        np.testing.assert_array_equal(a, b)


def test_progress_bar_can_be_forced(tmp_path, capsys):
    pair = trimesh.util.concatenate(
        [trimesh.creation.box([1, 1, 1]), trimesh.creation.box([1, 1, 1]).apply_translation(
            [3, 0, 0])]
    )
    decompose(pair, cache_dir=tmp_path, progress=True, name="pair")
    err = capsys.readouterr().err
    assert "decomposing pair: body 1 of 2" in err and "decomposing pair: body 2 of 2" in err
    assert err.endswith("\r\033[K")              # the line is cleared at the end
    decompose(pair, cache_dir=tmp_path / "other", progress=False, name="pair")
    assert capsys.readouterr().err == ""


def test_coacd_options(tmp_path):
    with pytest.raises(InvalidParameterError, match="coacd_options"):
        decompose(l_bracket(), cache_dir=tmp_path, coacd_options={"no_such_option": 1})
    with pytest.raises(InvalidParameterError, match="threshold"):
        decompose(l_bracket(), cache_dir=tmp_path, coacd_options={"threshold": 0.1})
    coarse = decompose(l_bracket(), cache_dir=tmp_path, coacd_options={"resolution": 500})
    assert not coarse.cache_hit and len(coarse.pieces) >= 2
    assert decompose(l_bracket(), cache_dir=tmp_path,
                     coacd_options={"resolution": 500}).cache_hit


@pytest.mark.parametrize("kind", ["link_to_dev_zero", "fifo", "link_to_a_good_entry"])
def test_a_cache_entry_that_is_no_regular_file_is_not_read(bracket_cache, tmp_path, caplog,
                                                           kind):
    directory, first = bracket_cache
    shutil.copytree(directory, tmp_path / "cache", dirs_exist_ok=True)
    (entry,) = entry_of(tmp_path / "cache")
    if kind == "link_to_dev_zero":  # read whole, it would never end
        entry.unlink()
        entry.symlink_to("/dev/zero")
    elif kind == "fifo":  # opened for reading, it would block forever
        entry.unlink()
        os.mkfifo(entry)
    else:
        good = tmp_path / "elsewhere.bin"
        shutil.move(entry, good)
        entry.symlink_to(good)
    with caplog.at_level(logging.WARNING, logger="planner.decompose"):
        result = decompose(l_bracket(), cache_dir=tmp_path / "cache", name="bracket")
    assert not result.cache_hit
    assert any("not a regular file" in r.getMessage() for r in caplog.records)
    for a, b in zip(first.pieces, result.pieces, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("content", ["nan_point", "single_point", "far_outside"])
def test_a_checksummed_entry_with_impossible_content_is_recomputed(bracket_cache, tmp_path,
                                                                   caplog, content):
    from planner.decompose_cache import _encode

    directory, first = bracket_cache
    shutil.copytree(directory, tmp_path, dirs_exist_ok=True)
    (entry,) = entry_of(tmp_path)
    pieces = [p.copy() for p in first.pieces]
    if content == "nan_point":
        pieces[0][0, 0] = np.nan
    elif content == "single_point":
        pieces[0] = pieces[0][:1]
    else:
        pieces[-1] = pieces[-1] + 100.0
    meta = {"key": entry.stem, "exact": first.exact, "excess": first.excess,
            "deficit": first.deficit, "method": first.method, "bodies": first.bodies}
    entry.write_bytes(_encode(pieces, meta))  # a valid checksum over impossible content
    with caplog.at_level(logging.WARNING, logger="planner.decompose"):
        result = decompose(l_bracket(), cache_dir=tmp_path, name="bracket")
    assert not result.cache_hit
    assert any("corrupt" in r.getMessage() for r in caplog.records)
    for a, b in zip(first.pieces, result.pieces, strict=True):
        np.testing.assert_array_equal(a, b)
