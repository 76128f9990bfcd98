"""The session engine: a headless state machine that runs one participant through a protocol.

The engine knows nothing of the paper beyond the protocol file. A protocol session unrolls
into a fixed timeline of steps (``mt_widgets.study.timeline``, which also draws each episode's
query states); the log is replayed against it (``mt_widgets.study.replay``).

A session can also end early: consent declined, screened out by an eligibility step, or
withdrawn (``withdraw``, at any step). Then ``finished`` is True, ``ended`` names why, the
study folder records the outcome (``StudyFolder.record_outcome``), the participant's data are
left out of the analysis and the export, and ``resume`` refuses the participant.

Each step is completed by exactly one logged event, and the position in the timeline is a
pure function of the log (the events are replayed on resume and checked against the
timeline, so a duplicated or missing event is detected, never silently accepted). A step's
event is written and fsync-ed before the call that completes it returns, so whatever the
participant saw last is on disk; after a crash the session continues at the first step
without its event: the first missing demonstration, with the same query states (read back
from the log, never redrawn).

Driver API (the widget app, scripts and synthetic teachers all use this)::

    study = StudyFolder.create("logs/pilot", load_protocol("paper-sim"))
    session = Session.start(study, "P07")          # or Session.resume(study, "P07")
    while not session.finished:
        step = session.current_step()
        if step.kind == "practice":
            session.finish_practice(duration_s=120.0)
        elif step.kind == "demonstration":         # step.state, step.query_states, step.guidance
            feedback = session.submit_demonstration(action, {"time_to_first_input_s": 1.2,
                                                             "drawing_duration_s": 0.8})
            # feedback.optimal is the optimal action when step.guidance, else None
        elif step.kind == "episode_end":
            result = session.finish_episode()      # theta_hat, teaching_error, trajectory
        else:                                      # welcome, consent, instructions,
            session.advance()                      # phase_intro, reproduction
    session.close()

``Session.lesson(protocol, group=...)`` runs the same engine unlogged, in memory, for lessons.

Sessions and returning participants (a protocol with ``[[sessions]]``,
``mt_widgets.study.session_plan``)::

    session = Session.arrive(study, "P07", now=now)          # or reentry_code="K7QM-3XRD"
    # a new ID: enrolled and started on the first session; an unfinished session: resumed;
    # a finished one followed by another: the next one if ``now`` is in its window, else the
    # protocol's rule: WindowError (.message, .check.opens_at) or started and flagged
    # (session.window["status"] == "late"). session.plan is the ProtocolSession shown.
    step = session.current_step()                             # at the end: step.kind == "thank_you",
    step.reentry_code, step.next_session                      # the code to come back with

    study.participants()                                      # blinded rows: no group, no code

Online participants (``[online]``, ``mt_widgets.study.online``)::

    arrival = protocol.online.participant_from_url(query)     # ParticipantIdError: nothing written
    session = Session.arrive(study, arrival.participant_id, parameters=arrival.parameters)
    ...
    protocol.online.completion_url(outcome_of(session))       # completed / screened_out / ...

A later session's log is ``<ID>.ses-<session>.jsonl`` beside ``<ID>.jsonl`` (the first), with
the same event types; its ``session_started`` adds ``session``, and when the arrival was
checked against a window, ``window`` (``WindowCheck.as_dict()``) and ``arrived_at``.

The events it writes, the schema version they carry and the migration of older logs:
``mt_widgets.study.schema``.
"""

from __future__ import annotations

import datetime as _dt
import platform
import time
from collections.abc import Mapping

import numpy as np

import mt_widgets
from mt_widgets.core import Demonstration, TeachingEpisode
from mt_widgets.core.validation import as_bool, as_count, as_positive

from .log import LogError, MemoryLog, ParticipantLog, read_events, to_jsonable
from .protocol import Phase, Protocol
from .replay import describe, replay
from .schema import LOG_FORMAT, migrate_events
from .session_plan import as_utc
from .session_types import EpisodeResult, Feedback, Step
from .study_folder import StudyFolder
from .timeline import ENDING_EVENTS, Slot, StepKind, episode_query_states, timeline  # noqa: F401 (ENDING_EVENTS: public here since format 1)

#: Timing keys ``submit_demonstration`` reads (seconds, None when unknown).
TIMING_KEYS = ("time_to_first_input_s", "drawing_duration_s")


class SessionStateError(RuntimeError):
    """A driver call that does not fit the current step (e.g. a second submission)."""


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


def _parse_time(stamp: str) -> float:
    return _dt.datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()


def _check_seconds(name: str, value):
    """A duration in seconds (>= 0), or None for "not measured"."""
    return None if value is None else as_positive(name, value, allow_zero=True)


class Session:
    """One participant's run through a protocol. Build with ``start``, ``resume`` or ``lesson``."""

    def __init__(self, protocol: Protocol, log, group: str, enrolment: dict, folder: StudyFolder | None = None,
                 around_task: bool = True, session: str | None = None):
        self.protocol, self.log, self.group, self.enrolment, self.folder = protocol, log, group, enrolment, folder
        #: The ``ProtocolSession`` this engine runs (the participant sees this session only).
        self.plan = protocol.session(session)
        #: Where the arrival fell in the session's window (``WindowCheck.as_dict()``), or None.
        self.window: dict | None = None
        self._slots = timeline(protocol, around_task, self.plan.id)
        replayed = replay(migrate_events(log.events, protocol.sessions[0].id, str(log.path or "<memory>")),
                          self._slots, self.plan)
        self._position = replayed.position
        #: {(phase_index, episode): its episode_started event} (states, guidance, seed, when).
        self._episodes: dict[tuple[int, int], dict] = replayed.episodes
        self._finished: set[tuple[int, int]] = set(replayed.finished)
        #: {(phase_index, episode): its TeachingEpisode}: the one place an episode's demonstrations
        #: live (rebuilt from the log on resume); the step's view demonstrates into it, the log
        #: records it, ``Step.actions`` and the result read it.
        self._teaching_episodes: dict[tuple[int, int], TeachingEpisode] = {
            key: self._episode_from_log(key, replayed.demonstrations.get(key, ())) for key in self._episodes}
        self._ended: str | None = replayed.ended
        self._entered_at = time.monotonic()

    # -- construction -----------------------------------------------------------------------------
    @classmethod
    def start(cls, study: StudyFolder, participant_id: str, group: str | None = None,
              parameters: dict | None = None) -> Session:
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
               session: str | None = None) -> Session:
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
               enrol_new: bool = True) -> Session:
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
               arrived_at=None) -> Session:
        plan = study.protocol.session(session)
        extra = {}
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
    def lesson(cls, protocol: Protocol, group: str | None = None, participant: str = "lesson") -> Session:
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

    def _describe(self, slot: Slot | None) -> str:
        return describe(slot, self.plan)

    # -- entering a step ----------------------------------------------------------------------------
    @property
    def _slot(self) -> Slot:
        return self._slots[self._position]

    def _phase(self, slot: Slot) -> Phase:
        return self.plan.phases[slot.phase_index]

    def _enter(self) -> None:
        """Logs what a step needs before it is shown (query states, practice start, the end)."""
        slot = self._slot
        self._entered_at = time.monotonic()
        if slot.kind == StepKind.DEMONSTRATION and (slot.phase_index, slot.episode) not in self._episodes:
            self._start_episode(slot)
        elif slot.kind == StepKind.PRACTICE:
            self.log.append("practice_started", skill=self.protocol.practice.skill,
                            duration_s=self.protocol.practice.duration_s)
        elif slot.kind == StepKind.THANK_YOU and not any(e["type"] == "session_finished" for e in self.log.events):
            self.log.append("session_finished")

    def _start_episode(self, slot: Slot) -> None:
        phase = self._phase(slot)
        skill = self.protocol.skills[phase.skill]
        states, seed = episode_query_states(self.protocol, phase.states_index, slot.episode, phase.demonstrations,
                                            phase.skill, participant=self.enrolment["index"])
        teaching = self._new_teaching_episode(skill, states)
        event = self.log.append(
            "episode_started", phase=phase.id, phase_index=phase.index, episode=slot.episode, skill=phase.skill,
            guidance=phase.guidance_for(self.group), guidance_modality=self.protocol.guidance_modality,
            n_demonstrations=phase.demonstrations, query_states=states,
            features=teaching.features, theta=skill.theta, lam=self.protocol.lam, optimal=teaching.optimal_actions,
            exact=teaching.exact,
            seed={"study_seed": self.protocol.seed, "spawn_key": list(seed.spawn_key)})
        self._episodes[(phase.index, slot.episode)] = event
        # Kept: the step's view shows this episode and the log records it (one per episode).
        self._teaching_episodes[(phase.index, slot.episode)] = teaching

    # -- reading the state ----------------------------------------------------------------------------
    @property
    def participant(self) -> str:
        return self.enrolment["participant"]

    @property
    def finished(self) -> bool:
        """True when nothing is left to do: at the thank-you step (every step of the protocol is
        logged), or once the session ended early (``ended``)."""
        return self._ended is not None or self._slot.kind == StepKind.THANK_YOU

    @property
    def completed(self) -> bool:
        """True at the thank-you step of a session that did not end early."""
        return self._ended is None and self._slot.kind == StepKind.THANK_YOU

    @property
    def ended(self) -> str | None:
        """Why the session ended early: "declined", "ineligible" or "withdrawn"; None otherwise."""
        return self._ended

    @property
    def events(self) -> list[dict]:
        return list(self.log.events)

    def progress(self) -> dict:
        """Episodes done and in all, and demonstrations done in the current episode."""
        done = len(self._finished)
        slot = self._slot
        teaching = self._teaching_episodes.get((slot.phase_index, slot.episode)) if slot.episode else None
        in_episode = 0 if teaching is None else len(teaching.demonstrations)
        return {"episodes_done": done, "episodes_total": self.plan.n_episodes,
                "demonstrations_done": in_episode}

    def current_step(self) -> Step:
        """The step to show now (see ``Step``)."""
        slot = self._slot
        texts = self.plan.texts
        if self._ended is not None:
            return Step("ended", texts[self._ended], ended=self._ended)
        if slot.kind == StepKind.THANK_YOU and self.plan.index + 1 < len(self.protocol.sessions):
            upcoming = self.protocol.sessions[self.plan.index + 1]
            return Step("thank_you", texts["thank_you"], reentry_code=self.enrolment.get("reentry_code"),
                        next_session={"id": upcoming.id, "window": upcoming.window.describe()})
        if slot.kind in ("welcome", "consent", "instructions", "thank_you"):
            return Step(slot.kind, texts[slot.kind])
        if slot.kind == StepKind.STEP:
            step = self.plan.steps[slot.index]
            return Step(step.kind, step.text, study_step=step)
        if slot.kind == StepKind.PRACTICE:
            practice = self.protocol.practice
            return Step("practice", practice.text, skill=practice.skill, duration_s=practice.duration_s,
                        practice_reproduction=practice.reproduction)
        phase = self._phase(slot)
        common = dict(phase=phase.id, phase_index=phase.index, n_episodes=phase.episodes,
                      n_demonstrations=phase.demonstrations, skill=phase.skill)
        if slot.kind == StepKind.PHASE_INTRO:
            return Step("phase_intro", phase.instructions, **common)
        key = (slot.phase_index, slot.episode)
        started = self._episodes[key]
        states = np.asarray(started["query_states"], dtype=float)
        common.update(episode=slot.episode, query_states=states, guidance=started["guidance"],
                      guidance_modality=started["guidance_modality"],
                      teaching_episode=self._teaching_episodes[key])
        if slot.kind == StepKind.DEMONSTRATION:
            return Step("demonstration", **common, index=slot.index, state=states[slot.index])
        if slot.kind == StepKind.EPISODE_END:
            return Step("episode_end", **common)
        return Step("reproduction", texts["reproduction"], **common, result=self._result(key))

    def _new_teaching_episode(self, skill, states) -> TeachingEpisode:
        """The episode of ``skill`` on ``states`` with this protocol's lambda and reproduction length."""
        return TeachingEpisode(skill, states, lam=self.protocol.lam, duration=self.protocol.reproduction_duration_s)

    def _teaching_episode(self, key) -> TeachingEpisode:
        """The episode's one ``TeachingEpisode``."""
        return self._teaching_episodes[key]

    def _episode_from_log(self, key, events) -> TeachingEpisode:
        """The episode a log describes: on its logged states, each logged demonstration recorded
        as it was given (action, method, timings), so a resumed view shows what the log holds."""
        started = self._episodes[key]
        episode = self._new_teaching_episode(self.protocol.skills[started["skill"]],
                                             np.asarray(started["query_states"], dtype=float))
        for event in events:
            given = event.get("input") or {}
            redraws = given.get("redraws", 0)
            episode.demonstrate(event["action"], method=str(given.get("method", "code")),
                                time_to_first_input_s=event.get("time_to_first_input_s"),
                                drawing_duration_s=event.get("drawing_duration_s"),
                                redraws=redraws if isinstance(redraws, int) and not isinstance(redraws, bool) else 0,
                                confirmed_at=_parse_time(event["time"]), guidance_shown=bool(event["guidance_shown"]),
                                episode_index=key[1] - 1)
        return episode

    def _result(self, key) -> EpisodeResult:
        started = self._episodes[key]
        return EpisodeResult(self._teaching_episodes[key], phase=started["phase"], phase_index=key[0],
                             episode_number=key[1])

    # -- driving --------------------------------------------------------------------------------------
    def _expect(self, call: str, *kinds: str) -> Slot:
        slot = self._slot
        if self._ended is not None:
            raise SessionStateError(f"{call}: the session ended ({self._ended}); nothing more is recorded")
        kind = self.plan.steps[slot.index].kind if slot.kind == StepKind.STEP else slot.kind
        if kind not in kinds:
            raise SessionStateError(f"{call}: expected the current step to be {' or '.join(kinds)}, it is "
                                    f"{self._describe(slot)}")
        return slot

    def _complete(self) -> None:
        self._position += 1
        self._enter()

    def advance(self) -> Step:
        """Completes a text step (welcome, consent, instructions, phase_intro, reproduction).

        Returns:
            The next step.
        """
        slot = self._expect("advance", "welcome", "consent", "instructions", "phase_intro", "reproduction", "text",
                            "information")
        if slot.kind == StepKind.STEP:
            step = self.plan.steps[slot.index]
            if step.kind == "consent":
                self.log.append("consent_given", step=step.id)
            else:
                self.log.append("step_done", step=step.id, kind=step.kind)
        elif slot.kind == StepKind.CONSENT:
            self.log.append("consent_given")
        else:
            fields = {}
            if slot.phase_index is not None:
                fields.update(phase=self._phase(slot).id, phase_index=slot.phase_index)
            if slot.episode is not None:
                fields["episode"] = slot.episode
            self.log.append("screen_done", screen=slot.kind, **fields)
        self._complete()
        return self.current_step()

    def decline_consent(self) -> Step:
        """"I do not agree": ends the session (logged; the participant is kept out of the analysis)."""
        slot = self._expect("decline_consent", "consent")
        step_id = self.plan.steps[slot.index].id if slot.kind == StepKind.STEP else None
        self.log.append("consent_declined", step=step_id)
        self._end("declined", step=step_id)
        return self.current_step()

    def submit_answers(self, answers) -> Step:
        """Completes an eligibility, demographics or questionnaire step with its answers.

        Args:
            answers: {item id: answer}; validated against the step's items (``Item.check``).

        Returns:
            The next step; an "ended" step (the protocol's ``texts.ineligible``) when an answer is
            outside what its item accepts as eligible (``Item.is_eligible``): screened out.
        """
        slot = self._expect("submit_answers", "eligibility", "demographics", "questionnaire")
        step = self.plan.steps[slot.index]
        answers = step.check_answers(answers)
        # A screener, or any asking step with an item that screens (an age band): same outcome.
        if step.kind == "eligibility" or any(item.screens for item in step.items):
            eligible = all(item.is_eligible(answers[item.id]) for item in step.items)
            self.log.append("step_done", step=step.id, kind=step.kind, answers=answers, eligible=eligible)
            if not eligible:
                self.log.append("screened_out", step=step.id, answers=answers)
                self._end("ineligible", step=step.id)
                return self.current_step()
        else:
            self.log.append("step_done", step=step.id, kind=step.kind, answers=answers)
        self._complete()
        return self.current_step()

    def finish_video(self, watched_to_end: bool, plays: int = 1) -> Step:
        """Completes a video step.

        Args:
            watched_to_end: whether the video played to its end at least once.
            plays: how many times it was started (replays included).
        """
        slot = self._expect("finish_video", "video")
        step = self.plan.steps[slot.index]
        if not isinstance(watched_to_end, bool):
            raise TypeError(f"watched_to_end: expected a bool, got {type(watched_to_end).__name__}")
        plays = as_count("plays", plays, minimum=0)
        if step.require_watched and not watched_to_end:
            raise SessionStateError(f"finish_video: step {step.id!r} requires the video to be watched to the end")
        self.log.append("step_done", step=step.id, kind=step.kind, watched_to_end=watched_to_end, plays=int(plays))
        self._complete()
        return self.current_step()

    def withdraw(self, reason: str = "") -> Step:
        """The participant withdraws, at any step: logged, then the protocol's data policy.

        With ``withdrawal = "exclude"`` (the default) the log is kept and left out of the
        analysis and the export; with ``"delete"`` the participant's log is deleted after the
        study folder records the withdrawal. Either way the session cannot be resumed.
        """
        if self._ended is not None:
            raise SessionStateError(f"withdraw: the session already ended ({self._ended})")
        if not isinstance(reason, str):
            raise TypeError(f"reason: expected text, got {type(reason).__name__}")
        policy = self.protocol.withdrawal
        at = self._describe(self._slot)
        self.log.append("withdrawn", reason=reason, data=policy, at=at)
        self._end("withdrawn", reason=reason, data=policy, step_reached=at)
        if policy == "delete" and self.folder is not None:
            self.log.close()
            for plan in self.protocol.sessions:
                self.folder.log_path(self.participant, plan.id).unlink(missing_ok=True)
        return self.current_step()

    def _end(self, ending: str, **fields) -> None:
        self._ended = ending
        if self.folder is not None:
            outcome = {"declined": "declined", "ineligible": "ineligible", "withdrawn": "withdrawn"}[ending]
            self.folder.record_outcome(self.participant, outcome, **fields)

    def finish_practice(self, duration_s: float | None = None) -> Step:
        """Completes the practice step.

        Args:
            duration_s: how long the participant practised, seconds (default: measured by the
                engine since the practice step began in this process).
        """
        self._expect("finish_practice", "practice")
        measured = time.monotonic() - self._entered_at
        duration_s = measured if duration_s is None else as_positive("duration_s", duration_s, allow_zero=True)
        self.log.append("practice_finished", duration_s=duration_s)
        self._complete()
        return self.current_step()

    def submit_demonstration(self, action, timings: Mapping | None = None, index: int | None = None) -> Feedback:
        """Records the action for the current query state; returns once it is on disk.

        Args:
            action: (R,) the demonstrated action, in the skill's action units; or the
                ``Demonstration`` a view built from the step's ``teaching_episode`` (its method,
                timings and redraws are logged, and that very object is what the episode keeps).
            timings: ``time_to_first_input_s`` and ``drawing_duration_s`` in seconds (None
                when unknown), plus any other input details to log (method, redraws, ...); None
                with a ``Demonstration``, which carries its own.
            index: the 0-based demonstration the caller means; if given and not the current
                one the call is refused (a double click cannot record an action twice).

        Returns:
            ``Feedback``: the optimal action if this episode shows guidance, else None.
        """
        slot = self._expect("submit_demonstration", "demonstration")
        if index is not None and index != slot.index:
            raise SessionStateError(f"index: expected the current demonstration {slot.index}, got {index}; "
                                    f"it was already recorded or is not reached yet")
        key = (slot.phase_index, slot.episode)
        started = self._episodes[key]
        teaching = self._teaching_episodes[key]
        if isinstance(action, Demonstration):
            demonstration = action
            if timings is not None:
                raise ValueError(f"timings: expected None with a Demonstration (it carries its own), got "
                                 f"{type(timings).__name__}")
            if demonstration.index != slot.index or not np.array_equal(demonstration.state,
                                                                        teaching.query_states[slot.index]):
                raise SessionStateError(f"action: expected a Demonstration at the current state {slot.index} of "
                                        f"{self._describe(slot)}, got one at state {demonstration.index} of "
                                        f"another episode or state")
            timings = {"time_to_first_input_s": demonstration.time_to_first_input_s,
                       "drawing_duration_s": demonstration.drawing_duration_s, "method": demonstration.method,
                       "redraws": demonstration.redraws}
        else:
            try:
                teaching.check_action(action)
            except ValueError as error:  # the episode's own check, said for this step
                raise ValueError(f"action: expected {teaching.action_dim} finite numbers, got {action!r}: "
                                 f"{error}"[:300]) from None
            demonstration = None
        if timings is None:
            timings = {}
        if not isinstance(timings, Mapping):
            raise ValueError(f"timings: expected a mapping (e.g. {{'time_to_first_input_s': 1.2, "
                             f"'drawing_duration_s': 0.8}}) or None, got {type(timings).__name__} {timings!r}")
        timings = dict(timings)
        measured = {key_: _check_seconds(f"timings[{key_!r}]", timings.pop(key_, None)) for key_ in TIMING_KEYS}
        for name, value in timings.items():  # refused here, by name, rather than inside the log write
            try:
                to_jsonable(value)
            except TypeError:
                raise ValueError(f"timings[{name!r}]: expected JSON-like data (numbers, text, lists, dicts), "
                                 f"got {type(value).__name__}") from None
        if demonstration is None:
            redraws = timings.get("redraws", 0)
            demonstration = teaching.analyse(
                action, method=str(timings.get("method", "code")), **measured,
                redraws=redraws if isinstance(redraws, int) and not isinstance(redraws, bool) else 0,
                confirmed_at=time.time(), guidance_shown=started["guidance"], episode_index=slot.episode - 1)
        optimal = np.asarray(started["optimal"])[slot.index]
        self.log.append("demonstration", phase=started["phase"], phase_index=slot.phase_index, episode=slot.episode,
                        index=slot.index, state=np.asarray(started["query_states"])[slot.index],
                        action=demonstration.action, optimal=optimal, guidance_shown=started["guidance"], **measured,
                        response_time_s=time.monotonic() - self._entered_at, input=timings,
                        modality="hand" if timings.get("method") == "hand" else "drawn")
        teaching.record(demonstration)  # on disk: now the episode keeps it (a view's record: that object)
        self._complete()
        return Feedback(slot.index, started["guidance"], optimal.copy() if started["guidance"] else None,
                        demonstration.action, started["guidance_modality"])

    def finish_episode(self, episode: TeachingEpisode | None = None) -> EpisodeResult:
        """Records the finished episode (what was learnt, its error and its reproduction) in the log.

        Args:
            episode: the ``TeachingEpisode`` a view ran on this step's query states with the
                logged actions, when it is not the step's own ``teaching_episode`` (which a view
                normally demonstrates into); it is checked against the log and kept as it is, so
                its one reproduction serves both the view and the log. None: the step's own.

        Returns:
            The ``EpisodeResult`` (the next step is the reproduction).
        """
        slot = self._expect("finish_episode", "episode_end")
        key = (slot.phase_index, slot.episode)
        started = self._episodes[key]
        if episode is not None and episode is not self._teaching_episodes[key]:
            self._check_recorded(episode, started, self._teaching_episodes[key])
            self._teaching_episodes[key] = episode
        teaching = self._teaching_episodes[key]
        trajectory = teaching.reproduction
        self.log.append(
            "episode_finished", phase=started["phase"], phase_index=slot.phase_index, episode=slot.episode,
            skill=started["skill"], guidance=started["guidance"], actions=teaching.actions,
            optimal=teaching.optimal_actions, theta_hat=teaching.theta_hat, teaching_error=teaching.error,
            rho1=teaching.rho1, rho2=teaching.rho2, bound=teaching.bound, residual=teaching.residual_norm,
            contributions=teaching.contribution_norms, exact=teaching.exact,
            reproduction={"diverged": trajectory.diverged, "diverged_at": trajectory.diverged_at,
                          "final_position": trajectory.final_position, "duration_s": float(trajectory.times[-1])},
            started_at=started["time"], duration_s=max(0.0, time.time() - _parse_time(started["time"])))
        self._finished.add(key)
        self._complete()
        return self._result(key)

    def _check_recorded(self, episode, started: dict, logged: TeachingEpisode) -> None:
        """Refuses an episode that is not the one this step logged (other states, actions, lambda...)."""
        if not isinstance(episode, TeachingEpisode):
            raise ValueError(f"episode: expected a TeachingEpisode or None, got {type(episode).__name__}")
        duration = self.protocol.reproduction_duration_s
        duration = self.protocol.skills[started["skill"]].default_duration if duration is None else duration
        checks = (
            ("skill", episode.skill.key == started["skill"]
             and np.array_equal(episode.skill.theta, np.asarray(started["theta"], dtype=float)),
             f"the skill {started['skill']!r} and its theta", repr(episode.skill.key)),
            ("lam", episode.lam == self.protocol.lam, f"the protocol's lam {self.protocol.lam}", episode.lam),
            ("duration", episode.duration == duration, f"the protocol's reproduction of {duration} s",
             episode.duration),
            ("query_states", np.array_equal(episode.query_states, np.asarray(started["query_states"], dtype=float)),
             "this step's logged query states", "other states"),
            ("actions", episode.complete and np.array_equal(episode.actions, logged.actions),
             f"the {len(logged.demonstrations)} logged actions, all given",
             f"{len(episode.demonstrations)} other or fewer"),
        )
        for name, ok, wanted, got in checks:
            if not ok:
                raise ValueError(f"episode: expected a TeachingEpisode with {wanted} (episode.{name}), got {got}")

    def close(self) -> None:
        """Releases the participant's log (the session can be resumed later)."""
        self.log.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        return f"Session({self.participant!r} at {self._describe(self._slot)})"
