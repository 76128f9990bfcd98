"""A protocol session unrolled into steps, and each episode's query states: the one place both are derived.

The session engine (``mt_widgets.study.session``) walks this timeline and the in-silico plan
(``mt_widgets.in_silico.plan``) reads the same episodes and the same states from here, so a
synthetic study and a real one meet the same episodes in the same order with the same states::

    welcome -> the session's [[before]] steps (consent right after the welcome when they
    have none, in the first session) -> instructions -> practice (first session, if
    duration_s > 0)
    -> for each phase: phase_intro
         -> for each episode: demonstration x N -> episode_end
            -> reproduction (after every episode, or after the phase's last one when the
               protocol says reproduction = "phase")
    -> the session's [[after]] steps -> thank_you

Query states: episode e (0-based) of a phase draws from ``SeedSchedule(seed).seed(
phase.states_index, e[, participant])``. With ``[matched_difficulty]`` a draw whose learner
sensitivity ||A||_F (A: the learner's ridge map, ``mt_widgets.core.episode_batch``) falls
outside the band is redrawn from the same seed's next child (``spawn_key + (attempt,)``), in
order, so the result is as reproducible as the first draw; attempt 0 is the plain seed.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from mt_widgets.core import SeedSchedule
from mt_widgets.core.episode_batch import EpisodeBatch
from mt_widgets.core.learner import RidgeLearner


class StepKind(str, Enum):
    """The kinds of step of a timeline (a protocol's own steps are ``STEP`` slots; their kinds
    are ``mt_widgets.study.steps.STEP_KINDS``). Equal to their text: ``StepKind.WELCOME == "welcome"``."""

    WELCOME = "welcome"
    CONSENT = "consent"
    STEP = "step"
    INSTRUCTIONS = "instructions"
    PRACTICE = "practice"
    PHASE_INTRO = "phase_intro"
    DEMONSTRATION = "demonstration"
    EPISODE_END = "episode_end"
    REPRODUCTION = "reproduction"
    THANK_YOU = "thank_you"

    __str__ = str.__str__
    __format__ = str.__format__


#: Screens completed by ``Session.advance`` with a ``screen_done`` event.
SCREENS = (StepKind.WELCOME, StepKind.INSTRUCTIONS, StepKind.PHASE_INTRO, StepKind.REPRODUCTION)
#: Events that end a session before the thank-you, and the text key each ends with.
ENDING_EVENTS = {"consent_declined": "declined", "screened_out": "ineligible", "withdrawn": "withdrawn"}
#: When the robot reproduces what it learnt: after every episode, or after each phase's last.
REPRODUCTION_TIMINGS = ("episode", "phase")
#: How many draws matched difficulty tries per episode before it says the band is too narrow.
MAX_DIFFICULTY_DRAWS = 500


@dataclass(frozen=True)
class Slot:
    """One step of a timeline.

    Attributes:
        kind: a ``StepKind``.
        phase_index: 0-based phase within the session (phase steps), else None.
        episode: 1-based episode within the phase, else None.
        index: 0-based demonstration within the episode, or for a ``STEP`` slot the index in
            the session's ``steps``; else None.
    """

    kind: str
    phase_index: int | None = None
    episode: int | None = None
    index: int | None = None


def timeline(protocol, around_task: bool = True, session: str | None = None) -> list[Slot]:
    """One session of the protocol unrolled into the steps a participant goes through, in order.

    A step of the session's ``before`` / ``after`` lists is ``Slot("step", index=i)`` with i
    its index in the session's ``steps``. ``around_task=False`` leaves those steps out (a lesson
    runs the task only: welcome, the default consent, instructions, practice, the phases).

    Args:
        protocol: the ``Protocol``.
        around_task: whether the protocol's steps around the task are included.
        session: the id of one of ``protocol.sessions`` (None: the first).
    """
    plan = protocol.session(session)
    before = plan.before if around_task else ()
    slots = [Slot(StepKind.WELCOME)]
    if plan.default_consent and not any(step.kind == "consent" for step in before):
        slots.append(Slot(StepKind.CONSENT))
    slots += [Slot(StepKind.STEP, index=i) for i in range(len(before))]
    slots.append(Slot(StepKind.INSTRUCTIONS))
    if plan.practice and protocol.practice.duration_s > 0:
        slots.append(Slot(StepKind.PRACTICE))
    for phase in plan.phases:
        slots.append(Slot(StepKind.PHASE_INTRO, phase.index))
        for episode in range(1, phase.episodes + 1):
            slots += [Slot(StepKind.DEMONSTRATION, phase.index, episode, i) for i in range(phase.demonstrations)]
            slots.append(Slot(StepKind.EPISODE_END, phase.index, episode))
            if protocol.reproduce_after == "episode" or episode == phase.episodes:
                slots.append(Slot(StepKind.REPRODUCTION, phase.index, episode))
    if around_task:
        slots += [Slot(StepKind.STEP, index=len(plan.before) + j) for j in range(len(plan.after))]
    slots.append(Slot(StepKind.THANK_YOU))
    return slots


@dataclass(frozen=True)
class PlannedEpisode:
    """One episode of a protocol, in order across its sessions (what the in-silico engine runs).

    Attributes:
        session: the protocol session's id; phase, phase_index (within the session), episode
            (1-based), episode_index (0-based), skill, demonstrations, guidance (groups),
        states_index: the seed position of the phase's states.
    """

    session: str
    phase: str
    phase_index: int
    episode: int
    skill: str
    demonstrations: int
    guidance: tuple
    states_index: int

    @property
    def episode_index(self) -> int:
        return self.episode - 1


def planned_episodes(protocol, session: str | None = None) -> list[PlannedEpisode]:
    """Every episode of the protocol's sessions in order (or of one session)."""
    sessions = protocol.sessions if session is None else (protocol.session(session),)
    return [PlannedEpisode(plan.id, phase.id, phase.index, e, phase.skill, phase.demonstrations, phase.guidance,
                           phase.states_index)
            for plan in sessions for phase in plan.phases for e in range(1, phase.episodes + 1)]


def learner_sensitivity(skill, states, lam: float) -> float:
    """||A||_F of the learner's ridge map on ``states``: how much a unit slip of the arrows moves
    the learnt policy (the same slip costs more where it is larger)."""
    batch = EpisodeBatch.of(skill, np.asarray(states, dtype=float)[None], RidgeLearner(lam))
    return float(np.linalg.norm(batch.learner_map[0]))


def episode_query_states(protocol, states_index: int, episode: int, demonstrations: int, skill_key: str,
                         participant: int | None = None, study_seed: int | None = None):
    """The query states of one episode and the seed they came from.

    Args:
        protocol: the ``Protocol`` (its seed, query_states rule, lambda, matched difficulty).
        states_index: the phase's ``states_index``.
        episode: 1-based episode within the phase.
        demonstrations: how many states.
        skill_key: the phase's skill.
        participant: the enrolment number (used when states are drawn per participant).
        study_seed: overrides the protocol's seed (each simulated study of a power analysis).

    Returns:
        (states (demonstrations, state_dim), the ``SeedSequence`` drawn from).

    Raises:
        ValueError: with matched difficulty, no draw within ``MAX_DIFFICULTY_DRAWS`` lies in the band.
    """
    seed_value = protocol.seed if study_seed is None else study_seed
    who = participant if protocol.query_states == "per-participant" else None
    seed = SeedSchedule(seed_value).seed(states_index, episode - 1, who)
    skill = protocol.skill(skill_key)
    band = protocol.matched_difficulty
    for attempt in range(MAX_DIFFICULTY_DRAWS if band is not None else 1):
        drawn = seed if attempt == 0 else np.random.SeedSequence(seed.entropy, spawn_key=seed.spawn_key + (attempt,))
        states = skill.query_states(seed=drawn, n=demonstrations)
        if band is None or band[0] <= learner_sensitivity(skill, states, protocol.lam) <= band[1]:
            return states, drawn
    raise ValueError(f"matched_difficulty: no query states of skill {skill_key!r} with ||A||_F in "
                     f"[{band[0]}, {band[1]}] in {MAX_DIFFICULTY_DRAWS} draws; widen the band")
