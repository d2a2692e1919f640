"""Run fuzz cases through ``minkplan``'s command line and say what each did.

Cases run in a child process (:mod:`child`) that imports ``planner`` once and calls the
CLI's ``main`` per case in the case's folder; the runner watches its time and resident
memory and kills it for a case over either (a new child takes the next case). Outcomes:

- ``clean``: exit 0, 1 or 2, at most one line on stderr besides the planner's own
  logged warnings, no Python warning, no half-written output;
- ``warning``: clean, but a Python warning (``RuntimeWarning: overflow ...``) reached
  stderr;
- ``internal``: exit 3, the CLI's one-line "internal error" (a bug it caught);
- ``traceback``: a traceback on stderr, or an exception that got past ``main``;
- ``signal``: the child died (a crash of the native module, an abort);
- ``hang``: over the time limit; ``memory``: over the memory limit;
- ``partial``: an output left half-written (a temporary file, a JSON file that does not
  parse) or any output of a bad-input exit besides an assembly's error report.
"""

from __future__ import annotations

import json
import os
import re
import select
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from cases import Case

from planner.batch.worker import resident_mb

__all__ = ["OUTCOMES", "Result", "Runner"]

OUTCOMES = ("clean", "warning", "internal", "traceback", "signal", "hang", "memory",
            "partial")
CHILD = Path(__file__).resolve().parent / "child.py"


@dataclass(frozen=True)
class Result:
    case: Case
    outcome: str
    code: int | None
    seconds: float
    detail: str


def _write(case: Case, folder: Path) -> None:
    for name, data in case.files.items():
        path = folder / name
        if data is None:
            path.mkdir(parents=True, exist_ok=True)
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)


def _partial(folder: Path, code: int | None) -> str:
    """What is half-written under ``folder/out`` (empty: nothing)."""
    out = folder / "out"
    if not out.is_dir():
        return ""
    for path in sorted(p for p in out.rglob("*") if p.is_file()):
        if ".tmp" in path.name or path.name.startswith("."):
            return f"temporary file left: {path.name}"
        if path.suffix == ".json":
            try:
                document = json.loads(path.read_text())
            except (ValueError, UnicodeDecodeError):
                return f"{path.name} does not parse"
            if code == 2 and not (isinstance(document, dict)
                                  and document.get("status") == "invalid_input"):
                return f"{path.name} written by a bad-input exit"
    return ""


def classify(code: int | None, stderr: str, partial: str) -> tuple[str, str]:
    """``(outcome, detail)`` of a finished case."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    if "Traceback (most recent call last)" in stderr:
        return "traceback", next((ln for ln in reversed(lines) if ln.strip()), "")
    if code == 3:
        return "internal", lines[-1] if lines else ""
    if partial:
        return "partial", partial
    if re.search(r"\b\w+Warning: ", stderr):
        return "warning", next(ln for ln in lines if re.search(r"\b\w+Warning: ", ln))
    said = [ln for ln in lines if not ln.startswith(("WARNING ", "INFO ", "DEBUG "))]
    if code not in (0, 1, 2) or len(said) > 1:
        return "traceback", f"exit {code}, {len(said)} lines: {said[:2]}"
    return "clean", said[0] if said else ""


class Runner:
    """The child process and the limits it runs cases under."""

    def __init__(self, *, timeout: float = 60.0, memory_mb: float = 4096.0) -> None:
        self.timeout = timeout
        self.memory_mb = memory_mb
        self.process: subprocess.Popen | None = None
        self.buffer = b""

    def _start(self) -> subprocess.Popen:
        env = {**os.environ, "PYTHONWARNINGS": "default"}
        process = subprocess.Popen([sys.executable, str(CHILD)], stdin=subprocess.PIPE,
                                   stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                   env=env, cwd="/")
        self.buffer = b""
        if self._line(process, 120.0) is None:
            raise RuntimeError("the fuzz child did not start")
        return process

    def _line(self, process: subprocess.Popen, wait: float) -> bytes | None:
        assert process.stdout is not None
        deadline = time.monotonic() + wait
        while b"\n" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            ready, _, _ = select.select([process.stdout.fileno()], [], [], min(left, 0.05))
            if ready:
                chunk = os.read(process.stdout.fileno(), 1 << 16)
                if not chunk:
                    return b""
                self.buffer += chunk
            elif resident_mb(process.pid) > self.memory_mb:
                return b"memory"
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line

    def _kill(self) -> None:
        if self.process is not None:
            self.process.kill()
            self.process.wait()
            for stream in (self.process.stdin, self.process.stdout):
                if stream is not None:
                    stream.close()
        self.process = None

    def close(self) -> None:
        self._kill()

    def run(self, case: Case, folder: Path) -> Result:
        """Run ``case`` in the empty folder ``folder``."""
        _write(case, folder)
        if self.process is None or self.process.poll() is not None:
            self.process = self._start()
        assert self.process.stdin is not None
        t0 = time.monotonic()
        self.process.stdin.write((json.dumps({"folder": str(folder),
                                              "argv": list(case.argv)}) + "\n").encode())
        self.process.stdin.flush()
        line = self._line(self.process, self.timeout)
        seconds = time.monotonic() - t0
        stderr = (folder / "stderr.txt").read_text(errors="replace") \
            if (folder / "stderr.txt").exists() else ""
        if line is None or line in (b"", b"memory"):
            code = self.process.wait() if line == b"" else self.process.poll()
            self._kill()
            if line is None:
                return Result(case, "hang", None, seconds, f"over {self.timeout:g} s")
            if line == b"memory":
                return Result(case, "memory", None, seconds, f"over {self.memory_mb:g} MB")
            name = signal.Signals(-code).name if code is not None and code < 0 else code
            return Result(case, "signal", None, seconds, f"child died: {name}")
        answer = json.loads(line)
        if answer.get("escaped"):
            return Result(case, "traceback", None, seconds,
                          answer["escaped"].strip().splitlines()[-1])
        code = answer["code"]
        outcome, detail = classify(code, stderr, _partial(folder, code))
        return Result(case, outcome, code, seconds, detail)


def run_cases(cases: list[Case], root: Path, **limits: float) -> list[Result]:
    """Every case in its own folder under ``root`` (removed after a clean outcome)."""
    runner = Runner(**limits)
    results = []
    try:
        for i, case in enumerate(cases):
            folder = root / f"{i:05d}"
            folder.mkdir(parents=True)
            result = runner.run(case, folder)
            results.append(result)
            if result.outcome == "clean":
                shutil.rmtree(folder, ignore_errors=True)
    finally:
        runner.close()
    return results
