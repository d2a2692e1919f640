"""Faults a run must survive: SIGKILL in the middle of a cold decomposition (the rerun is
right and the cache holds one good entry), four processes decomposing the same part into
one cold cache at once (all right, one entry), and SIGTERM in the middle of a plan (exit
143, every output whole or absent)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

_DECOMPOSE = """
import sys, numpy as np
sys.path.insert(0, {tests!r})
from test_decompose import l_bracket
from planner.decompose import decompose
sys.stdout.write("started\\n"); sys.stdout.flush()
result = decompose(l_bracket(), cache_dir={cache!r}, name="bracket", progress=False)
np.save({out!r}, np.concatenate(result.pieces))
sys.stdout.write(f"done {{result.cache_hit}}\\n")
"""


def _decompose(cache: Path, out: Path) -> subprocess.Popen:
    code = _DECOMPOSE.format(tests=str(ROOT / "tests"), cache=str(cache), out=str(out))
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)


def _entries(cache: Path) -> list[Path]:
    return sorted(p for p in cache.iterdir() if p.is_file())


def test_a_decomposition_killed_midway_leaves_no_bad_entry(tmp_path):
    cache = tmp_path / "cache"
    first = _decompose(cache, tmp_path / "killed.npy")
    assert first.stdout is not None and first.stdout.readline() == "started\n"
    time.sleep(0.2)  # inside CoACD (about 0.7 s for this part)
    first.send_signal(signal.SIGKILL)
    first.wait()
    first.stdout.close()
    again = _decompose(cache, tmp_path / "again.npy")
    out, _ = again.communicate(timeout=300)
    assert again.returncode == 0 and out.endswith("done False\n")
    fresh = _decompose(tmp_path / "fresh", tmp_path / "fresh.npy")
    fresh.communicate(timeout=300)
    np.testing.assert_array_equal(np.load(tmp_path / "again.npy"),
                                  np.load(tmp_path / "fresh.npy"))
    assert len(_entries(cache)) == 1  # the killed writer's temporary file is gone or ignored
    hit = _decompose(cache, tmp_path / "hit.npy")
    assert hit.communicate(timeout=300)[0].endswith("done True\n")


def test_four_processes_on_one_cold_cache_agree_and_leave_one_entry(tmp_path):
    cache = tmp_path / "cache"
    runs = [_decompose(cache, tmp_path / f"run{i}.npy") for i in range(4)]
    for run in runs:
        run.communicate(timeout=300)
        assert run.returncode == 0
    results = [np.load(tmp_path / f"run{i}.npy") for i in range(4)]
    for result in results[1:]:
        np.testing.assert_array_equal(result, results[0])
    assert len(_entries(cache)) == 1


def test_sigterm_mid_plan_exits_143_with_whole_outputs_or_none(tmp_path):
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "planner", "plan",
                            str(ROOT / "scenarios" / "peg_in_hole_0.01.yaml"), "--out",
                            str(out), "--html", "--no-progress"], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    assert run.stdout is not None
    assert "found" in run.stdout.readline()  # planned; the scene takes seconds more
    run.send_signal(signal.SIGTERM)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 143, err
    assert err.strip().splitlines()[-1] == "minkplan: terminated"
    written = sorted(p.name for p in out.iterdir())
    assert written == ["path.json", "report.json"], written  # the page: none, not half
    for name in written:
        if name.endswith(".json"):
            json.loads((out / name).read_text())  # whole, not cut short


_STUCK_IN_NATIVE_CODE = """
import sys
import numpy as np
import planner.cli as cli

cli.TERMINATE_GRACE = 0.5


def stuck(argv):
    matrix = np.random.default_rng(0).random((4000, 4000))
    print("ready", flush=True)
    np.linalg.eigvals(matrix)  # one native call of many seconds, the GIL released
    return 0


cli._main = stuck
sys.exit(cli.main([]))
"""


def test_sigterm_ends_a_command_stuck_in_native_code(tmp_path):
    """Python runs a signal handler only between its own steps: SIGTERM during one long
    native call (the core's, here LAPACK's) ends the process after the grace anyway,
    with the same exit code and line."""
    script = tmp_path / "stuck.py"
    script.write_text(_STUCK_IN_NATIVE_CODE)
    run = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True, cwd=ROOT)
    assert run.stdout is not None and run.stdout.readline().strip() == "ready"
    time.sleep(0.5)  # inside the native call
    start = time.perf_counter()
    run.send_signal(signal.SIGTERM)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 143, err
    assert err.strip().splitlines()[-1] == "minkplan: terminated"
    assert time.perf_counter() - start < 10.0  # the call alone takes far longer

