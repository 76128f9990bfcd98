"""Synthetic teachers through the session engine: real study logs, written as people's are.

``run_through_sessions`` enrols synthetic participants in a study folder and drives each through
``mt_widgets.study.Session`` one demonstration at a time, so the folder holds exactly what a real
study writes; the shipped example studies (``mt_widgets.analysis.example_studies``) are made so.
"""

from __future__ import annotations

import datetime as _dt

import numpy as np

from mt_widgets.core.validation import as_bool, as_count
from mt_widgets.study.session import Session
from mt_widgets.study.study_folder import StudyFolder

from .plan import (
    default_parameters,
    episode_plan,
    imagined_line_target,
    participant_id,
    resolve_protocol,
    session_delays,
    teacher_seed,
)
from .progress import Progress
from .teachers import TeacherParameters, TeacherPopulation, along_line_offsets, position_gain, target_offsets


class SessionTeacher:
    """One synthetic teacher driving a ``Session`` exactly as the study app drives it for a person.

    The teacher sees what a participant sees: the episode's query states as they appear, and
    after each demonstration the optimal arrow only when the session shows guidance. Its arrows
    are those the batched engine computes for the same seed (the same model, the same draws).

    Args:
        protocol: the ``Protocol``.
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        seed: the teacher's seed (``teacher_seed(run_seed, participant)``).
    """

    def __init__(self, protocol, parameters: TeacherParameters | None, seed):
        self.protocol = protocol
        # Answers to the steps around the task come from a stream of their own, so adding a
        # questionnaire to a protocol does not change anyone's arrows.
        self._answers_rng = np.random.default_rng(np.random.SeedSequence(
            seed.entropy, spawn_key=tuple(seed.spawn_key) + (7,)) if isinstance(seed, np.random.SeedSequence)
            else np.random.SeedSequence(int(seed), spawn_key=(7,)))
        self.plan = episode_plan(protocol)
        self._episode_of = {(step["session"], step["phase_index"], step["episode"]): e
                            for e, step in enumerate(self.plan)}
        parameters = default_parameters(protocol) if parameters is None else parameters
        self.population = TeacherPopulation.draw(parameters, [seed], len(self.plan),
                                                 max(step["demonstrations"] for step in self.plan))
        self._episode = None

    def run(self, session) -> list:
        """Takes the session from its current step to the end; returns the ``EpisodeResult``s."""
        results = []
        while not session.finished:
            step = session.current_step()
            if step.kind == "demonstration":
                self.demonstrate(session, step)
            elif step.kind == "episode_end":
                results.append(session.finish_episode())
                if self.plan[self._episode_of[(session.plan.id, step.phase_index, step.episode)]]["reproduced"]:
                    self.population.see_reproduction()
            elif step.kind == "practice":
                session.finish_practice(duration_s=float(step.duration_s or 0.0))
            elif step.kind == "video":
                session.finish_video(watched_to_end=True, plays=1)
            elif step.kind in ("eligibility", "demographics", "questionnaire"):
                session.submit_answers(self.answers(step.study_step))
            else:
                session.advance()
        return results

    def answers(self, study_step) -> dict:
        """Answers to an asking step: eligible ones to a screener (synthetic teachers are novices),
        and seeded draws for the rest (a number inside its bounds, a level or option, no free text)."""
        answers = {}
        for item in study_step.items:
            if item.eligible:
                answers[item.id] = item.eligible[0]
            elif item.kind in ("likert", "choice"):
                answers[item.id] = item.choices[int(self._answers_rng.integers(len(item.choices)))]
            elif item.kind == "number":
                # Inside the eligible band when the item has one (a synthetic teacher is an adult).
                floor = item.minimum if item.eligible_minimum is None else item.eligible_minimum
                ceiling = item.maximum if item.eligible_maximum is None else item.eligible_maximum
                low = 18 if floor is None else floor
                high = max(low, 40 if ceiling is None else min(ceiling, low + 22))
                value = self._answers_rng.uniform(low, high)
                answers[item.id] = int(round(value)) if item.integer else float(value)
            elif item.required:
                answers[item.id] = "synthetic participant"
        return answers

    def demonstrate(self, session, step) -> None:
        """Draws one arrow for the current query state and submits it with its timings."""
        skill = self.protocol.skill(step.skill)
        e = self._episode_of[(session.plan.id, step.phase_index, step.episode)]
        if self._episode is None or self._episode[0] != e:
            # What the teacher works from for this episode: where the target is from each tip
            # position, and the optimal arrows its understanding blends in.
            positions, _ = skill.end_effector(step.query_states)
            # The session's own episode: no second TeachingEpisode (and SVD) per study episode.
            optimal = step.teaching_episode.optimal_actions
            anchor = imagined_line_target(self.protocol, step.phase_index, session.plan.id)
            along = None if anchor is None else along_line_offsets(positions, skill.target, anchor)
            self._episode = (e, target_offsets(skill, step.query_states), optimal, along)
        _, offsets, optimal, along = self._episode
        d = step.index
        guided = np.array([bool(step.guidance)])
        action = self.population.act(e, d, offsets[d][None], optimal[d][None], position_gain(skill.theta),
                                     skill.key, guided, None if along is None else along[d][None])[0]
        first, drawing = self.population.timings(e, d, guided)
        session.submit_demonstration(action, {"time_to_first_input_s": float(first[0]),
                                              "drawing_duration_s": float(drawing[0]), "method": "synthetic"},
                                     index=d)
        self.population.see_guidance(skill.key, guided)


def run_through_sessions(folder, n_participants: int = 8, protocol=None, parameters: TeacherParameters | None = None,
                         seed: int = 0, groups=None, progress: bool | None = None, forgetting=None,
                         delays: dict | None = None):
    """Runs synthetic teachers through the session engine into a real study folder.

    Every participant is enrolled, assigned to a group (by the protocol's randomisation unless
    ``groups`` says otherwise) and driven step by step through ``Session``, so the folder holds
    the same logs a real study writes and ``read_study`` / the analysis read it unchanged.
    Participant i is seeded ``teacher_seed(seed, i)``: ``run_in_silico`` with the same seed and
    groups gives the same arrows and teaching errors.

    Args:
        folder: the study folder (created; must not hold another protocol's study).
        n_participants: participants to run, coded "S001", "S002", ...
        protocol: a ``Protocol``, a shipped name or a path (default "paper-sim").
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        seed: root seed of the teachers.
        groups: a group per participant, or None for the protocol's randomisation.
        progress: show a progress bar (default: for more than 16 participants).
        forgetting: how teachers forget between the protocol's sessions (``Forgetting``; None:
            they do not).
        delays: {session id: seconds} after the previous session's end at which each teacher
            comes back (default: each window's earliest); the arrival is checked against the
            window as a person's is (``Session.arrive`` with that time as ``now``).

    Returns:
        The ``StudyFolder``.
    """
    progress = as_bool("progress", progress, allow_none=True)
    protocol = resolve_protocol(protocol)
    n_participants = as_count("n_participants", n_participants)
    if groups is not None and len(list(groups)) != n_participants:
        raise ValueError(f"groups: expected {n_participants} group names, got {len(list(groups))}")
    study = StudyFolder.create(folder, protocol)
    bar = Progress(n_participants, "participants", progress if progress is not None else n_participants > 16)
    delays = session_delays(protocol, delays)
    for p in range(n_participants):
        session = Session.start(study, participant_id(p), group=None if groups is None else list(groups)[p])
        teacher = SessionTeacher(protocol, parameters, teacher_seed(seed, p))
        try:
            teacher.run(session)
        finally:
            session.close()
        for later in protocol.sessions[1:]:
            if not session.completed:
                break
            ended = _dt.datetime.fromisoformat(session.events[-1]["time"].replace("Z", "+00:00"))
            teacher.population.forget(forgetting, delays[later.id])
            session = Session.arrive(study, participant_id(p), now=ended + _dt.timedelta(seconds=delays[later.id]))
            try:
                teacher.run(session)
            finally:
                session.close()
        bar.update()
    return study
