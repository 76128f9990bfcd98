"""A study folder: one study, one protocol, its participants' enrolments, outcomes and logs.

A study folder holds:

- ``study.json``: the study's name, its protocol (plain data and source text), the protocol
  hash, the software version, the creation time and the schema format
  (``mt_widgets.study.schema``). Written once (exclusive creation) and never changed: a folder
  runs exactly one protocol, so logs of different protocols never mix.
- ``_enrolment.jsonl``: one line per enrolled participant (ID, enrolment number, group, how the
  group was assigned, time, format; a re-entry code when the protocol has several sessions;
  the identifying URL parameters of an online participant), appended under a lock so two
  processes never draw the same enrolment number. A kill mid-write can leave a torn last
  record: that participant never started, and the next enrolment first ends the torn line and
  records the repair (``repaired_torn_line``, bytes), so it is never glued onto it; any other
  damage is reported, never skipped. Participant IDs cannot start with "_", so no log can be
  named like it.
- ``_outcomes.jsonl``: how a participation ended early (withdrawn, declined, ineligible,
  dropped out), one record a line.
- ``_pseudonyms.json`` (mode 0600): the key from participant ID to the random code exports
  use (``mt_widgets.study.pseudonyms``); ``_erasures.jsonl``: one line per participant erased
  on request (``mt_widgets.study.erasure``), with a keyed hash of the ID, never the ID.
- the participant logs (``mt_widgets.study.log``): ``<participant>.jsonl`` and, for later
  sessions, ``<participant>.ses-<session>.jsonl``.

``status()`` is the experimenter's view (with groups); ``participants()`` the blinded one.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import mt_widgets
from mt_widgets.core.validation import as_bool

from . import jsonl
from .jsonl import Lock, LogError, append_line, encode, read_jsonl
from .log import LOCK_FOLDER, check_folder_writable, read_events, storage_problem, to_jsonable, utc_now
from .participants import block_assignment, new_reentry_code, normalise_reentry_code, validate_participant_id
from .protocol import Protocol, protocol_from_data
from .pseudonyms import ERASURE_FILE, erased_record
from .schema import LOG_FORMAT, migrate_record, migrate_study_meta

STUDY_FILE = "study.json"
ENROLMENT_FILE = "_enrolment.jsonl"
#: Append-only records of how a participant's participation ended early: withdrawn, declined
#: consent, screened out as ineligible, or dropped out (marked by the experimenter).
OUTCOME_FILE = "_outcomes.jsonl"
#: Outcomes that take a participant out of the analysis and free their place in the
#: randomisation (see ``StudyFolder.enrol``).
LOST_OUTCOMES = ("withdrawn", "declined", "ineligible", "dropped_out")


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
        self.meta = migrate_study_meta(json.loads(path.read_text(encoding="utf-8")), str(path))
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
                "software_version": mt_widgets.__version__, "format": LOG_FORMAT}
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
            records.append(migrate_record(record, f"{path}, line {line.number}"))
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
            if erased_record(self.folder, participant_id) is not None:
                # Their erasure was a request to record nothing more about them: a link opened again
                # (or an ID typed again) must not enrol them afresh.
                raise LogError(f"participant_id: the data of this ID were erased from this study at its owner's "
                               f"request, so the study records nothing more for it (see {ERASURE_FILE})")
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
            record = {"format": LOG_FORMAT, "participant": participant_id, "index": index, "group": group,
                      "method": method,
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
            found[record["participant"]] = migrate_record(record, f"{path}, line {number}")
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
        record = {"format": LOG_FORMAT, "participant": participant_id, "group": enrolment["group"],
                  "method": enrolment["method"],
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

    def storage_problem(self) -> str | None:
        """Why this folder could not take a participant's next step now (a full disk), or None."""
        return storage_problem(self.folder)

    def status_report(self) -> str:
        """The per-group status as a small text table (for the experimenter and the notes), after a
        line on the folder's storage when it could not take a participant's next step."""
        counts = self.group_status()
        columns = ["enrolled", "completed", "in progress", *LOST_OUTCOMES]
        problem = self.storage_problem()
        lines = [f"STORAGE FAULT: {problem}"] if problem else []
        lines.append("group    " + "  ".join(f"{c:>11}" for c in columns))
        for group, row in counts.items():
            lines.append(f"{group:<9}" + "  ".join(f"{row[c]:>11}" for c in columns))
        return "\n".join(lines)
