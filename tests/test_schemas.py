"""Every JSON file minkplan writes names its schema (``"schema": "minkplan/NAME/1"``) and
validates against ``docs/schemas/NAME.schema.json``: the files of real runs of ``plan``
(a path, a proved no-path), ``assemble`` (a sequence, an interlock), ``minkowski --stats``,
``depth --json`` and a batch's records (an answer and a failure); the timing keys are the
same in every run."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from planner.batch import Limits, find_problems, make_tasks
from planner.batch.execute import execute
from planner.batch.worker import run_task
from planner.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCHEMAS = ROOT / "docs" / "schemas"


def _validator(name: str) -> jsonschema.Draft202012Validator:
    schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _valid(name: str, document: dict) -> None:
    assert document["schema"] == f"minkplan/{name}/1"
    errors = [e.message for e in _validator(name).iter_errors(document)]
    assert not errors, (name, errors[:3])


def _read(path: Path) -> dict:
    return json.loads(path.read_text())


@pytest.mark.parametrize("scenario, files", [
    ("peg_in_hole.yaml", ("path", "report")),
    ("sealed_chamber.yaml", ("path", "report", "certificate")),
])
def test_plan_files_validate(tmp_path, scenario, files):
    main(["plan", str(ROOT / "scenarios" / scenario), "--out", str(tmp_path), "--no-progress"])
    for name in files:
        _valid(name, _read(tmp_path / f"{name}.json"))
    if "certificate" in files:  # the report summarises the certificate it wrote
        assert _read(tmp_path / "report.json")["certificate"]["verified"] is True


@pytest.mark.parametrize("assembly", ["pegs_and_holes.yaml", "linked_rings.yaml",
                                      "hooked_pair.yaml"])
def test_assembly_files_validate(tmp_path, assembly):
    main(["assemble", str(ROOT / "scenarios" / "assemblies" / assembly), "--out",
          str(tmp_path), "--no-progress"])
    _valid("sequence", _read(tmp_path / "sequence.json"))
    _valid("assembly_report", _read(tmp_path / "report.json"))


def test_the_report_of_an_overlapping_assembly_validates(tmp_path):
    block = tmp_path / "overlap.yaml"
    block.write_text("parts:\n  - {name: a, box: [2, 2, 2]}\n"
                     "  - {name: b, box: [2, 2, 2], position: [1, 0, 0]}\n")
    assert main(["assemble", str(block), "--out", str(tmp_path / "out"),
                 "--no-progress"]) == 2
    report = _read(tmp_path / "out" / "report.json")
    _valid("assembly_error", report)
    assert report["overlap"]["penetration_depth"] is not None


def test_the_files_of_an_interference_fit_validate(tmp_path):
    fit = tmp_path / "fit.yaml"
    fit.write_text("parts:\n  - {name: a, box: [2, 2, 2]}\n"
                   "  - {name: b, box: [1, 1, 1], position: [0, 0, 1.48]}\n")
    assert main(["assemble", str(fit), "--out", str(tmp_path / "short"), "--no-progress",
                 "--interference", "0.01"]) == 2
    refused = _read(tmp_path / "short" / "report.json")
    _valid("assembly_error", refused)
    assert refused["overlap"]["interference"] == 0.01
    assert main(["assemble", str(fit), "--out", str(tmp_path / "ok"), "--no-progress",
                 "--interference", "0.03"]) == 0
    sequence, report = _read(tmp_path / "ok" / "sequence.json"), _read(tmp_path / "ok" /
                                                                       "report.json")
    _valid("sequence", sequence)
    _valid("assembly_report", report)
    assert sequence["interference"] == report["interference"] == 0.03
    assert [(o["part"], o["other"]) for o in report["overlaps"]] == [("b", "a")]


def test_minkowski_stats_validate(tmp_path):
    block = ROOT / "scenarios" / "_schema_examples" / "block.stl"
    peg = ROOT / "scenarios" / "_schema_examples" / "peg.stl"
    stats = tmp_path / "stats.json"
    assert main(["minkowski", str(block), str(peg), "--mirror-b", "-o",
                 str(tmp_path / "sum.stl"), "--stats", str(stats), "--no-progress"]) == 0
    _valid("minkowski_stats", _read(stats))


def test_depth_json_validates(capsys):
    block = ROOT / "scenarios" / "_schema_examples" / "block.stl"
    peg = ROOT / "scenarios" / "_schema_examples" / "peg.stl"
    assert main(["depth", str(block), str(peg), "--json", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert len(out.splitlines()) == 1
    _valid("depth", json.loads(out))


def test_a_refused_depth_is_a_json_line_too(tmp_path, capsys):
    block = ROOT / "scenarios" / "_schema_examples" / "block.stl"
    missing = tmp_path / "missing.stl"
    assert main(["depth", str(block), str(missing), "--json", "--no-progress"]) == 2
    captured = capsys.readouterr()
    document = json.loads(captured.out)
    _valid("depth_error", document)
    assert document["b"] == str(missing) and "file not found" in document["error"]
    assert captured.err.strip() == f"minkplan: error: {document['error']}"


@pytest.mark.parametrize("scenario, planner", [
    ("peg_in_hole.yaml", "minkplan"),          # found, exact source: no decomposition
    ("bug_trap.yaml", "minkplan"),             # found, decomposed
    ("sealed_chamber.yaml", "minkplan"),       # a certificate, no shortcut or validation
    ("start_in_collision.yaml", "minkplan"),   # no search at all
    ("peg_in_hole.yaml", "ompl:RRTConnect"),   # no octree
])
def test_the_timing_keys_are_the_same_in_every_run(tmp_path, scenario, planner):
    from planner.planning.report import STAGES

    main(["plan", str(ROOT / "scenarios" / scenario), "--out", str(tmp_path), "--planner",
          planner, "--no-progress"])
    path, report = _read(tmp_path / "path.json"), _read(tmp_path / "report.json")
    assert list(path["timings"]) == list(report["seconds"]) == list(STAGES)
    assert path["timings"]["total"] > 0
    _valid("path", path)
    _valid("report", report)


def test_batch_records_validate():
    problems = find_problems([ROOT / "scenarios" / "bug_trap.yaml"])
    task = make_tasks(problems, ["minkplan"], 1)[0]
    _valid("batch_record", execute(task))
    _valid("batch_record", run_task(task.to_json(), Limits(memory_limit_mb=1)))


def test_a_file_that_breaks_its_schema_is_caught(tmp_path):
    main(["plan", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--out", str(tmp_path),
          "--no-progress"])
    document = _read(tmp_path / "path.json")
    document["status"] = "maybe"
    document["waypoints"] = [[0.0, 1.0]]
    messages = {e.validator for e in _validator("path").iter_errors(document)}
    assert {"enum", "minItems"} <= messages


def test_every_schema_names_its_file():
    names = {p.name.removesuffix(".schema.json") for p in SCHEMAS.glob("*.schema.json")}
    assert names == {"path", "report", "certificate", "sequence", "assembly_report",
                     "assembly_error", "minkowski_stats", "batch_record", "depth",
                     "depth_error"}
    for name in names:
        schema = json.loads((SCHEMAS / f"{name}.schema.json").read_text())
        assert schema["properties"]["schema"]["const"] == f"minkplan/{name}/1"
