"""The decomposition cache's entries on disk: one file per key, written atomically
(a temporary file in the same folder, synced, then renamed), read back only when it is a
regular file of bounded size whose checksum, key and content fit the part.

An entry is ``MAGIC``, the SHA-256 of the payload, the payload's length, then the payload:
an ``.npz`` of the pieces' points, their offsets and the metadata (key, exact, excess,
deficit, method, bodies). Anything else found under an entry's name is logged, deleted
and recomputed, never trusted.

Entry points: :func:`load_entry`, :func:`store_entry` (used by :mod:`planner.decompose`).
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import math
import os
import stat
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["FORMAT_VERSION", "SUFFIX", "load_entry", "store_entry"]

log = logging.getLogger("planner.decompose")

FORMAT_VERSION = 1
"""Part of every cache key: a new layout of the entries makes new keys."""
_MAGIC = b"MKPDEC01"
SUFFIX = ".mkdec"
_HEADER = len(_MAGIC) + 32 + 8  # magic, sha256 of payload, payload length


def _encode(pieces: list[np.ndarray], meta: dict) -> bytes:
    offsets = np.cumsum([0] + [len(p) for p in pieces]).astype("<i8")
    points = (
        np.concatenate(pieces).astype("<f8")
        if pieces
        else np.zeros((0, 3), dtype="<f8")
    )
    buffer = io.BytesIO()
    np.savez(
        buffer,
        points=points,
        offsets=offsets,
        meta=np.frombuffer(json.dumps(meta, sort_keys=True).encode(), dtype=np.uint8),
    )
    payload = buffer.getvalue()
    digest = hashlib.sha256(payload).digest()
    return _MAGIC + digest + len(payload).to_bytes(8, "little") + payload


class _CorruptEntry(Exception):
    pass


def _decode(data: bytes, key: str):
    if len(data) < _HEADER or not data.startswith(_MAGIC):
        raise _CorruptEntry("bad header")
    digest = data[len(_MAGIC):len(_MAGIC) + 32]
    length = int.from_bytes(data[len(_MAGIC) + 32:_HEADER], "little")
    payload = data[_HEADER:]
    if len(payload) != length:
        raise _CorruptEntry(f"truncated ({len(payload)} of {length} payload bytes)")
    if hashlib.sha256(payload).digest() != digest:
        raise _CorruptEntry("checksum mismatch")
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as archive:
            points = np.array(archive["points"], dtype=np.float64)
            offsets = np.array(archive["offsets"], dtype=np.int64)
            meta = json.loads(bytes(archive["meta"]).decode())
    except Exception as exc:  # a checksummed payload should never fail to parse
        raise _CorruptEntry(f"unreadable payload ({type(exc).__name__})") from exc
    if not isinstance(meta, dict) or meta.get("key") != key:
        raise _CorruptEntry("entry belongs to another key")
    if (
        points.ndim != 2
        or points.shape[1] != 3
        or offsets.ndim != 1
        or offsets.size < 2
        or offsets[0] != 0
        or offsets[-1] != len(points)
        or np.any(np.diff(offsets) < 1)
    ):
        raise _CorruptEntry("inconsistent arrays")
    pieces = [points[a:b].copy() for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    return pieces, meta


MAX_ENTRY_BYTES = 1 << 30
"""The largest cache entry read (1 GiB; a CoACD decomposition takes kilobytes to
megabytes): anything larger is not an entry this code wrote."""


def _read_regular(entry: Path) -> bytes:
    """The bytes of ``entry`` if it is a regular file (not a link, a FIFO or a device)
    of at most :data:`MAX_ENTRY_BYTES`.

    Raises:
        FileNotFoundError: no entry.
        _CorruptEntry: anything else there.
    """
    try:
        fd = os.open(entry, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
                     | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise
    except OSError as exc:  # ELOOP: a symbolic link
        raise _CorruptEntry(f"not a regular file ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise _CorruptEntry("not a regular file")
        if info.st_size > MAX_ENTRY_BYTES:
            raise _CorruptEntry(f"{info.st_size} bytes, over {MAX_ENTRY_BYTES}")
        return handle.read(MAX_ENTRY_BYTES + 1)


def _check_content(pieces: list[np.ndarray], meta: dict, box: np.ndarray) -> None:
    """An entry's pieces must fit the part they claim to decompose: finite points, at
    least four per piece, none outside the part's box grown by the recorded excess.

    Raises:
        _CorruptEntry: they do not.
    """
    try:
        excess = float(meta["excess"])
        for field in ("exact", "deficit", "method", "bodies"):
            meta[field]  # noqa: B018 (present, or the entry is not ours)
    except (KeyError, TypeError, ValueError):
        raise _CorruptEntry("incomplete metadata") from None
    if not math.isfinite(excess) or excess < 0:
        raise _CorruptEntry(f"impossible excess {excess!r}")
    slack = excess + 1e-6 * float(np.linalg.norm(box[1] - box[0]))
    for piece in pieces:
        if len(piece) < 4 or not np.all(np.isfinite(piece)):
            raise _CorruptEntry("a piece with fewer than 4 points or a non-finite point")
        if np.any(piece < box[0] - slack) or np.any(piece > box[1] + slack):
            raise _CorruptEntry("a piece outside the part's box")


def load_entry(entry: Path, key: str, name: str, box: np.ndarray | None = None):
    try:
        data = _read_regular(entry)
        pieces, meta = _decode(data, key)
        if box is not None:
            _check_content(pieces, meta, box)
        return pieces, meta
    except FileNotFoundError:
        return None
    except OSError as exc:
        log.warning("%s: cannot read decomposition cache entry %s (%s)", name, entry, exc)
        return None
    except _CorruptEntry as exc:
        log.warning(
            "%s: corrupt decomposition cache entry %s (%s); deleting it and recomputing",
            name, entry, exc,
        )
        try:
            entry.unlink()
        except OSError:
            pass
        return None


def store_entry(directory: Path, entry: Path, pieces, meta, name: str) -> None:
    data = _encode(pieces, meta)
    temp = None
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, temp = tempfile.mkstemp(dir=directory, prefix=f".{entry.stem[:16]}.", suffix=".tmp")
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temp, entry)
        temp = None
        _fsync_directory(directory)
    except OSError as exc:
        log.warning(
            "%s: cannot write decomposition cache in %s (%s); continuing without cache",
            name, directory, exc,
        )
    finally:
        if temp is not None:
            try:
                os.unlink(temp)
            except OSError:
                pass


def _fsync_directory(directory: Path) -> None:
    if os.name != "posix":
        return
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
