"""The crash-safe participant log: one append-only JSON-lines file per participant session.

A participant's events go to ``<participant>.jsonl`` (the protocol's first session) or
``<participant>.ses-<session>.jsonl`` (a later one) in a study folder
(``mt_widgets.study.study_folder``); ``.locks/`` holds lock files (``fcntl.flock``); a lock
dies with its process, so a crash never leaves a folder locked.

Every event is written with one ``os.write`` on an ``O_APPEND`` descriptor and ``fsync``-ed
before ``append`` returns, so the interface moves on only once the event is on disk (as
PsychoPy's experiment handler saves each trial as it completes). A log file is created with
``O_EXCL`` (never overwritten) and each event is written under its participant's lock after
checking that nobody else wrote since, so two processes never interleave events in one log:
a newer session (a reloaded page) takes over, and the older one is refused. A crash can leave
at most the last line torn; loading drops it,
and reopening for writing first ends it with a newline so the next event starts on a line of
its own; the ``session_resumed`` event that follows (or the ``session_started`` of a start
made again, when the torn line was the first event) records the repair, and only such repaired
lines are tolerated in the middle of a log.

Events are JSON objects with at least ``seq`` (0-based, consecutive), ``type``, ``time``
(ISO 8601 UTC), ``participant`` and ``study``; the event types, the schema version the log
carries and the migration of older logs are in ``mt_widgets.study.schema``. ``read_events``
returns the events as written; ``read_log`` returns them in the current format (migrated).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import secrets
import shutil
from pathlib import Path

import numpy as np

from . import jsonl
from .jsonl import Lock, LogError, NotSavedError, read_jsonl
from .schema import migrate_events

LOCK_FOLDER = ".locks"
#: Refuse to start a participant with less free space than this in the log folder (bytes): a
#: participant's log is about 50 kB, so this leaves room for hundreds.
MIN_FREE_BYTES = 20 * 1024 * 1024


class LogFolderError(LogError):
    """A study folder that cannot be written: refused before any participant starts."""


class ContinuedElsewhereError(LogError):
    """This session's participant was continued by another session since it last wrote (the same
    link opened in a second tab, a reload): this one is stale, and nothing it tries is written."""


def utc_now() -> str:
    """The current time as ISO 8601 UTC with milliseconds, e.g. '2025-01-31T14:03:07.123Z'."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def to_jsonable(value):
    """Plain JSON data from numpy arrays and scalars, tuples and dicts; non-finite floats -> None."""
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, str):
        return value
    raise TypeError(f"value: expected JSON-like data (numbers, text, lists, dicts, numpy arrays), "
                    f"got {type(value).__name__}")


# -- reading --------------------------------------------------------------------------------------

def read_events(path) -> tuple[list[dict], dict]:
    """Reads a participant log, tolerating a torn last line and repaired torn lines.

    Args:
        path: the ``<participant>.jsonl`` file.

    Returns:
        (events, info): the events in order, and ``info`` with ``torn_tail`` (bytes of an
        unfinished last line, 0 if none) and ``repaired_lines`` (line numbers skipped because a
        later ``session_resumed`` event records their repair).

    Raises:
        LogError: a line that does not parse in the middle of the log and was not repaired,
            or events out of sequence; naming the file and the line.
    """
    path = Path(path)
    contents = read_jsonl(path)
    complete = contents.lines
    torn_tail = len(contents.tail.raw) if contents.tail is not None else 0
    events: list[dict] = []
    pending_bad: list[int] = []
    repaired: list[int] = []
    for line in complete:
        number, event = line.number, line.value
        if event is None:
            # Blank (only a repaired tear leaves one) or not a JSON object.
            pending_bad.append(number)
            continue
        if pending_bad:
            if event.get("type") in ("session_resumed", "session_started") and event.get("repaired_torn_line"):
                repaired.extend(pending_bad)
                pending_bad = []
            else:
                raise LogError(f"{path}, line {pending_bad[0]}: not a JSON event, and no later session_resumed "
                               f"event records repairing it; the log is damaged")
        if event.get("seq") != len(events):
            raise LogError(f"{path}, line {number}: expected event seq {len(events)}, got {event.get('seq')!r}; "
                           f"events are missing, duplicated or from another log")
        events.append(event)
    if torn_tail:
        # Every byte but the final newline reached the disk: the event is complete, keep it
        # (its writer had not returned yet, so nothing after it can depend on it either way).
        event = contents.tail.value
        if event is not None and event.get("seq") == len(events) and not pending_bad:
            events.append(event)
            return events, {"torn_tail": 0, "unterminated": True, "repaired_lines": repaired}
    if pending_bad:
        # Torn lines already ended with a newline by resumes that were killed before logging the
        # repair: each such resume may leave one (its own session_resumed torn on top of the
        # last), so any run of them at the very end, and only there, is a tear still to record.
        # (Found by benchmarks/bench_kill_soak.py: three kills in a row left two.)
        if pending_bad != list(range(len(complete) - len(pending_bad) + 1, len(complete) + 1)):
            raise LogError(f"{path}, line {pending_bad[0]}: not a JSON event; the log is damaged")
        torn_tail += sum(len(complete[number - 1].raw) + 1 for number in pending_bad)
    return events, {"torn_tail": torn_tail, "unterminated": False, "repaired_lines": repaired}


def read_log(path, first_session: str = "main") -> list[dict]:
    """A participant log's events in the current schema (``mt_widgets.study.schema``): older logs
    are migrated, a log of a newer schema is refused.

    Args:
        path: the log file.
        first_session: the protocol's first session's id (what a format-1 log ran).
    """
    events, _ = read_events(path)
    return migrate_events(events, first_session, str(path))


# -- writing --------------------------------------------------------------------------------------

class ParticipantLog:
    """One participant's append-only log, held open by the session that writes to it.

    Build it with ``create`` (a new participant) or ``open`` (to continue). Each ``append``
    takes the participant's lock, checks that the file is exactly as this session left it,
    writes, fsyncs and lets go. So a session can always take over a participant whose old
    kernel is still alive (a reloaded page), and the old session, if it ever tries to write
    again, is refused instead of interleaving its events with the new one's.

    Attributes:
        path: the log file.
        events: every event, as read at opening plus those appended since.
        repaired_torn_bytes: length of a torn last line found at opening (0 if none); the next
            appended event should record it (``session_resumed`` does).
    """

    def __init__(self, path: Path, fd: int, lock_path: Path, events: list[dict], repaired_torn_bytes: int,
                 lock_timeout_s: float):
        self.path, self._fd, self._lock_path = path, fd, lock_path
        self.events = events
        self.repaired_torn_bytes = repaired_torn_bytes
        # "P07.jsonl" or a later session's "P07.ses-followup.jsonl": IDs hold no ".".
        self.participant = path.name.split(".")[0]
        self.study = events[0]["study"] if events else None
        self.lock_timeout_s = lock_timeout_s
        self._size = os.fstat(fd).st_size

    @staticmethod
    def _lock(path: Path, timeout_s: float) -> Lock:
        return Lock(path.parent / LOCK_FOLDER / (path.stem + ".lock"), f"participant {path.stem!r}", timeout_s)

    @classmethod
    def create(cls, path, study: str, lock_timeout_s: float = 5.0) -> ParticipantLog:
        """Creates a new log; refuses if the file exists (a log is never overwritten)."""
        path = Path(path)
        with cls._lock(path, lock_timeout_s) as lock:
            try:
                fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND, 0o644)
            except FileExistsError:
                raise LogError(f"participant {path.stem!r} already has a log at {path}; resume them instead "
                               f"(a log is never overwritten)") from None
            jsonl.fsync_folder(path.parent)
            log = cls(path, fd, lock.path, [], 0, lock_timeout_s)
        log.study = study
        return log

    @classmethod
    def open(cls, path, lock_timeout_s: float = 5.0) -> ParticipantLog:
        """Opens an existing log to continue it, repairing a torn last line."""
        path = Path(path)
        with cls._lock(path, lock_timeout_s) as lock:
            if not path.is_file():
                raise LogError(f"participant {path.stem!r} has no log at {path}")
            events, info = read_events(path)
            fd = os.open(path, os.O_WRONLY | os.O_APPEND)
            torn = info["torn_tail"]
            if (torn or info["unterminated"]) and not path.read_bytes().endswith(b"\n"):
                # End the torn line so the next event starts a line of its own; its bytes stay
                # (append-only) and the session_resumed event records the repair.
                jsonl.write_all(fd, b"\n")
                os.fsync(fd)
            return cls(path, fd, lock.path, events, torn, lock_timeout_s)

    def append(self, event_type: str, **fields) -> dict:
        """Appends one event and returns once it is on disk (written and fsync-ed).

        Args:
            event_type: the event's ``type``.
            **fields: its data (numpy arrays become lists).

        Returns:
            The event as written, with ``seq``, ``type``, ``time``, ``participant`` and ``study``.

        Raises:
            NotSavedError: the event could not be stored (a full disk, a quota, an I/O error):
                nothing of it is in the log, and the next ``append`` may succeed once there is room.
            LogError: the log is closed, or another session has continued this participant
                since (this session is stale and must stop).
        """
        if self._fd is None:
            raise LogError(f"the log of participant {self.participant!r} is closed")
        event = {"seq": len(self.events), "type": event_type, "time": utc_now(),
                 "participant": self.participant, "study": self.study}
        event.update(to_jsonable(fields))
        line = (json.dumps(event, separators=(",", ":"), allow_nan=False, ensure_ascii=True) + "\n").encode("ascii")
        with Lock(self._lock_path, f"participant {self.participant!r}", self.lock_timeout_s):
            if os.fstat(self._fd).st_size != self._size:
                raise ContinuedElsewhereError(f"participant {self.participant!r} was continued by another session "
                                              f"(a reloaded page or a second tab) since this one last wrote; this "
                                              f"one stops here, nothing was written")
            try:
                jsonl.write_all(self._fd, line)
                os.fsync(self._fd)
            except OSError as error:
                # Not acknowledged: the bytes that reached the file are taken back, so the log reads
                # as it did, and this session writes again once there is room. Where even that
                # fails, the log is closed: a resume ends the half line as after a kill.
                try:
                    jsonl.take_back(self._fd, self._size)
                except OSError:
                    self.close()
                raise NotSavedError(f"participant {self.participant!r}: this step could not be saved "
                                    f"({jsonl.why_not_saved(error)}); nothing of it was written, and "
                                    f"everything before it is saved", error.errno) from error
            self._size += len(line)
        self.events.append(event)
        return event

    def close(self) -> None:
        """Closes the file (idempotent); the session can be resumed later."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    @property
    def closed(self) -> bool:
        return self._fd is None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # at interpreter exit the os module may already be gone
            pass


class MemoryLog:
    """The same interface as ``ParticipantLog``, kept in memory: for unlogged lessons."""

    def __init__(self, participant: str = "lesson", study: str = "lesson"):
        self.participant, self.study = participant, study
        self.events: list[dict] = []
        self.repaired_torn_bytes = 0
        self.path = None
        self.closed = False

    def append(self, event_type: str, **fields) -> dict:
        event = {"seq": len(self.events), "type": event_type, "time": utc_now(),
                 "participant": self.participant, "study": self.study}
        event.update(to_jsonable(fields))
        self.events.append(event)
        return event

    def close(self) -> None:
        self.closed = True


# -- a folder that can take logs ---------------------------------------------------------------------

def check_folder_writable(folder) -> Path:
    """Refuses a log folder that cannot take a log, before any participant starts.

    Creates the folder if needed, then writes, fsyncs and removes a probe file, and checks the
    free space.

    Raises:
        LogFolderError: saying why (not a folder, permission denied, read-only, disk full).
    """
    folder = Path(folder).expanduser()
    if folder.exists() and not folder.is_dir():
        raise LogFolderError(f"log folder {folder}: expected a folder, found a file")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise LogFolderError(f"log folder {folder}: cannot be created ({error.strerror or error})") from None
    if not folder.is_dir():
        raise LogFolderError(f"log folder {folder}: expected a folder, found a file")
    probe = folder / f".write-test-{secrets.token_hex(4)}"
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        try:
            jsonl.write_all(fd, b"probe\n")
            os.fsync(fd)
        finally:
            os.close(fd)
        probe.unlink()
    except OSError as error:
        raise LogFolderError(f"log folder {folder}: not writable ({error.strerror or error}); choose another "
                             f"folder before the participant starts") from None
    free = shutil.disk_usage(folder).free
    if free < MIN_FREE_BYTES:
        raise LogFolderError(f"log folder {folder}: only {free // 1024} kB free, expected at least "
                             f"{MIN_FREE_BYTES // 1024 // 1024} MB")
    return folder




def storage_problem(folder) -> str | None:
    """Why ``folder`` could not take a participant's next step now (the disk is full, or nearly:
    less than ``MIN_FREE_BYTES`` free; not writable), or None. The experimenter's listing and
    ``python -m mt_widgets.study status`` show it: a page whose step could not be saved holds its
    participant until there is room (docs/guide/faults.md)."""
    try:
        check_folder_writable(folder)
    except LogFolderError as error:
        return str(error)
    return None
