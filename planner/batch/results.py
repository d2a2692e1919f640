"""``results.jsonl``: one line per finished task, appended as each finishes.

Each record is written with one ``write`` of a whole line, flushed and synced before the
next, by the driver alone, so the file is always a sequence of whole records; a line cut
short by a crash of the driver is dropped (and logged) when the file is read back for
``--resume``.

Entry point: :class:`ResultsFile`.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import IO, Any

__all__ = ["ResultsFile", "read_records"]

log = logging.getLogger(__name__)


def read_records(path: Path, *, warn: bool = False) -> list[dict[str, Any]]:
    """The whole records of a ``results.jsonl`` (none if it does not exist); a line cut
    short is dropped (logged with ``warn``)."""
    if not path.exists():
        return []
    records = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            if warn:
                log.warning("%s:%d: an incomplete record (the batch was cut short there); "
                            "its task runs again", path, number)
            continue
        if isinstance(record, dict) and "key" in record:
            records.append(record)
    return records


class ResultsFile:
    """The batch's ``results.jsonl``.

    Args:
        path: the file.
        resume: keep the records already there (their tasks count as done); without it
            a file with records is refused, so no run is overwritten by accident.

    Raises:
        FileExistsError: ``path`` has records and ``resume`` is false.
    """

    def __init__(self, path: Path, *, resume: bool) -> None:
        self.path = path
        self.records: list[dict[str, Any]] = self._read() if resume else []
        if not resume and self.path.exists() and self.path.stat().st_size > 0:
            raise FileExistsError(f"{path} holds the results of an earlier batch; "
                                  f"use --resume to finish it, or another --out")
        if self.path.exists():
            self._rewrite()
        self._file: IO[str] | None = None  # opened at the first record: none, no file

    def _read(self) -> list[dict[str, Any]]:
        return read_records(self.path, warn=True)

    def _rewrite(self) -> None:
        """The file as the records kept (drops cut-short lines before appending)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8") as out:
            out.writelines(json.dumps(r, allow_nan=False) + "\n" for r in self.records)
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, self.path)

    @property
    def done(self) -> set[str]:
        """The keys of the tasks with a record."""
        return {r["key"] for r in self.records}

    def append(self, record: dict[str, Any]) -> None:
        if self._file is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 (kept open)
        self._file.write(json.dumps(record, allow_nan=False) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self.records.append(record)

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
