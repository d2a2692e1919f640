"""OMPL's benchmark log format: what planner.ompl_log writes, OMPL's own statistics
script (shipped with the ompl wheel) reads into its SQLite database."""

from __future__ import annotations

import math
import sqlite3

from ompl import _benchmark_statistics as statistics

from planner.ompl_log import Run, write_log


def test_the_log_reads_into_ompls_database(tmp_path, capsys):
    runs = {
        "minkplan": [Run(0.25, "found", 12.5, 0.1, True, "path"),
                     Run(0.5, "no_path", reason="certificate")],
        "ompl:RRTConnect": [Run(1.0, "found", 14.0, 0.05, True, "path"),
                            Run(20.0, "not_found", reason="time_limit")],
    }
    log = tmp_path / "Easy.log"
    write_log(log, experiment="Easy translation", setup="Easy.cfg\nhold: none", runs=runs,
              time_limit=20.0, total_seconds=21.75, seed=3, version="0.1.0")
    database = tmp_path / "bench.db"
    statistics.readBenchmarkLog(str(database), [str(log)], moveitformat=False)
    capsys.readouterr()
    with sqlite3.connect(database) as db:
        experiment = db.execute("SELECT name, timelimit, runcount, seed, version, setup "
                                "FROM experiments").fetchone()
        assert experiment == ("Easy_translation", 20.0, 2, "3", "minkplan 0.1.0",
                              "Easy.cfg\nhold: none\n")
        rows = db.execute("SELECT plannerConfigs.name, time, solved, status, solution_length, "
                          "valid, proved_no_path, reason FROM runs JOIN plannerConfigs ON "
                          "runs.plannerid = plannerConfigs.id ORDER BY runs.id").fetchall()
        statuses = dict(db.execute("SELECT value, description FROM enums WHERE name = "
                                   "'status'").fetchall())
    assert statuses == {0: "found", 1: "no_path", 2: "not_found"}
    assert rows[0] == ("minkplan", 0.25, 1, 0, 12.5, 1, 0, "path")
    assert rows[1][:4] == ("minkplan", 0.5, 0, 1) and rows[1][4] is None and rows[1][6] == 1
    assert rows[3][0] == "ompl:RRTConnect" and rows[3][3] == 2 and rows[3][7] == "time_limit"
    assert math.isclose(sum(r[1] for r in rows), 21.75)
