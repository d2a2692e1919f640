"""`minkplan assemble`: exit codes, outputs, one-line errors."""

import json
from pathlib import Path

from planner.cli import main

ASM = Path(__file__).resolve().parent.parent / "scenarios" / "assemblies"


def test_assemble_writes_a_sequence(tmp_path, capsys):
    out = tmp_path / "pegs"
    assert main(["assemble", str(ASM / "pegs_and_holes.yaml"), "--out", str(out),
                 "--no-progress"]) == 0
    seq = json.loads((out / "sequence.json").read_text())
    assert (out / "report.json").is_file()
    text = json.dumps(seq)
    assert "lower" in text and "upper" in text and "contact_tolerance" in text
    assert "assembly order" in capsys.readouterr().out


def test_interlocked_rings_exit_1(tmp_path, capsys):
    assert main(["assemble", str(ASM / "linked_rings.yaml"), "--out", str(tmp_path / "r"),
                 "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "ring_a" in out and "ring_b" in out


def test_bad_assembly_input_is_one_line_exit_2(tmp_path, capsys):
    assert main(["assemble", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "o")]) == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("parts:\n  - {name: a, box: [1, 1, 1]}\n  - {name: b, bx: [1, 1, 1]}\n")
    assert main(["assemble", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("minkplan: error:") for line in err)
    assert "bad.yaml" in err[1]
