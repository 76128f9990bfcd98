"""The crash-safe study log: one append-only JSON-lines file per participant, in a study folder.

A study folder holds:

- ``study.json``: the study's name, its protocol (plain data and source text), the protocol
  hash, the software version and the creation time. Written once (exclusive creation) and
  never changed: a folder runs exactly one protocol, so logs of different protocols never mix.
- ``_enrolment.jsonl``: one line per enrolled participant (ID, enrolment number, group, how the
  group was assigned, time), appended under a lock so two processes never draw the same
  enrolment number. A kill mid-write can leave a torn last record: that participant never
  started, and the next enrolment first ends the torn line and records the repair
  (``repaired_torn_line``, bytes), so it is never glued onto it; any other damage is reported,
  never skipped. Participant IDs cannot start with "_", so no log can be named like it.
- ``<participant>.jsonl``: the participant's events, one JSON object a line.
- ``.locks/``: lock files (``fcntl.flock``); a lock dies with its process, so a crash never
  leaves a folder locked.

Every event is written with one ``os.write`` on an ``O_APPEND`` descriptor and ``fsync``-ed
before ``append`` returns, so the interface moves on only once the event is on disk (as
PsychoPy's experiment handler saves each trial as it completes). A log file is created with
``O_EXCL`` (never overwritten) and each event is written under its participant's lock after
checking that nobody else wrote since, so two processes never interleave events in one log:
a newer session (a reloaded page) takes over, and the older one is refused. A crash can leave
at most the last line torn; loading drops it,
and reopening for writing first ends it with a newline so the next event starts on a line of
its own; the ``session_resumed`` event that follows records the repair, and only such
repaired lines are tolerated in the middle of a log.

Events are JSON objects with at least ``seq`` (0-based, consecutive), ``type``, ``time``
(ISO 8601 UTC), ``participant`` and ``study``; see ``mt_widgets.study.session`` for the types.
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

import mt_widgets
from mt_widgets.core.validation import as_bool

from . import jsonl
from .jsonl import Lock, LogError, append_line, encode, read_jsonl
from .participants import block_assignment, new_reentry_code, normalise_reentry_code, validate_participant_id
from .protocol import Protocol, protocol_from_data

STUDY_FILE = "study.json"
ENROLMENT_FILE = "_enrolment.jsonl"
#: Append-only records of how a participant's participation ended early: withdrawn, declined
#: consent, screened out as ineligible, or dropped out (marked by the experimenter).
OUTCOME_FILE = "_outcomes.jsonl"
#: Outcomes that take a participant out of the analysis and free their place in the
#: randomisation (see ``StudyFolder.enrol``).
LOST_OUTCOMES = ("withdrawn", "declined", "ineligible", "dropped_out")
LOCK_FOLDER = ".locks"
#: Refuse to start a participant with less free space than this in the log folder (bytes): a
#: participant's log is about 50 kB, so this leaves room for hundreds.
MIN_FREE_BYTES = 20 * 1024 * 1024


class LogFolderError(LogError):
    """A study folder that cannot be written: refused before any participant starts."""


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
            if event.get("type") == "session_resumed" and event.get("repaired_torn_line"):
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
        # A torn line already ended with a newline by a resume that crashed before logging.
        if len(pending_bad) > 1 or pending_bad[0] != len(complete):
            raise LogError(f"{path}, line {pending_bad[0]}: not a JSON event; the log is damaged")
        torn_tail += len(complete[-1].raw) + 1
    return events, {"torn_tail": torn_tail, "unterminated": False, "repaired_lines": repaired}


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
                raise LogError(f"participant {self.participant!r} was continued by another session (a reloaded "
                               f"page or a second tab) since this one last wrote; this one stops here, nothing "
                               f"was written")
            jsonl.write_all(self._fd, line)
            os.fsync(self._fd)
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


# -- the study folder -------------------------------------------------------------------------------

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


def _open_place(records: list[dict], outcomes: dict) -> dict | None:
    """The earliest randomised participant who left the study and whose place no replacement
    has taken yet (their enrolment record), or None.

    The rule (why: the study's comparisons are among completers): a randomised participant who
    withdraws, declines consent, is screened out or drops out frees their place, and the next
    randomised enrolment takes it, in the same group, before the block sequence goes on. So
    the participants still in the study are always the ones a block design without losses
    would hold, balanced within every block, whoever leaves. Places freed by experimenter-
    assigned participants are not refilled (they were never drawn from the sequence).
    """
    lost = [r for r in records if r["participant"] in outcomes and r["method"] in ("block", "replacement")]
    taken: dict[str, int] = {}
    for r in records:
        if r["method"] == "replacement":
            taken[r["group"]] = taken.get(r["group"], 0) + 1
    for r in lost:
        if taken.get(r["group"], 0) > 0:
            taken[r["group"]] -= 1
            continue
        return r
    return None


class StudyFolder:
    """A folder of participant logs for one study and one protocol.

    Use ``StudyFolder.create(folder, protocol)`` for a new study (or to reopen one with the same
    protocol), ``StudyFolder(folder)`` to open an existing one.
    """

    def __init__(self, folder):
        self.folder = Path(folder).expanduser()
        path = self.folder / STUDY_FILE
        if not path.is_file():
            raise LogError(f"folder: {self.folder} holds no {STUDY_FILE}; create the study with "
                           f"StudyFolder.create(folder, protocol)")
        self.meta = json.loads(path.read_text(encoding="utf-8"))
        self.protocol: Protocol = protocol_from_data(self.meta["protocol"], str(path))
        if self.protocol.hash != self.meta["protocol_hash"]:
            raise LogError(f"{path}: the stored protocol hash does not match the stored protocol; the file was edited")

    @classmethod
    def create(cls, folder, protocol: Protocol) -> StudyFolder:
        """Creates the study folder for ``protocol``, or reopens it if it runs the same protocol.

        Raises:
            LogFolderError: the folder is not writable.
            LogError: the folder already runs a different protocol.
        """
        if not isinstance(protocol, Protocol):
            raise ValueError(f"protocol: expected a Protocol (load_protocol(...)), got {type(protocol).__name__}")
        folder = check_folder_writable(folder)
        path = folder / STUDY_FILE
        meta = {"study": protocol.name, "title": protocol.title, "protocol_hash": protocol.hash,
                "protocol": protocol.data, "protocol_source": protocol.source_text,
                "protocol_file": Path(protocol.source).name, "created_at": utc_now(),
                "software_version": mt_widgets.__version__, "format": 1}
        text = json.dumps(meta, indent=1, sort_keys=True, allow_nan=False)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            study = cls(folder)
            if study.protocol.hash != protocol.hash:
                raise LogError(f"folder: {folder} already runs study {study.meta['study']!r} with protocol "
                               f"{study.protocol.hash[:19]}..., not {protocol.name!r} {protocol.hash[:19]}...; "
                               f"use a new folder for a different protocol") from None
            return study
        try:
            jsonl.write_all(fd, text.encode())
            os.fsync(fd)
        finally:
            os.close(fd)
        jsonl.fsync_folder(folder)
        return cls(folder)

    # -- participants ---------------------------------------------------------------------------
    def log_path(self, participant_id: str, session: str | None = None) -> Path:
        """The log of a participant's session: ``<ID>.jsonl`` for the first session, and
        ``<ID>.ses-<session>.jsonl`` for a later one (an ID holds no ".", so none collides)."""
        if session is None or session == self.protocol.sessions[0].id:
            return self.folder / f"{participant_id}.jsonl"
        self.protocol.session(session)  # refuses an unknown session
        return self.folder / f"{participant_id}.ses-{session}.jsonl"

    def participant_for_code(self, reentry_code: str) -> str:
        """The participant a re-entry code belongs to (``normalise_reentry_code`` reads what was typed).

        Raises:
            TypeError, ValueError: not a code of that form.
            LogError: no participant of this study has it.
        """
        code = normalise_reentry_code(reentry_code)
        for record in self.enrolments():
            if record.get("reentry_code") == code:
                return record["participant"]
        raise LogError("reentry_code: no participant of this study has this code; check it and type it again")

    def participants(self, blinded: bool = True) -> list[dict]:
        """Who is enrolled and how far they are, for a caller that must not see groups.

        Args:
            blinded: True (the default): rows hold participant, state and each session's state
                ("not started", "in progress", "completed") and nothing of the assignment (no
                group, method, block slot, enrolment number or re-entry code). False: the
                experimenter's rows of ``status`` with the sessions added.
        """
        blinded = as_bool("blinded", blinded)
        rows = []
        for row in self.status():
            sessions = {}
            for session in self.protocol.sessions:
                path = self.log_path(row["participant"], session.id)
                if not path.exists():
                    sessions[session.id] = "not started"
                    continue
                try:
                    events, _ = read_events(path)
                except LogError:
                    sessions[session.id] = "damaged"
                    continue
                done = any(e["type"] == "session_finished" for e in events)
                sessions[session.id] = "completed" if done else "in progress"
            if blinded:
                rows.append({"participant": row["participant"], "state": row["state"], "sessions": sessions})
            else:
                rows.append({**row, "sessions": sessions})
        return rows

    def enrolments(self) -> list[dict]:
        """Every enrolment record, in enrolment order.

        Raises:
            LogError: a line that does not parse and that no later record's repair covers
                (only an enrolment killed mid-write leaves one, and the next enrolment ends it
                and records the repair), naming the file and the line.
        """
        return self._read_enrolments()[0]

    def _read_enrolments(self) -> tuple[list[dict], int]:
        """(records, damaged_bytes): ``damaged_bytes`` > 0 when the file ends in damage (a torn
        record, or lines a crash left unrepaired) that the next record must say it repairs."""
        path = self.folder / ENROLMENT_FILE
        if not path.exists():
            return [], 0
        contents = read_jsonl(path)
        records: list[dict] = []
        pending: list[tuple[int, int]] = []  # (line number, bytes) of lines that do not parse
        # The tail (after the last newline) is a record killed mid-write, or complete but for its newline.
        for line in contents.lines + ([contents.tail] if contents.tail is not None else []):
            record = line.value
            if record is None or "participant" not in record:
                pending.append((line.number, len(line.raw) + (0 if line is contents.tail else 1)))
                continue
            if pending and not record.get("repaired_torn_line"):
                raise LogError(f"{path}, line {pending[0][0]}: not an enrolment record, and the next record does "
                               f"not record repairing it; the enrolment file is damaged (participants after it "
                               f"would be lost)")
            pending = []
            # A last record missing only its newline is complete: it was enrolled (the next
            # enrolment ends its line first).
            records.append(record)
        return records, sum(size for _, size in pending)

    def enrolment(self, participant_id: str) -> dict:
        for record in self.enrolments():
            if record["participant"] == participant_id:
                return record
        raise LogError(f"participant_id: {participant_id!r} is not enrolled in study {self.meta['study']!r}")

    def participant_ids(self) -> list[str]:
        return [record["participant"] for record in self.enrolments()]

    def enrol(self, participant_id: str, group: str | None = None, parameters: dict | None = None) -> dict:
        """Enrols a new participant and assigns their group, under the study lock.

        Args:
            participant_id: a new pseudonymous ID.
            group: None for the protocol's block randomisation, or a group chosen by the
                experimenter (recorded as such).
            parameters: identifying URL parameters to record (an online participant's
                STUDY_ID and SESSION_ID), or None.

        Returns:
            The enrolment record: participant, index, group, method, enrolled_at (and
            reentry_code for a protocol of several sessions, url_parameters when given).
        """
        check_folder_writable(self.folder)
        if group is not None and group not in self.protocol.groups:
            raise ValueError(f"group: expected None (randomised) or one of {list(self.protocol.groups)}, "
                             f"got {group!r}")
        with Lock(self.folder / LOCK_FOLDER / "_study.lock", f"study folder {self.folder}", timeout_s=10.0):
            records, damaged = self._read_enrolments()
            existing = [r["participant"] for r in records]
            existing += [p.stem for p in self.folder.glob("*.jsonl") if not p.name.startswith("_")]
            validate_participant_id(participant_id, existing)
            index = len(records)
            # Block randomisation counts only randomised enrolments, so an experimenter's
            # manual choice does not shift the sequence everyone else gets.
            slot = sum(1 for r in records if r["method"] == "block")
            replaces = None
            if group is None:
                replaces = _open_place(records, self.outcomes())
                if replaces is not None:
                    group, method = replaces["group"], "replacement"
                else:
                    group, method = block_assignment(slot, self.protocol.groups, self.protocol.block_size,
                                                     self.protocol.assignment_seed), "block"
            else:
                method = "experimenter"
            record = {"participant": participant_id, "index": index, "group": group, "method": method,
                      "block_slot": slot if method == "block" else None, "enrolled_at": utc_now(),
                      "protocol_hash": self.protocol.hash}
            if replaces is not None:
                record["replaces"] = replaces["participant"]
            if len(self.protocol.sessions) > 1:
                taken_codes = {r.get("reentry_code") for r in records}
                code = new_reentry_code()
                while code in taken_codes:
                    code = new_reentry_code()
                record["reentry_code"] = code
            if parameters:
                record["url_parameters"] = dict(parameters)
            if damaged:
                # The last enrolment was killed mid-write: its bytes stay (append-only), and this
                # record says it repairs them, so only such lines are tolerated mid-file.
                record["repaired_torn_line"] = damaged
            # append_line ends a torn (or newline-less) last line first, as ParticipantLog.open
            # does, so this record never gets glued onto it.
            append_line(self.folder / ENROLMENT_FILE, encode(record))
        return record

    def status(self) -> list[dict]:
        """For the experimenter: each participant with group, whether their (first session's) log
        is complete, and their outcome ("completed" once their last session is, "in progress",
        or one of ``LOST_OUTCOMES``). Holds the groups: ``participants()`` is the blinded list."""
        rows = []
        outcomes = self.outcomes()
        for record in self.enrolments():
            path = self.log_path(record["participant"])
            finished, n_events = False, 0
            if path.exists():
                try:
                    events, _ = read_events(path)
                    n_events = len(events)
                    finished = any(e["type"] == "session_finished" for e in events)
                except LogError:
                    n_events = -1
            last = self.log_path(record["participant"], self.protocol.sessions[-1].id)
            if last != path:  # several sessions: completed once the last one is
                try:
                    completed = last.exists() and any(e["type"] == "session_finished" for e in read_events(last)[0])
                except LogError:
                    completed = False
            else:
                completed = finished
            outcome = outcomes.get(record["participant"], {}).get("outcome")
            state = outcome or ("completed" if completed else "in progress")
            rows.append({**record, "events": n_events, "finished": finished, "state": state})
        return rows

    # -- how participation ended --------------------------------------------------------------------
    def outcomes(self) -> dict[str, dict]:
        """{participant: their outcome record} for those whose participation ended early."""
        path = self.folder / OUTCOME_FILE
        if not path.exists():
            return {}
        found = {}
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
            except ValueError:
                raise LogError(f"{path}, line {number}: not an outcome record; the file is damaged") from None
            found[record["participant"]] = record
        return found

    def record_outcome(self, participant_id: str, outcome: str, **fields) -> dict:
        """Records, under the study lock, that a participant withdrew, declined, was screened out
        or dropped out; the record is fsynced before this returns.

        Args:
            participant_id: an enrolled participant.
            outcome: one of ``LOST_OUTCOMES``.
            **fields: what else to keep (reason, the data policy, the step reached).
        """
        if outcome not in LOST_OUTCOMES:
            raise ValueError(f"outcome: expected one of {list(LOST_OUTCOMES)}, got {outcome!r}")
        enrolment = self.enrolment(participant_id)
        record = {"participant": participant_id, "group": enrolment["group"], "method": enrolment["method"],
                  "outcome": outcome, "at": utc_now(), **to_jsonable(fields)}
        with Lock(self.folder / LOCK_FOLDER / "_study.lock", f"study folder {self.folder}", timeout_s=10.0):
            if participant_id in self.outcomes():
                raise LogError(f"participant_id: {participant_id!r} already left the study "
                               f"({self.outcomes()[participant_id]['outcome']})")
            append_line(self.folder / OUTCOME_FILE, encode(record))
        return record

    def mark_dropped_out(self, participant_id: str, reason: str = "") -> dict:
        """The experimenter's record that an in-progress participant will not come back."""
        for row in self.status():
            if row["participant"] == participant_id and row["state"] != "in progress":
                raise LogError(f"participant_id: {participant_id!r} is {row['state']}, not in progress")
        return self.record_outcome(participant_id, "dropped_out", reason=reason)

    def group_status(self) -> dict[str, dict[str, int]]:
        """Per group: enrolled, completed, in progress, and each way of leaving (withdrawn, ...)."""
        counts = {group: {"enrolled": 0, "completed": 0, "in progress": 0, **{o: 0 for o in LOST_OUTCOMES}}
                  for group in self.protocol.groups}
        for row in self.status():
            counts[row["group"]]["enrolled"] += 1
            counts[row["group"]][row["state"]] += 1
        return counts

    def status_report(self) -> str:
        """The per-group status as a small text table (for the experimenter and the notes)."""
        counts = self.group_status()
        columns = ["enrolled", "completed", "in progress", *LOST_OUTCOMES]
        lines = ["group    " + "  ".join(f"{c:>11}" for c in columns)]
        for group, row in counts.items():
            lines.append(f"{group:<9}" + "  ".join(f"{row[c]:>11}" for c in columns))
        return "\n".join(lines)
