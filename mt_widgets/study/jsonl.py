"""Crash-safe JSON-lines files: one record a line, appended under a lock and fsync-ed, read
tolerating the one line a killed writer can tear.

The study log (``mt_widgets.study.log``: participant logs, enrolments, outcomes) and the class
progress files (``mt_widgets.classroom``) are both written and read through this module, so the
rules a crash relies on are written once:

- ``Lock``: an exclusive ``fcntl.flock`` on a lock file; it dies with its process, so a crash
  never leaves a file locked.
- ``append_line``: ends a torn last line with a newline first (its bytes stay: append-only), so
  the new record never gets glued onto it; writes the record with ``write_all`` and fsyncs it
  (and the folder when the file is new) before returning.
- A write that fails (a full disk, a quota, an I/O error) is taken back: the file is cut back to
  its length before the write (``take_back``), so no half line is left, and ``NotSavedError``
  says that nothing of the record was stored. Nothing is acknowledged that is not on disk, and
  the next write, once there is room again, goes on from the last stored record.
- ``read_jsonl``: every newline-ended line, parsed or marked as not parsing, and the bytes after
  the last newline (a record still being written, or torn by a kill) reported apart. What a
  reader tolerates (skip and count, or only lines a later record says it repaired) is its own
  policy; the parsing is this one.

Every write goes through ``write_all`` (looked up at call time), so a test can kill a process
half-way through one (tests/study/test_crash_safety.py).
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path


class LogError(RuntimeError):
    """A log or study folder that cannot be used as asked (in use, corrupt, mismatched)."""


class NotSavedError(LogError):
    """A record that could not be stored (the disk is full, a quota is reached, an I/O error):
    nothing of it is in the file, and the file reads as before. ``errno`` is the system's error
    number (``errno.ENOSPC``, ``errno.EDQUOT``, ``errno.EIO``...)."""

    def __init__(self, message: str, errno_: int | None = None):
        super().__init__(message)
        self.errno = errno_


#: Why a write failed, in words a page can show (the system's own words otherwise).
_WHY = {errno.ENOSPC: "the disk holding it is full", errno.EDQUOT: "its disk quota is used up",
        errno.EIO: "the disk reported an input/output error", errno.EFBIG: "the file reached its size limit"}


def why_not_saved(error: OSError) -> str:
    """An OSError of a write as words: "the disk holding it is full (No space left on device)"."""
    words = error.strerror or str(error)
    return f"{_WHY[error.errno]} ({words})" if error.errno in _WHY else words


def take_back(fd: int, length: int) -> None:
    """Cuts the file open at ``fd`` back to ``length`` bytes, on disk: what a failed write left is gone.
    (Shortening a file needs no free space.)"""
    os.ftruncate(fd, length)
    os.fsync(fd)


def write_all(fd: int, data: bytes) -> None:
    """Writes every byte (regular files take it in one call; the loop covers signals)."""
    view = memoryview(data)
    while view:
        written = os.write(fd, view)
        view = view[written:]


def fsync_folder(folder: Path) -> None:
    """Makes a new file's directory entry durable (it is only once the directory is synced)."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class Lock:
    """An exclusive ``flock`` on ``path``, waiting up to ``timeout_s`` seconds.

    Args:
        path: the lock file (created, with its folder, if missing).
        what: the locked thing in words, for the error ("participant 'P01'").
        timeout_s: how long to wait for another holder to let go.

    Raises:
        LogError: still held by another process after ``timeout_s``.
    """

    def __init__(self, path: Path, what: str, timeout_s: float = 0.0):
        path.parent.mkdir(exist_ok=True)
        self.path = path
        self.fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return
            except OSError as error:
                if error.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    os.close(self.fd)
                    raise
                if time.monotonic() >= deadline:
                    os.close(self.fd)
                    raise LogError(f"{what} is in use by another session (a second tab, kernel or process); "
                                   f"close it first, or wait for it to end") from None
                time.sleep(0.05)

    def release(self) -> None:
        if self.fd is not None:
            os.close(self.fd)  # closing the descriptor releases the flock
            self.fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


def encode(record: dict) -> bytes:
    """One record as a compact JSON line (NaN refused: it is not JSON)."""
    return (json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n").encode()


def append_line(path: Path, line: bytes | Callable[[int], bytes]) -> int:
    """Appends one line to ``path`` (created if missing) and returns once it is on disk; raises
    ``NotSavedError`` (the file as before) when it cannot.

    The caller holds the file's ``Lock``. A torn last line (a writer killed mid-line) is ended
    with a newline first, so the new line starts a line of its own; the torn bytes stay.

    Args:
        path: the JSON-lines file.
        line: the bytes to append (ending in a newline), or a function of the torn bytes found
            (0 if none) returning them, so the record can say that it repairs a torn line.

    Returns:
        The bytes of the torn last line that was ended (0 if none).
    """
    created = not path.exists()
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_APPEND, 0o644)
    try:
        size = os.fstat(fd).st_size
        torn = 0
        if size and os.pread(fd, 1, size - 1) != b"\n":
            torn = size - (os.pread(fd, size, 0).rfind(b"\n") + 1)
        data = line(torn) if callable(line) else line
        try:
            write_all(fd, (b"\n" if torn else b"") + data)
            os.fsync(fd)
        except OSError as error:
            try:
                take_back(fd, size)
            except OSError:
                pass  # a half line stays: the next append ends it first (above), as after a kill
            raise NotSavedError(f"{path.name}: this record could not be saved: {why_not_saved(error)}; nothing of "
                                f"it was written", error.errno) from error
    finally:
        os.close(fd)
    if created:
        fsync_folder(path.parent)
    return torn


@dataclass(frozen=True)
class JsonLine:
    """One line of a JSON-lines file as read.

    Attributes:
        number: 1-based line number.
        raw: its bytes, without the newline.
        value: the JSON object it holds, or None when it holds none (torn, garbled, blank, or
            JSON that is not an object).
    """

    number: int
    raw: bytes
    value: dict | None

    @property
    def blank(self) -> bool:
        return not self.raw.strip()


@dataclass(frozen=True)
class JsonlContents:
    """A JSON-lines file as read.

    Attributes:
        lines: every newline-ended line, in order.
        tail: what follows the last newline, or None when the file ends with one: a record still
            being written, torn by a kill, or complete but for its newline (then ``value`` is set).
    """

    lines: list[JsonLine]
    tail: JsonLine | None

    @property
    def torn_tail(self) -> int:
        """Bytes of an unfinished last line that holds no complete record (0 if none)."""
        return len(self.tail.raw) if self.tail is not None and self.tail.value is None else 0


def _parse(number: int, raw: bytes) -> JsonLine:
    try:
        value = json.loads(raw)
    except ValueError:  # includes a UnicodeDecodeError from torn multi-byte text
        value = None
    return JsonLine(number, raw, value if isinstance(value, dict) else None)


def read_jsonl(path) -> JsonlContents:
    """Reads a JSON-lines file, parsing every line and reporting a torn last one apart.

    Raises:
        OSError: the file cannot be read.
    """
    pieces = Path(path).read_bytes().split(b"\n")
    # The last piece is what follows the final newline: empty, or an unfinished line.
    tail = pieces.pop()
    lines = [_parse(number, raw) for number, raw in enumerate(pieces, start=1)]
    return JsonlContents(lines, _parse(len(pieces) + 1, tail) if tail else None)
