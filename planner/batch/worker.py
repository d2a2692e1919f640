"""A batch worker's side of a task: it runs the task in its child process
(:mod:`planner.batch.child`) and enforces the task's wall-clock and memory limits.

Each Ray worker process keeps one child, started at its first task with ``planner``
imported, and reuses it (an import costs about a second; most tasks take less). While a
task runs, the worker watches the child's resident memory every 50 ms; a task over
``memory_limit_mb`` or ``task_timeout`` has its child killed and is recorded as
``memory_limit`` or ``timeout``; a child that dies by itself is ``crashed`` (with its
signal and the last line it wrote to stderr). Either way the next task gets a new child.
The child is killed with its worker (``PR_SET_PDEATHSIG``), so a worker that Ray loses
and retries leaves nothing running.

Entry point: :func:`run_task` (the body of the Ray task).
"""

from __future__ import annotations

import ctypes
import json
import os
import select
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from typing import IO, Any

from planner.output import schema_id

from .tasks import Task

__all__ = ["Limits", "resident_mb", "run_task"]

_POLL_SECONDS = 0.05
_START_SECONDS = 300.0
"""How long a new child may take to import ``planner`` (about a second on a warm disk)."""
_PAGE = os.sysconf("SC_PAGE_SIZE")
_PR_SET_PDEATHSIG = 1


@dataclass(frozen=True)
class Limits:
    """Per-task limits: wall-clock seconds and resident memory in MB (``None``: none)."""

    task_timeout: float | None = None
    memory_limit_mb: float | None = None


def _libc_prctl():
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):  # not Linux: the worker's exit closes stdin instead
        return None


_PRCTL = _libc_prctl()
"""``prctl`` looked up once here: between fork and exec (in a threaded Ray worker) the
child must not load libraries."""


def _die_with_parent() -> None:
    """In the child, before exec: be killed when the worker dies."""
    if _PRCTL is not None:
        _PRCTL(_PR_SET_PDEATHSIG, signal.SIGKILL)


def _status_kb(pid: int, field: str) -> float:
    """A ``VmRSS``/``VmHWM`` line of ``/proc/PID/status`` in KB (0 when unreadable)."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as status:
            for line in status:
                if line.startswith(field + ":"):
                    return float(line.split()[1])
    except OSError:
        pass
    return 0.0


def resident_mb(pid: int) -> float:
    """The resident memory of process ``pid`` in MB (0 when it cannot be read)."""
    try:
        with open(f"/proc/{pid}/statm", encoding="ascii") as statm:
            return int(statm.read().split()[1]) * _PAGE / 2**20
    except (OSError, IndexError, ValueError):
        return 0.0


def _reset_peak(pid: int) -> None:
    """Restart the child's peak-memory count (``VmHWM``) for the next task."""
    try:
        with open(f"/proc/{pid}/clear_refs", "w", encoding="ascii") as refs:
            refs.write("5")
    except OSError:
        pass


class _Child:
    """The child process and its pipes."""

    def __init__(self, memory_limit_mb: float | None = None) -> None:
        self.memory_limit_mb = memory_limit_mb
        env = dict(os.environ)
        if memory_limit_mb is not None:  # the planner refuses (exit 2) before it is killed
            env["MINKPLAN_MEMORY_LIMIT"] = repr(max(CHILD_BUDGET_SHARE * memory_limit_mb / 1024,
                                                    1 / 1024))
        self.stderr: IO[bytes] = tempfile.TemporaryFile()
        # -P and a neutral folder: a source tree in the worker's folder must not shadow
        # the installed planner
        self.process = subprocess.Popen(
            [sys.executable, "-P", "-m", "planner.batch.child"], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=self.stderr, preexec_fn=_die_with_parent,
            cwd=tempfile.gettempdir(), env=env)
        self.buffer = b""
        self._wait_ready()
        self.idle_mb = resident_mb(self.process.pid)

    def _wait_ready(self) -> None:
        deadline = time.perf_counter() + _START_SECONDS
        while time.perf_counter() < deadline:
            line = self.line(_POLL_SECONDS)
            if line == b"":
                tail = self.last_error_line()
                raise ChildProcessError(f"the task process exited with code {self.kill()} "
                                        f"before its first task: {tail}")
            if line is not None:
                return
        self.kill()
        raise ChildProcessError(f"the task process did not start in {_START_SECONDS:g} s")

    def alive(self) -> bool:
        return self.process.poll() is None

    def send(self, task: Task) -> None:
        self.stderr.seek(0)
        self.stderr.truncate()
        _reset_peak(self.process.pid)
        assert self.process.stdin is not None
        self.process.stdin.write((json.dumps(task.to_json()) + "\n").encode())
        self.process.stdin.flush()

    def line(self, wait: float) -> bytes | None:
        """The answer line if it came within ``wait`` seconds; ``b""`` at end of file."""
        assert self.process.stdout is not None
        fd = self.process.stdout.fileno()
        if b"\n" not in self.buffer:
            ready, _, _ = select.select([fd], [], [], wait)
            if not ready:
                return None
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                return b""
            self.buffer += chunk
        if b"\n" not in self.buffer:
            return None
        line, self.buffer = self.buffer.split(b"\n", 1)
        return line

    def last_error_line(self) -> str:
        self.stderr.seek(0)
        lines = self.stderr.read()[-4096:].decode(errors="replace").strip().splitlines()
        return lines[-1] if lines else ""

    def kill(self) -> int:
        """Kill the child (if it still runs) and close its pipes; its exit code."""
        if self.process.poll() is None:
            self.process.kill()
        code = self.process.wait()
        for stream in (self.process.stdin, self.process.stdout, self.stderr):
            if stream is not None:
                stream.close()
        return code


_CHILD: _Child | None = None

CHILD_BUDGET_SHARE = 0.75
"""The task process's memory budget (``MINKPLAN_MEMORY_LIMIT``, :mod:`planner.budget`)
is this share of ``--memory-limit``: the rest is its interpreter, meshes and results."""


def _child(memory_limit_mb: float | None = None) -> _Child:
    global _CHILD
    if _CHILD is not None and (not _CHILD.alive()
                               or _CHILD.memory_limit_mb != memory_limit_mb):
        _CHILD.kill()
        _CHILD = None
    if _CHILD is None:
        _CHILD = _Child(memory_limit_mb)
    return _CHILD


def _failure(task: Task, status: str, message: str, seconds: float,
             peak_mb: float) -> dict[str, Any]:
    return {"schema": schema_id("batch_record"), **task.to_json(), "key": task.key,
            "status": status, "reason": status,
            "message": message, "seconds": seconds, "peak_mb": peak_mb}


def _wait(child: _Child, task: Task, limits: Limits, t0: float) -> dict[str, Any]:
    global _CHILD
    peak = 0.0
    while True:
        line = child.line(_POLL_SECONDS)
        elapsed = time.perf_counter() - t0
        if line:
            record = json.loads(line)
            record["peak_mb"] = max(peak, _status_kb(child.process.pid, "VmHWM") / 1024)
            return record
        if line == b"":  # the child died
            tail = child.last_error_line()
            code = child.kill()
            _CHILD = None
            why = f"exited with code {code}"
            if code < 0:
                try:
                    why = f"killed by {signal.Signals(-code).name}"
                except ValueError:
                    why = f"killed by signal {-code}"
            return _failure(task, "crashed", f"the task's process {why}"
                            + (f": {tail}" if tail else ""), elapsed, peak)
        peak = max(peak, resident_mb(child.process.pid))
        over = limits.memory_limit_mb is not None and peak > limits.memory_limit_mb
        late = limits.task_timeout is not None and elapsed > limits.task_timeout
        if over or late:
            child.kill()
            _CHILD = None
            if over:
                return _failure(task, "memory_limit", f"resident memory {peak:.0f} MB "
                                f"over the limit of {limits.memory_limit_mb:g} MB (the "
                                f"task's process takes {child.idle_mb:.0f} MB before any "
                                f"work)", elapsed, peak)
            return _failure(task, "timeout", f"still running after "
                            f"{limits.task_timeout:g} s (the task timeout)", elapsed, peak)


def run_task(task_json: dict[str, Any], limits: Limits) -> dict[str, Any]:
    """Run one task in this worker's child; the task's record, with the worker's host,
    process id and the task's peak resident memory (``peak_mb``)."""
    task = Task.from_json(task_json)
    child = _child(limits.memory_limit_mb)
    try:
        child.send(task)
    except BrokenPipeError:  # it died between tasks: once more, with a new one
        child = _child(limits.memory_limit_mb)
        child.send(task)
    record = _wait(child, task, limits, time.perf_counter())
    record.update(host=socket.gethostname(), worker_pid=os.getpid(),
                  child_pid=child.process.pid, task_timeout=limits.task_timeout,
                  memory_limit_mb=limits.memory_limit_mb)
    return record
