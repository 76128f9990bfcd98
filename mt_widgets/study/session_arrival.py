"""Arriving at a session: which participant log a ``Session`` runs, started, resumed or refused.

The constructors of ``mt_widgets.study.session.Session`` (a mixin it inherits): ``start`` (a new
participant), ``resume`` (the first step their log does not record), ``arrive`` (the right
session of a protocol with ``[[sessions]]`` for someone who comes now: started, resumed, or
refused outside its window with ``WindowError``) and ``lesson`` (the engine unlogged, in
memory). Each writes the ``session_started`` / ``session_resumed`` event and enters the first
step; what happens at each step is the engine's (``mt_widgets.study.session``).
"""

from __future__ import annotations

import datetime as _dt
import platform

import numpy as np

import mt_widgets
from mt_widgets.core.validation import as_bool

from .log import LogError, MemoryLog, ParticipantLog, read_events
from .protocol import Protocol
from .schema import LOG_FORMAT
from .session_plan import as_utc
from .study_folder import StudyFolder


class WindowError(LogError):
    """A participant who came back outside their next session's window, where the protocol refuses.

    Attributes:
        check: the ``WindowCheck`` (status "early" or "late", opens_at, closes_at, delay_s).
        session: the id of the session refused.
        message: the words for the participant (the protocol's too_early_text / too_late_text).
    """

    def __init__(self, check, session: str):
        self.check, self.session, self.message = check, session, check.message
        super().__init__(check.message)


class SessionArrival:
    """How a ``Session`` is built (``start``, ``resume``, ``arrive``, ``lesson``); mixed into ``Session``."""

    @classmethod
    def start(cls, study: StudyFolder, participant_id: str, group: str | None = None,
              parameters: dict | None = None) -> SessionArrival:
        """Enrols a new participant (validating the ID, assigning the group) and starts their log
        of the protocol's first session.

        Args:
            study: the study folder.
            participant_id: a new pseudonymous ID.
            group: None for the protocol's block randomisation, or the experimenter's choice.
            parameters: identifying URL parameters to record with the enrolment (online).
        """
        if not isinstance(study, StudyFolder):
            raise ValueError(f"study: expected a StudyFolder, got {type(study).__name__}")
        enrolment = study.enrol(participant_id, group, parameters=parameters)
        log = ParticipantLog.create(study.log_path(participant_id), study.meta["study"])
        return cls._begin(study, log, enrolment)

    @classmethod
    def resume(cls, study: StudyFolder, participant_id: str, lock_timeout_s: float = 3.0,
               session: str | None = None) -> SessionArrival:
        """Continues an enrolled participant at the first step their log does not record.

        Args:
            study: the study folder.
            participant_id: an enrolled participant.
            lock_timeout_s: how long to wait for the participant's lock, which a writer holds
                only while it writes one event. An older session of the same participant (a
                reloaded page's kernel still alive) is taken over: its next write is refused.
            session: which protocol session (None: the latest one the participant started).
        """
        if not isinstance(study, StudyFolder):
            raise ValueError(f"study: expected a StudyFolder, got {type(study).__name__}")
        enrolment = study.enrolment(participant_id)
        cls._refuse_lost(study, participant_id)
        if session is None:
            started = [s.id for s in study.protocol.sessions if study.log_path(participant_id, s.id).exists()]
            session = started[-1] if started else study.protocol.sessions[0].id
        path = study.log_path(participant_id, session)
        try:
            log = ParticipantLog.open(path, lock_timeout_s=lock_timeout_s)
        except LogError:
            if path.exists() or session != study.protocol.sessions[0].id:
                raise
            # Enrolled, then stopped before the log was created: start the log now.
            log = ParticipantLog.create(path, study.meta["study"], lock_timeout_s=lock_timeout_s)
        log.study = study.meta["study"]
        if not log.events:
            return cls._begin(study, log, enrolment, session)
        first = log.events[0]
        if first.get("type") != "session_started" or first.get("protocol_hash") != study.protocol.hash:
            log.close()
            raise LogError(f"participant {participant_id!r}: the log was not started with this study's protocol "
                           f"({study.protocol.hash[:19]}...); it will not be continued")
        session_ = cls(study.protocol, log, first["group"], enrolment, study, session=session)
        session_.window = first.get("window")
        log.append("session_resumed", format=LOG_FORMAT, software_version=mt_widgets.__version__,
                   protocol_hash=study.protocol.hash,
                   at=session_._describe(session_._slot), repaired_torn_line=log.repaired_torn_bytes)
        session_._enter()
        return session_

    @staticmethod
    def _refuse_lost(study: StudyFolder, participant_id: str) -> None:
        left = study.outcomes().get(participant_id)
        if left is not None:
            what = {"withdrawn": "withdrew from the study", "declined": "declined consent",
                    "ineligible": "was screened out as ineligible", "dropped_out": "was marked as dropped out"}
            raise LogError(f"participant_id: {participant_id!r} {what[left['outcome']]} ({left['at']}); their "
                           f"session cannot be resumed. Enrol a new participant ID for a new person.")

    @classmethod
    def arrive(cls, study: StudyFolder, participant_id: str | None = None, *, reentry_code: str | None = None,
               now=None, group: str | None = None, parameters: dict | None = None,
               enrol_new: bool = True) -> SessionArrival:
        """The right session for a participant who arrives now: starts, resumes or refuses.

        - A new ID (when ``enrol_new``): enrolled (randomised unless ``group``) and started on
          the first session.
        - An enrolled participant (by ID, or by the re-entry code shown at the end of their
          previous session) whose current session is unfinished: resumed there.
        - One whose session is finished and whom another session follows: that session
          starts if ``now`` is inside its window; outside it, the protocol's rule: "refuse"
          raises ``WindowError`` with the words to show (nothing is written), "flag" starts it
          and the ``session_started`` event (and ``session.window``) says it is early or late.
        - One who completed the last session: that session, finished (its thank-you).

        The group is the enrolment's, in every session.

        Args:
            study: the study folder.
            participant_id: the participant's ID, or None when ``reentry_code`` is given.
            reentry_code: the code shown at the end of a previous session ("K7QM-3XRD").
            now: the arrival time, an aware datetime (None: the clock; tests pass their own).
            group: the experimenter's choice for a new participant (None: randomised).
            parameters: identifying URL parameters recorded with a new enrolment.
            enrol_new: False refuses an ID that is not enrolled (a follow-up-only page).

        Raises:
            WindowError: outside the window of a session whose protocol says "refuse".
            LogError: an unknown code, an unknown ID when ``enrol_new`` is False, or a participant
                who withdrew, declined or was screened out.
        """
        if not isinstance(study, StudyFolder):
            raise ValueError(f"study: expected a StudyFolder, got {type(study).__name__}")
        enrol_new = as_bool("enrol_new", enrol_new)
        now = as_utc(now)
        if (participant_id is None) == (reentry_code is None):
            raise ValueError("participant_id, reentry_code: expected exactly one of them")
        if reentry_code is not None:
            participant_id = study.participant_for_code(reentry_code)
        if participant_id not in study.participant_ids():
            if not enrol_new:
                raise LogError(f"participant_id: {participant_id!r} is not enrolled in this study")
            return cls.start(study, participant_id, group=group, parameters=parameters)
        cls._refuse_lost(study, participant_id)
        sessions = study.protocol.sessions
        for position, plan in enumerate(sessions):
            path = study.log_path(participant_id, plan.id)
            if not path.exists():
                if position == 0:
                    return cls.resume(study, participant_id, session=plan.id)
                break
            events, _ = read_events(path)
            finished = [e for e in events if e["type"] == "session_finished"]
            if not finished or position == len(sessions) - 1:
                return cls.resume(study, participant_id, session=plan.id)
            previous_end = finished[0]["time"]
        else:  # pragma: no cover - the loop returns at the last session
            raise AssertionError("unreachable")
        check = plan.window.check(_dt.datetime.fromisoformat(previous_end.replace("Z", "+00:00")), now)
        if check.action == "refuse":
            raise WindowError(check, plan.id)
        enrolment = study.enrolment(participant_id)
        log = ParticipantLog.create(path, study.meta["study"])
        return cls._begin(study, log, enrolment, plan.id, window=check.as_dict(), arrived_at=now)

    @classmethod
    def _begin(cls, study, log, enrolment, session: str | None = None, window: dict | None = None,
               arrived_at=None) -> SessionArrival:
        plan = study.protocol.session(session)
        extra = {}
        if log.repaired_torn_bytes:
            # A start killed inside its own first event: this start ends that torn line, and says so.
            extra["repaired_torn_line"] = log.repaired_torn_bytes
        if window is not None:
            extra.update(window=window, arrived_at=as_utc(arrived_at).isoformat(timespec="milliseconds")
                         .replace("+00:00", "Z"))
        log.append("session_started", format=LOG_FORMAT, session=plan.id, software_version=mt_widgets.__version__,
                   protocol_hash=study.protocol.hash, protocol_name=study.protocol.name, group=enrolment["group"],
                   enrolment=enrolment,
                   lam=study.protocol.lam, numpy_version=np.__version__, python_version=platform.python_version(),
                   **extra)
        session_ = cls(study.protocol, log, enrolment["group"], enrolment, study, session=plan.id)
        session_.window = window
        session_._enter()
        return session_

    @classmethod
    def lesson(cls, protocol: Protocol, group: str | None = None, participant: str = "lesson") -> SessionArrival:
        """The same engine, unlogged (events kept in memory), for a guided lesson: the task only,
        without the protocol's steps around it (video, information, forms, questionnaires).

        Args:
            protocol: what to run.
            group: which group's conditions to show (default: the first group, which sees
                guidance where the protocol gives any).
        """
        if not isinstance(protocol, Protocol):
            raise ValueError(f"protocol: expected a Protocol, got {type(protocol).__name__}")
        group = protocol.groups[0] if group is None else group
        if group not in protocol.groups:
            raise ValueError(f"group: expected one of {list(protocol.groups)}, got {group!r}")
        log = MemoryLog(participant, protocol.name)
        enrolment = {"participant": participant, "index": 0, "group": group, "method": "lesson"}
        log.append("session_started", format=LOG_FORMAT, session=protocol.sessions[0].id,
                   software_version=mt_widgets.__version__, protocol_hash=protocol.hash, protocol_name=protocol.name,
                   group=group, enrolment=enrolment, lam=protocol.lam,
                   numpy_version=np.__version__, python_version=platform.python_version())
        # A lesson is the task only: the study's video, forms and questionnaires are for participants.
        session = cls(protocol, log, group, enrolment, around_task=False)
        session._enter()
        return session
