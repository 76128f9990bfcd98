"""A participant's erasure request: their data removed from the study folder, and what is kept said.

A participant (online: by their Prolific ID, the ID the study knows them by) may ask for their
data to be erased. ``erase_participant(study_folder, participant_id)`` then, under the study's lock:

- deletes their participant logs (every session's) and their lock files;
- rewrites their enrolment record (``_enrolment.jsonl``) without them: the record of enrolment
  number k keeps only what the randomisation needs (its group, method and block slot, under the
  tombstone ``_erased-<k>``, which no URL or experimenter can give), and loses the ID, the URL
  parameters (STUDY_ID, SESSION_ID), the re-entry code and the enrolment time;
- rewrites their outcome record the same way, or records that they withdrew (reason "erasure
  request") when they had none: their place is refilled by the next randomised arrival, so the
  groups stay balanced among the participants kept (``StudyFolder.enrol``);
- removes their entry from the pseudonym key (``mt_widgets.study.pseudonyms``): datasets exported
  before no longer link to them (the report names the code they had there, to withdraw those
  copies too);
- replaces the ID where another participant's log names it (a replacement's ``replaces``), in
  place and at the same length, so that participant's running session goes on;
- rewrites the study folder's tidy CSVs (``episodes.csv``, ``demonstrations.csv``) if present.

It keeps one line in ``_erasures.jsonl``: when, a keyed hash of the ID (HMAC with the study's
secret salt: the ID is not stored, but the same ID is recognised again, so a link reopened after
the erasure records nothing, ``StudyFolder.enrol``), how their participation had ended and, for
an online study, the completion code it ended with. That is what the pool's payment needs
(Prolific pays a submission by its completion code; the experimenter checks a submission with
``erased_record``), and the proof the request was answered.

Any other file of the folder that still holds the ID (one this package did not write) is named in
the report: remove it by hand.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from . import jsonl, pseudonyms
from .jsonl import Lock, LogError, append_line, encode, read_jsonl
from .log import LOCK_FOLDER, utc_now
from .schema import LOG_FORMAT
from .study_folder import ENROLMENT_FILE, ERASURE_FILE, LOST_OUTCOMES, OUTCOME_FILE, STUDY_FILE, StudyFolder
from .tidy import export_study

#: The tidy CSVs ``export_study`` writes into the study folder by default.
TIDY_FILES = ("episodes.csv", "demonstrations.csv")
#: Enrolment fields kept for an erased participant: what the block randomisation reads.
KEPT_ENROLMENT = ("format", "index", "group", "method", "block_slot", "protocol_hash")
#: Outcome fields kept for an erased participant.
KEPT_OUTCOME = ("format", "group", "method", "outcome")


class UnknownParticipantError(LogError):
    """An erasure request for an ID the study folder does not hold."""


@dataclass
class ErasureReport:
    """What an erasure did.

    Attributes:
        participant_id: the ID erased (as asked; it is not stored anywhere).
        removed: what was removed, in words (file names and records).
        kept: (what, why) pairs: what the study folder still holds about the participant.
        exported_code: the ``sub-`` code the participant had in datasets exported before (None
            if never exported): copies of those datasets still hold their data under it.
        left_over: files this package did not write that still name the participant.
    """

    participant_id: str
    removed: list[str] = field(default_factory=list)
    kept: list[tuple[str, str]] = field(default_factory=list)
    exported_code: str | None = None
    left_over: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        lines = [f"Erased participant {self.participant_id!r}.", "Removed:"]
        lines += [f"  - {item}" for item in self.removed]
        lines.append("Kept:" if self.kept else "Kept: nothing.")
        lines += [f"  - {what} (why: {why})" for what, why in self.kept]
        if self.exported_code:
            lines.append(f"Datasets exported before today hold this participant as sub-{self.exported_code}: "
                         f"export again and replace or withdraw the copies you shared.")
        if self.left_over:
            lines.append("Still naming the participant (files mt-widgets did not write; edit or remove them by hand):")
            lines += [f"  - {path}" for path in self.left_over]
        return "\n".join(lines)


def _rewrite(path: Path, transform) -> None:
    """Rewrites a JSON-lines file line by line (``transform(JsonLine) -> bytes``), atomically:
    a new file with the old one's mode, fsynced, renamed over it. Only for files opened afresh
    for every append (enrolments, outcomes), under the study lock."""
    contents = read_jsonl(path)
    pieces = [transform(line) + b"\n" for line in contents.lines]
    if contents.tail is not None:
        pieces.append(transform(contents.tail))
    temporary = path.with_name(path.name + ".tmp")
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, path.stat().st_mode & 0o777)
    try:
        jsonl.write_all(fd, b"".join(pieces))
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(temporary, path)
    jsonl.fsync_folder(path.parent)


def _same_length_mask(participant_id: str, tombstone: str) -> str:
    """The tombstone cut or padded to the ID's length (for in-place edits of another's log)."""
    text = tombstone if len(tombstone) <= len(participant_id) else "_" * len(participant_id)
    return text.ljust(len(participant_id), "-")


def _scrub_other_log(path: Path, participant_id: str, mask: str) -> bool:
    """Replaces the ID (as a JSON string) in another participant's log in place, at the same
    length, under that participant's lock: their open session keeps writing to the same file."""
    needle = json.dumps(participant_id).encode()
    data = path.read_bytes()
    if needle not in data:
        return False
    with Lock(path.parent / LOCK_FOLDER / (path.stem + ".lock"), f"participant {path.stem!r}", timeout_s=10.0):
        fd = os.open(path, os.O_RDWR)
        try:
            data = os.pread(fd, os.fstat(fd).st_size, 0)
            replacement = json.dumps(mask).encode()
            start = data.find(needle)
            while start >= 0:
                os.pwrite(fd, replacement, start)
                start = data.find(needle, start + len(needle))
            os.fsync(fd)
        finally:
            os.close(fd)
    return True


def erased_record(study_folder, participant_id: str) -> dict | None:
    """The erasure record of ``participant_id`` (when erased, how their participation ended, the
    completion code), or None if they were never erased: the experimenter's check before paying."""
    return pseudonyms.erased_record(study_folder, participant_id)


def erase_participant(study_folder, participant_id: str) -> ErasureReport:
    """Erases a participant from a study folder (see the module docstring for what and why).

    Args:
        study_folder: the study folder.
        participant_id: the ID the study knows them by (online: their Prolific ID).

    Returns:
        An ``ErasureReport``; ``str(report)`` is the answer to give, in words.

    Raises:
        TypeError: ``participant_id`` is not text.
        UnknownParticipantError: no participant of the study has this ID (nothing was changed),
            or they were erased already.
        LogError: their session is writing right now (try again once their page is closed).
    """
    if not isinstance(participant_id, str):
        raise TypeError(f"participant_id: expected the participant's ID as text, got {type(participant_id).__name__}")
    study = StudyFolder(study_folder)
    folder = study.folder
    report = ErasureReport(participant_id)
    with Lock(folder / LOCK_FOLDER / "_study.lock", f"study folder {folder}", timeout_s=10.0):
        if erased_record(folder, participant_id) is not None:
            raise UnknownParticipantError(f"participant_id: {participant_id!r} was erased from study "
                                          f"{study.meta['study']!r} already; nothing more holds it")
        rows = {row["participant"]: row for row in study.status()}
        if participant_id not in rows:
            close = [p for p in rows if p.lower() == participant_id.strip().lower()]
            hint = f" (did you mean {close[0]!r}? IDs are matched exactly)" if close else ""
            raise UnknownParticipantError(f"participant_id: {participant_id!r} is not enrolled in study "
                                          f"{study.meta['study']!r} at {folder}{hint}; nothing was erased")
        row = rows[participant_id]
        tombstone = f"_erased-{row['index']}"
        outcome = row["state"]
        completion = None
        if study.protocol.online is not None and outcome != "in progress":
            ended = {"ineligible": "screened_out", "dropped_out": None}.get(outcome, outcome)
            if ended is not None:
                completion = study.protocol.online.completion(ended).code

        # 1. Their logs (every session's) and lock files. Taking each log's lock first means no
        # session of theirs is writing at this moment.
        logs = [study.log_path(participant_id, s.id) for s in study.protocol.sessions]
        for path in logs:
            if path.exists():
                with Lock(folder / LOCK_FOLDER / (path.stem + ".lock"), f"participant {path.stem!r}", timeout_s=10.0):
                    path.unlink()
                report.removed.append(f"log {path.name}")
        for lock in (folder / LOCK_FOLDER).glob("*.lock"):
            if lock.name.split(".")[0] == participant_id:
                lock.unlink()

        # 2. The enrolment record: only what the randomisation needs stays, under the tombstone.
        def enrolment_line(line):
            record = line.value
            if record is None:  # a torn line: mask the ID if it holds it, keep its length
                return line.raw.replace(participant_id.encode(), b"#" * len(participant_id.encode()))
            if record.get("participant") == participant_id:
                kept = {k: record[k] for k in KEPT_ENROLMENT if k in record}
                return encode({**kept, "participant": tombstone, "erased": True})[:-1]
            if record.get("replaces") == participant_id:
                return encode({**record, "replaces": tombstone})[:-1]
            return line.raw
        _rewrite(folder / ENROLMENT_FILE, enrolment_line)
        report.removed.append(f"the enrolment record (ID, identifying URL parameters, re-entry code, time) in "
                              f"{ENROLMENT_FILE}")

        # 3. The outcome record, or a withdrawal so the place is refilled.
        outcomes_path = folder / OUTCOME_FILE
        if participant_id in study.outcomes():
            def outcome_line(line):
                record = line.value
                if record is not None and record.get("participant") == participant_id:
                    kept = {k: record[k] for k in KEPT_OUTCOME if k in record}
                    return encode({**kept, "participant": tombstone, "erased": True})[:-1]
                return line.raw
            _rewrite(outcomes_path, outcome_line)
            report.removed.append(f"the outcome record (time, reason, answers kept with it) in {OUTCOME_FILE}")
        else:
            append_line(outcomes_path, encode({"format": LOG_FORMAT, "participant": tombstone, "group": row["group"],
                                               "method": row["method"], "outcome": "withdrawn",
                                               "reason": "erasure request", "erased": True}))

        # 4. Other participants' logs that name them (a replacement's enrolment says whom it replaces).
        mask = _same_length_mask(participant_id, tombstone)
        for path in sorted(folder.glob("*.jsonl")):
            if not path.name.startswith("_") and _scrub_other_log(path, participant_id, mask):
                report.removed.append(f"their ID where {path.name} names them (as whom it replaced)")

        # 5. The pseudonym key, then the erasure record.
        report.exported_code = pseudonyms.forget(folder, participant_id)
        if report.exported_code:
            report.removed.append(f"their entry in the pseudonym key {pseudonyms.KEY_FILE} (code "
                                  f"{report.exported_code})")
        record = {"format": LOG_FORMAT, "erased_at": utc_now(),
                  "id_digest": pseudonyms.id_digest(folder, participant_id), "enrolment": tombstone,
                  "outcome": outcome, "completion_code": completion}
        append_line(folder / ERASURE_FILE, encode(record))
        report.kept.append((f"{ENROLMENT_FILE}: enrolment {row['index']} as {tombstone}, group and block slot, "
                            f"no ID, time or URL parameter",
                            "the block randomisation counts every enrolment; without it the next arrivals would get "
                            "other groups than the sequence promises"))
        left = (f"how {tombstone} left ({outcome})" if outcome in LOST_OUTCOMES
                else f"{tombstone} withdrew (reason: erasure request)")
        report.kept.append((f"{OUTCOME_FILE}: {left}, no ID, time or free text",
                            "their place is refilled by the next randomised arrival, so the groups stay balanced"))
        report.kept.append((f"{ERASURE_FILE}: the time of erasure, a keyed hash of the ID (not the ID), their outcome "
                            f"({outcome})" + (f" and completion code {completion}" if completion else ""),
                            "the pool pays by completion code and the experimenter must be able to check a submission "
                            "(erased_record); the same link reopened records nothing more; proof the request was "
                            "answered"))

        # 6. Tidy CSVs in the folder are derived from the logs: write them again without the participant.
        tidy = [folder / name for name in TIDY_FILES if (folder / name).exists()]
        if tidy:
            export_study(folder)
            report.removed.append("their rows in " + ", ".join(p.name for p in tidy) + " (written again)")

    # 7. Anything else in the folder that still names them.
    known = {STUDY_FILE}
    needle = participant_id.encode()
    for path in sorted(folder.rglob("*")):
        if path.is_file() and path.name not in known and (needle in path.read_bytes() or participant_id in path.name):
            report.left_over.append(str(path.relative_to(folder)))
    return report


def is_erased(study_folder, participant_id: str) -> bool:
    """Whether ``participant_id`` asked to be erased from the study (then nothing is recorded for them)."""
    return erased_record(study_folder, participant_id) is not None


__all__ = ["ERASURE_FILE", "ErasureReport", "UnknownParticipantError", "erase_participant", "erased_record",
           "is_erased"]
