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
            result = session.finish_episode()      # theta_hat, theta_error, policy_risk, trajectory
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

A view passes the ``Demonstration`` its canvas confirmed instead of an action and timings
(``session.submit_demonstration(record, index=record.index)``): its method and timings are
logged, and that object is what the step's ``teaching_episode`` keeps, the one place an
episode's demonstrations live (``mt_widgets.study.session_episodes``).

The parts: this module (where a session stands, the steps around the episodes), its
constructors (``mt_widgets.study.session_arrival``) and its episode steps
(``mt_widgets.study.session_episodes``). The events it writes, the schema version they carry
and the migration of older logs: ``mt_widgets.study.schema``.
"""

from __future__ import annotations

import time

import numpy as np

from mt_widgets.core import TeachingEpisode
from mt_widgets.core.validation import as_count, as_positive

from .protocol import Phase, Protocol
from .replay import describe, replay
from .schema import migrate_events
from .session_arrival import SessionArrival, WindowError
from .session_episodes import TIMING_KEYS, SessionEpisodes
from .session_types import EpisodeResult, Feedback, SessionStateError, Step
from .study_folder import StudyFolder
from .timeline import ENDING_EVENTS, Slot, StepKind, timeline


class Session(SessionArrival, SessionEpisodes):
    """One participant's run through a protocol. Build with ``start``, ``resume``, ``arrive`` or
    ``lesson`` (``mt_widgets.study.session_arrival``); its episode steps are
    ``mt_widgets.study.session_episodes``'; the other steps, and where it stands, are here."""

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

    def close(self) -> None:
        """Releases the participant's log (the session can be resumed later)."""
        self.log.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        return f"Session({self.participant!r} at {self._describe(self._slot)})"


#: What this module has always offered (the engine's parts live in the modules above).
__all__ = ["ENDING_EVENTS", "TIMING_KEYS", "EpisodeResult", "Feedback", "Session", "SessionStateError", "Step",
           "WindowError", "timeline"]
