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
from typing import Any

__all__ = ["ResultsFile"]

log = logging.getLogger(__name__)


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
        self._rewrite()
        self._file = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 (kept open)

    def _read(self) -> list[dict[str, Any]]:
        if not self.path.exists():
            return []
        records = []
        for number, line in enumerate(self.path.read_text(encoding="utf-8").splitlines(), 1):
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                log.warning("%s:%d: an incomplete record (the batch was cut short there); "
                            "its task runs again", self.path, number)
                continue
            if isinstance(record, dict) and "key" in record:
                records.append(record)
        return records

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
        self._file.write(json.dumps(record, allow_nan=False) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())
        self.records.append(record)

    def close(self) -> None:
        self._file.close()
