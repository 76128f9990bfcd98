"""What the session engine hands a view: the current ``Step``, a demonstration's ``Feedback`` and an
episode's ``EpisodeResult`` (``mt_widgets.study.session`` builds them; views only read them).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mt_widgets.core import TeachingEpisode

from .steps import StudyStep


@dataclass(frozen=True)
class EpisodeResult:
    """What the learner made of one episode.

    Attributes:
        theta_hat: (R, S) the learnt policy.
        teaching_error: E = ||vec(theta_hat) - vec(theta)||.
        rho1, rho2: the risk decomposition (see ``mt_widgets.core.TeachingEpisode``).
        diverged: whether the reproduction left the plant's bounds.
        episode: the ``TeachingEpisode`` recorded (query states, actions, contributions, ...).
        trajectory: the reproduction (a ``Trajectory``) from the skill's start: the episode's
            one rollout, made when first read.
    """

    phase: str
    phase_index: int
    episode: int
    skill: str
    theta_hat: np.ndarray
    teaching_error: float
    rho1: float
    rho2: float
    diverged: bool
    teaching_episode: TeachingEpisode = field(repr=False, compare=False)

    @property
    def trajectory(self):
        return self.teaching_episode.reproduction


@dataclass(frozen=True)
class Feedback:
    """What ``submit_demonstration`` returns: the optimal action only where guidance is shown."""

    index: int
    guidance: bool
    optimal: np.ndarray | None
    action: np.ndarray
    guidance_modality: str = "arrows+words"


@dataclass(frozen=True)
class Step:
    """The step a participant is at, with what a view needs to show it.

    Attributes:
        kind: welcome, consent, instructions, practice, phase_intro, demonstration,
            episode_end, reproduction, thank_you; a protocol step's kind (text, video,
            information, consent, eligibility, demographics, questionnaire); or "ended" when
            the session ended early (``ended`` says why).
        text: the protocol's text for this step (empty for demonstrations).
        phase, phase_index: the phase id ("P3") and its 0-based index, or None.
        episode, n_episodes: 1-based episode within the phase, and the phase's episodes.
        index, n_demonstrations: 0-based demonstration within the episode, and per episode.
        skill: the key of the skill taught (or practised).
        query_states: (N, state_dim) the episode's query states.
        state: (state_dim,) the current query state.
        actions: the actions already given in this episode (to restore a view on resume).
        guidance: whether guidance follows each demonstration in this episode.
        duration_s: the practice time.
        result: the ``EpisodeResult`` a reproduction step shows.
        study_step: the protocol's ``StudyStep`` for a step around the task.
        guidance_modality: how guidance is shown ("arrows", "arrows+words", "words", "none").
        practice_reproduction: whether practice rounds end with a reproduction.
        ended: why the session ended early ("declined", "ineligible", "withdrawn"), else None.
        teaching_episode: the step's ``TeachingEpisode`` (demonstration, episode end and
            reproduction steps): the one object a view shows and the log records, so an episode
            is built (one SVD) and rolled out once. A view demonstrates into it (after a resume
            it first restores the step's ``actions``); without a view the session records the
            logged actions into it when it finishes the episode.
        reentry_code: at the thank-you of a session that another follows, the code the
            participant notes to come back with (their ID works too); None otherwise.
        next_session: there too, {"id": the next session, "window": when, in words}.
    """

    kind: str
    text: str = ""
    phase: str | None = None
    phase_index: int | None = None
    episode: int | None = None
    n_episodes: int | None = None
    index: int | None = None
    n_demonstrations: int | None = None
    skill: str | None = None
    query_states: np.ndarray | None = None
    state: np.ndarray | None = None
    actions: tuple = ()
    guidance: bool = False
    duration_s: float | None = None
    result: EpisodeResult | None = None
    study_step: StudyStep | None = None
    guidance_modality: str = "arrows+words"
    practice_reproduction: bool = True
    ended: str | None = None
    teaching_episode: TeachingEpisode | None = field(default=None, repr=False, compare=False)
    reentry_code: str | None = None
    next_session: dict | None = None
