"""What the session engine hands a view: the current ``Step``, a demonstration's ``Feedback`` and an
episode's ``EpisodeResult`` (``mt_widgets.study.session`` builds them; views only read them), and
the ``SessionStateError`` a driver call that does not fit the step raises.

The ``EpisodeResult`` is core's (``mt_widgets.core.EpisodeResult``), the one a widget reports
too: the ``TeachingEpisode`` with its phase, phase index and ``episode_number``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mt_widgets.core import EpisodeResult, TeachingEpisode

from .steps import StudyStep


class SessionStateError(RuntimeError):
    """A driver call that does not fit the current step (e.g. a second submission)."""


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
        actions: the actions already given in this episode, read from ``teaching_episode`` (a
            property: the step holds no list of its own).
        guidance: whether guidance follows each demonstration in this episode.
        duration_s: the practice time.
        result: the ``EpisodeResult`` a reproduction step shows.
        study_step: the protocol's ``StudyStep`` for a step around the task.
        guidance_modality: how guidance is shown ("arrows", "arrows+words", "words", "none").
        practice_reproduction: whether practice rounds end with a reproduction.
        ended: why the session ended early ("declined", "ineligible", "withdrawn"), else None.
        teaching_episode: the step's ``TeachingEpisode`` (demonstration, episode end and
            reproduction steps): the one object a view shows and the log records, so an episode
            is built (one SVD) and rolled out once. It holds the demonstrations given so far
            (after a resume, those the log holds): a view shows it as it stands and demonstrates
            into it; ``Session.submit_demonstration`` records each one in it once it is logged.
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

    @property
    def actions(self) -> tuple:
        """The actions already given in this episode (rows of ``teaching_episode.actions``), () outside one."""
        return () if self.teaching_episode is None else tuple(self.teaching_episode.actions)


__all__ = ["EpisodeResult", "Feedback", "SessionStateError", "Step"]
