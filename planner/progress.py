"""Progress on a terminal, in one place for every command and API function.

Two displays, both on stderr and both off unless asked for (``enabled=True``) or, by
default (``enabled=None``), unless stderr is a terminal; ``--no-progress`` passes
``False``:

- :class:`StatusLine` -- one line rewritten in place, naming the current step and the
  seconds it has taken so far (a ticker thread refreshes the count while native work,
  which releases the GIL, runs). Lines nest, the innermost shown: a decomposition's
  bodies inside a sum's stages inside the planner's C-space build; an offset, a
  penetration-depth search, an assembly's steps.
- :func:`bar` -- a counted bar (tqdm) with a rate and an ETA, for a batch's tasks (the
  one long loop that nothing else draws inside).

Log records written to stderr while a line is shown go through :class:`LogAround`, which
clears the line first and draws it again after, so a warning never runs on from it.

Entry points: :func:`shown`, :class:`StatusLine`, :func:`bar`, :class:`LogAround`.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import Any

__all__ = ["LogAround", "StatusLine", "bar", "shown"]

TICK_SECONDS = 0.5
"""How often the status line's seconds are refreshed."""

SHOW_SECONDS_AFTER = 2.0
"""A step's seconds are shown once it has taken this long (short steps just name
themselves)."""


def shown(enabled: bool | None) -> bool:
    """Whether a display asked for with ``enabled`` is shown: ``None`` means only when
    stderr is a terminal."""
    if enabled is None:
        return sys.stderr.isatty()
    return bool(enabled)


class StatusLine:
    """One status line on stderr, rewritten in place: ``"<step> (<seconds> s)"``.

    :meth:`show` starts a step; :meth:`close` (or leaving the ``with`` block) ends the
    line. Lines nest: while an inner one is open (a sum's inside the planner's C-space
    build, a decomposition's inside a sum) it is the one shown, and when it closes the
    outer one is shown again; the terminal line is cleared when the last one closes. A
    disabled line does nothing at all.

    Thread safety: every write, the ticker's included, holds one module lock.
    """

    def __init__(self, enabled: bool | None) -> None:
        self.enabled = shown(enabled)
        self._text = ""
        self._since = 0.0

    def show(self, text: str) -> None:
        """Start the step ``text`` (its clock starts now) and write the line."""
        if not self.enabled:
            return
        global _ticker
        with _lock:
            self._text, self._since = text, time.perf_counter()
            if self in _open:
                _open.remove(self)
            _open.append(self)
            self._write()
            if _ticker is None:
                _ticker = threading.Thread(target=_tick, name="minkplan-progress",
                                           daemon=True)
                _ticker.start()

    def close(self) -> None:
        """End this line: the outer one is shown again, or the terminal line cleared."""
        global _written
        with _lock:
            if self not in _open:
                return
            _open.remove(self)
            if _open:
                _open[-1]._write()
            else:
                sys.stderr.write("\r\033[K")
                sys.stderr.flush()
                _written = ""

    def __enter__(self) -> StatusLine:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _write(self, *, again: bool = True) -> None:
        """Write the line; with ``again=False`` only when it changed (the ticker)."""
        global _written
        elapsed = time.perf_counter() - self._since
        seconds = f" ({elapsed:.0f} s)" if elapsed >= SHOW_SECONDS_AFTER else ""
        line = f"{self._text}{seconds}"
        if again or line != _written:
            sys.stderr.write(f"\r\033[K{line}")
            sys.stderr.flush()
            _written = line


_lock = threading.RLock()
_open: list[StatusLine] = []
"""The open status lines, innermost last (the one shown)."""
_ticker: threading.Thread | None = None
_written = ""
"""The text on the terminal line now."""


def _tick() -> None:
    """Refresh the innermost open line's seconds until no line is open."""
    global _ticker
    while True:
        time.sleep(TICK_SECONDS)
        with _lock:
            if not _open:
                _ticker = None
                return
            _open[-1]._write(again=False)


class LogAround(logging.StreamHandler):
    """A stderr log handler that writes each record on a line of its own: the status line
    shown (if any) is cleared first and drawn again after it."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)

    def emit(self, record: logging.LogRecord) -> None:
        global _written
        with _lock:
            shown_line = bool(_written)
            if shown_line:
                self.stream.write("\r\033[K")
                _written = ""
            super().emit(record)
            if shown_line and _open:
                _open[-1]._write()


def bar(*, total: int, enabled: bool | None, unit: str, **options: Any) -> Any:
    """A tqdm bar on stderr counting to ``total`` (``options`` go to tqdm); drawing
    nothing when it is not :func:`shown`."""
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, file=sys.stderr, disable=not shown(enabled),
                **options)
