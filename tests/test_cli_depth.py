"""`minkplan depth` (one line or JSON, exit 0; bad input one line, exit 2) and the depth
of an assembled-pose overlap in `minkplan assemble`'s report.json."""

import json

import pytest
import shapes
import trimesh

from planner.cli import main


def _exit_code(argv) -> int:
    """``main``'s exit code, also when argparse exits (a bad option value)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


@pytest.fixture
def pair(tmp_path):
    a = tmp_path / "a.stl"
    b = tmp_path / "b.stl"
    shapes.box().export(a)
    shapes.box(center=(0.0, 0.75, 0.0)).export(b)  # overlap 0.25 along y
    return a, b


def test_depth_prints_one_line(pair, capsys):
    assert main(["depth", str(pair[0]), str(pair[1])]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    assert "penetration depth in [0.2" in out[0] and "along (0, -1, 0)" in out[0]
    assert "FCL agrees" in out[0]


def test_depth_json(pair, capsys):
    assert main(["depth", str(pair[0]), str(pair[1]), "--json", "--tolerance", "1e-5"]) == 0
    r = json.loads(capsys.readouterr().out)
    # the STL stores float32: 0.25 up to its rounding
    assert r["lower"] <= 0.25 + 1e-7 and 0.25 - 1e-7 <= r["upper"] <= r["lower"] + 1e-5
    assert r["direction"] == pytest.approx([0.0, -1.0, 0.0])
    assert r["separated"] is False and r["validated"] is True and r["converged"] is True


def test_depth_of_separated_meshes(tmp_path, capsys):
    a, b = tmp_path / "a.stl", tmp_path / "b.stl"
    shapes.box().export(a)
    shapes.box(center=(2.0, 0.0, 0.0)).export(b)
    assert main(["depth", str(a), str(b), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["separated"] is True and r["distance"] == pytest.approx(1.0)
    assert r["lower"] == r["upper"] == -r["distance"]


def test_depth_bad_input_is_one_line_exit_2(pair, tmp_path, capsys):
    open_box = tmp_path / "open.stl"
    box = shapes.box()
    trimesh.Trimesh(box.vertices, box.faces[:-2], process=False).export(open_box)
    huge = tmp_path / "huge.obj"  # finite, but its volume overflows
    trimesh.Trimesh(box.vertices * 1e150, box.faces, process=False).export(huge)
    cases = [
        ["depth", str(huge), str(pair[1])],
        ["offset", str(huge), "-r", "1e149", "-o", str(tmp_path / "grown.stl")],
        ["depth", str(pair[0]), str(tmp_path / "missing.stl")],
        ["depth", str(pair[0]), str(tmp_path)],
        ["depth", str(pair[0]), str(pair[1]), "--tolerance", "-1"],
        ["depth", str(pair[0]), str(pair[1]), "--tolerance", "x"],
        ["depth", str(open_box), str(pair[1])],
    ]
    for argv in cases:
        assert _exit_code(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("minkplan: error:"), (argv, err)
        if argv[1] == str(huge):  # repair would not mend it: not offered
            assert "exceed 1e+30" in err[0] and "repair" not in err[0], err[0]
        assert "Traceback" not in err[0]


def test_depth_offers_repair_where_the_offset_does_and_it_mends(pair, tmp_path, capsys):
    """A try-out: an operand with a NaN corner. ``offset`` offered ``--repair`` for it
    and ``depth`` did not, though ``depth --repair`` mends it (the faces at that corner
    dropped, the hole filled)."""
    box = shapes.box()
    nan = tmp_path / "nan.obj"
    corners = ["v nan nan nan"] + [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in box.vertices[1:]]
    nan.write_text("\n".join(corners + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in box.faces])
                   + "\n")
    assert _exit_code(["depth", str(nan), str(pair[1])]) == 2
    err = capsys.readouterr().err
    assert "NaN" in err and "--repair" in err
    assert _exit_code(["depth", str(nan), str(pair[1]), "--repair", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["upper"] > 0


def test_assemble_overlap_reports_depth(tmp_path, capsys):
    asm = tmp_path / "overlap.yaml"
    asm.write_text("parts:\n  - {name: a, box: [1, 1, 1]}\n"
                   "  - {name: b, box: [1, 1, 1], position: [0, 0, 0.6]}\n")
    out = tmp_path / "out"
    assert main(["assemble", str(asm), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "penetration depth in [" in err[0] and "(0, 0, 1)" in err[0]
    report = json.loads((out / "report.json").read_text())
    assert report["status"] == "invalid_input"
    depth = report["overlap"]["penetration_depth"]
    assert report["overlap"]["part"] == "b" and report["overlap"]["other"] == "a"
    assert depth["lower"] <= 0.4 <= depth["upper"]
    assert depth["direction"] == pytest.approx([0.0, 0.0, 1.0])


def test_depth_refuses_a_tolerance_as_wide_as_the_pair(pair, capsys):
    assert main(["depth", str(pair[0]), str(pair[1]), "--tolerance", "1e3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("minkplan: error: tolerance = 1000.0: ")
    assert "use at most 0.2" in err[0]  # a tenth of the pair's 2.0 diagonal (1 × 1.75 × 1)


def _open_box(path) -> None:
    """A unit box with one square (two triangles) removed, written at ``path``."""
    box = shapes.box()
    trimesh.Trimesh(box.vertices, box.faces[:-2], process=False).export(path)


def test_a_degenerate_face_dropped_is_on_the_line(pair, tmp_path, capsys):
    """A face ``f 1 1 2`` (a repeated vertex) is dropped to make the solid, and the line
    says so with the count, as it says a turned face."""
    box = shapes.box()
    degenerate = tmp_path / "degenerate.obj"
    degenerate.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in box.vertices.tolist())
                          + "".join(f"f {i + 1} {j + 1} {k + 1}\n"
                                    for i, j, k in [*box.faces.tolist(), [0, 0, 1]]))
    assert main(["depth", str(degenerate), str(pair[1])]) == 0
    line = capsys.readouterr().out.strip()
    assert line.endswith(f"; made a solid by: {degenerate} removed_collapsed_faces 1"), line


def test_depth_and_minkowski_repair_an_open_mesh_with_repair(pair, tmp_path, capsys):
    """Without --repair the refusal names it; with it the commands work and say what they
    changed to make a solid."""
    open_box = tmp_path / "open.stl"
    _open_box(open_box)
    out = tmp_path / "sum.stl"
    commands = [["depth", str(open_box), str(pair[1])],
                ["minkowski", str(open_box), str(pair[1]), "-o", str(out), "--no-progress"]]
    for argv in commands:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "not watertight" in err[0] and "--repair" in err[0], err
        assert not out.exists()
        assert main([*argv, "--repair"]) == 0, argv
        line = capsys.readouterr().out.strip()
        made = line.split("; made a solid by: ", 1)[1]
        assert made.startswith(f"{open_box} ") and "filled_holes 1" in made, line
    assert line.startswith(f"wrote {out}") and trimesh.load(out).is_watertight
    assert main(["depth", str(open_box), str(pair[1]), "--repair", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["lower"] <= 0.25 + 1e-6 and r["upper"] >= 0.25 - 1e-6
    assert r["stats"]["changes"]["a"]["filled_holes"] == 1
