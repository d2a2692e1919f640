"""Progress on a terminal (``planner.progress``): the status line of every long command
appears when stderr is a terminal (a pseudo-terminal here), not when it is a pipe, and
not with ``--no-progress``; nested lines show the innermost and give the line back."""

from __future__ import annotations

import os
import pty
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

from planner import progress
from planner.progress import StatusLine

ROOT = Path(__file__).resolve().parents[1]
PEG = ROOT / "scenarios" / "peg_in_hole"

# (command after `minkplan`, a status line it shows); {out} is a fresh folder
COMMANDS = {
    "minkowski": (["minkowski", str(PEG / "block.stl"), str(PEG / "peg.stl"), "-o",
                   "{out}/sum.stl"], "b (peg.stl): convolution facets"),
    "offset": (["offset", str(PEG / "peg.stl"), "-r", "0.5", "--eps", "0.5", "-o",
                "{out}/grown.stl"], "minkplan: growing"),
    "depth": (["depth", str(PEG / "block.stl"), str(PEG / "peg.stl")],
              "minkplan: depth of"),
    "plan": (["plan", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--out", "{out}"],
             "minkplan: building the C-space"),
    "plan --html": (["plan", str(ROOT / "scenarios" / "peg_in_hole.yaml"), "--out", "{out}",
                     "--html"], "minkplan: drawing the scene"),
    "assemble": (["assemble", str(ROOT / "scenarios" / "assemblies" / "peg_in_block.yaml"),
                  "--out", "{out}"], "peg_in_block: step 1: straight removals"),
}


def minkplan(args: list[str], out: Path, *, terminal: bool) -> tuple[int, str]:
    """Run ``minkplan ARGS`` with stderr on a pseudo-terminal (``terminal``) or a pipe;
    returns the exit code and everything written to stderr."""
    command = [sys.executable, "-m", "planner", *[a.format(out=out) for a in args]]
    if not terminal:
        proc = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=out)
        return proc.returncode, proc.stderr
    controller, stderr = pty.openpty()
    child = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=stderr, cwd=out)
    os.close(stderr)
    seen = bytearray()
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:
        ready, _, _ = select.select([controller], [], [], 1.0)
        if not ready:
            if child.poll() is not None:
                break
            continue
        try:
            chunk = os.read(controller, 65536)
        except OSError:  # the child closed its end
            break
        if not chunk:
            break
        seen += chunk
    os.close(controller)
    return child.wait(timeout=60), seen.decode(errors="replace")


@pytest.mark.parametrize("name", list(COMMANDS))
def test_a_long_command_shows_its_status_line_on_a_terminal_only(tmp_path, name):
    args, expected = COMMANDS[name]
    for terminal, extra in ((True, []), (False, []), (True, ["--no-progress"])):
        out = tmp_path / f"{terminal}{len(extra)}"
        out.mkdir()
        code, err = minkplan(args + extra, out, terminal=terminal)
        assert code == 0, err
        if terminal and not extra:
            assert expected in err, err
            assert "\r\033[K" in err  # rewritten in place, cleared at the end
        else:
            assert expected not in err and "\r\033[K" not in err, (terminal, extra, err)


def test_lines_nest_and_the_outer_one_comes_back(capsys):
    with StatusLine(True) as outer:
        outer.show("outer step")
        with StatusLine(True) as inner:
            inner.show("inner step")
        outer.show("outer again")
    err = capsys.readouterr().err
    assert err.split("\r\033[K") == ["", "outer step", "inner step", "outer step",
                                     "outer again", ""]


def test_a_log_record_clears_the_line_and_the_line_comes_back(capsys):
    import logging

    log = logging.getLogger("minkplan.test_progress")
    handler = progress.LogAround()  # (stderr as it is now: pytest's capture)
    handler.setFormatter(logging.Formatter("%(levelname)s %(message)s"))
    log.addHandler(handler)
    try:
        with StatusLine(True) as line:
            line.show("growing the part")
            log.warning("a fault")
        log.warning("no line shown")
    finally:
        log.removeHandler(handler)
    err = capsys.readouterr().err
    # the record on a line of its own, the status line drawn again after it
    assert err.split("\r\033[K") == ["", "growing the part", "WARNING a fault\n",
                                      "growing the part", "WARNING no line shown\n"]


def test_a_disabled_line_writes_nothing(capsys):
    with StatusLine(False) as line:
        line.show("hidden")
    assert capsys.readouterr().err == ""
    assert StatusLine(None).enabled is False  # pytest's captured stderr is no terminal


def test_the_ticker_shows_the_seconds_of_a_long_step(capsys, monkeypatch):
    monkeypatch.setattr(progress, "SHOW_SECONDS_AFTER", 0.0)
    monkeypatch.setattr(progress, "TICK_SECONDS", 0.01)
    seen = ""
    with StatusLine(True) as line:
        line.show("native work")
        for _ in range(500):  # the ticker writes while this thread waits
            time.sleep(0.01)
            seen += capsys.readouterr().err
            if "native work (1 s)" in seen:
                break
    assert "native work (0 s)" in seen and "native work (1 s)" in seen
    assert capsys.readouterr().err.endswith("\r\033[K")
