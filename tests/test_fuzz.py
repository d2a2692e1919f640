"""A seeded sample of the fuzz harness (``tests/fuzz/``) in the default suite: about 300
bad inputs by family through ``minkplan``'s command line, each of which must end clean
(exit 0, 1 or 2 with one line on stderr, no traceback, signal, hang, memory blow-up,
Python warning or half-written output). ``python tests/fuzz/run_fuzz.py`` is the full
run (10,000 cases)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "fuzz"))

from cases import FAMILIES, Case, cases  # noqa: E402
from runner import classify, run_cases  # noqa: E402

SAMPLE_ROUNDS = 7
"""Rounds of every family's cases in the sample (about 45 cases a round)."""


def test_a_seeded_sample_of_bad_inputs_ends_clean(tmp_path):
    sample = cases(seed=20261202, rounds=SAMPLE_ROUNDS)
    assert len(sample) >= 300 and {c.family for c in sample} == set(FAMILIES)
    results = run_cases(sample, tmp_path, timeout=60.0, memory_mb=4096.0)
    bad = [f"{r.case.name} [{r.outcome}] minkplan {' '.join(r.case.argv)}: {r.detail}"
           for r in results if r.outcome != "clean"]
    assert not bad, "\n".join(bad)


def test_the_classifier_tells_each_outcome_apart():
    assert classify(2, "minkplan: error: s.yaml:3: start: expected 3 numbers\n", "") \
        == ("clean", "minkplan: error: s.yaml:3: start: expected 3 numbers")
    assert classify(2, "Traceback (most recent call last):\n  ...\nValueError: x\n",
                    "")[0] == "traceback"
    assert classify(3, "minkplan: internal error in plan: KeyError: 'a'\n", "")[0] \
        == "internal"
    assert classify(0, "x.py:3: RuntimeWarning: overflow encountered\n", "")[0] == "warning"
    assert classify(2, "minkplan: error: bad\n", "path.json does not parse")[0] == "partial"
    assert classify(2, "line one\nline two\n", "")[0] == "traceback"
    assert classify(1, "WARNING planner.io: repaired\nminkplan: no path\n", "")[0] == "clean"


FOUND_BY_FULL_RUNS = [
    # a control character: PyYAML's reader refuses it while the loader is made
    Case("control_character", "assembly", ("assemble", "a.yaml", "--out", "out"),
         {"a.yaml": b"\x1fparts: []\n"}),
    Case("control_character", "scenario", ("plan", "s.yaml", "--out", "out"),
         {"s.yaml": b"robot: {box: [1, 1, 1]}\x1f\n"}),
]
"""Cases the full run (``run_fuzz.py``) found, kept once fixed."""


def test_what_full_runs_found_stays_fixed(tmp_path):
    results = run_cases(FOUND_BY_FULL_RUNS, tmp_path, timeout=60.0)
    assert [(r.outcome, r.code) for r in results] == [("clean", 2)] * len(results), \
        [r.detail for r in results]
