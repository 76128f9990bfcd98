"""A whole teaching episode of a plant drawn in space, with the study-facing interface of ``EpisodeWidget``.

``SpaceTeachingCanvas`` draws the 3-D demonstrations, the guidance and the reproduction itself;
this widget puts the teaching-effort progress above it and gives the pages what they drive an
``EpisodeWidget`` by: the ``phase`` trait ("teaching", "guidance", "finished"), ``state_index``,
``error``, the ``on_demonstration`` and ``on_finished`` callbacks, ``result`` (an
``EpisodeResult``) and a ``next_actions`` box where a page puts what comes after the episode.
It uses the canvas through its public API only.

Which of the two a page builds is the plant's to say: ``drawn_in_space(skill)`` is true when the
skill's plant draws itself as a ``SpaceDrawing`` (``episode_widget_class``); no page asks which
robot it shows.

The canvas records each confirmed demonstration in the episode before its ``on_confirm``
callbacks run, so ``on_demonstration`` here runs once the episode holds it (``EpisodeWidget``
calls it before). A study page that cannot log it stops for the experimenter (the page is then
replaced and the session closed, ``apps/study/participant.py``), so nothing shows guidance for,
or moves past, a demonstration that is not on disk; a reload rebuilds the episode from the log.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ipywidgets import HTML, Layout, VBox
from traitlets import Float, Int, Unicode

from mt_widgets.core import SKILLS, EpisodeResult, Skill, TeachingEpisode
from mt_widgets.core.drawing import SpaceDrawing
from mt_widgets.core.guidance import guidance_parts
from mt_widgets.core.validation import as_bool, as_count

from .callbacks import Callbacks
from .episode import episode_to_show
from .progress import EffortProgress
from .space_teaching import SpaceTeachingCanvas


def drawn_in_space(skill) -> bool:
    """Whether ``skill`` (a ``Skill``, a skill key or a ``TeachingEpisode``) has a plant drawn in space."""
    if isinstance(skill, TeachingEpisode):
        skill = skill.skill
    elif isinstance(skill, str):
        skill = SKILLS[skill]
    if not isinstance(skill, Skill):
        raise TypeError(f"skill: expected a Skill, a skill key or a TeachingEpisode, got {type(skill).__name__}")
    return isinstance(skill.plant.drawing(), SpaceDrawing)


class _EpisodeCanvas(SpaceTeachingCanvas):
    """The canvas, telling its episode widget each time it leaves a state (``advance``)."""

    def __init__(self, *args, after_advance: Callable[[], None], **kwargs):
        self._after_advance = after_advance
        super().__init__(*args, **kwargs)

    def advance(self) -> None:
        super().advance()
        self._after_advance()


class SpaceEpisodeWidget(VBox):
    """A full teaching episode of a plant drawn in space (the UR5): progress, 3-D canvas, reproduction.

    Args:
        skill: a ``Skill`` whose plant is drawn in space, its key ("ur5-reach"), or the
            ``TeachingEpisode`` to show (then leave ``query_states``, ``duration`` unset).
        query_states: (N, state_dim) states to demonstrate at (default: the skill's, from ``seed``).
        seed: seed of the default query states.
        guidance: show the optimal arrow after each demonstration ("Next state" or Enter goes on).
        guidance_modality: as ``EpisodeWidget``'s; guidance is shown when it has arrows or words
            (the 3-D canvas draws the arrows and says both in its words, its text alternative).
        lam: the learner's ridge parameter (default ``DEFAULT_LAMBDA``, or the episode's own).
        theme: a ``Theme`` or theme name.
        duration: reproduction length in seconds (default: the skill's).
        episode_index, episodes_total: this episode's index and the phase's episodes (progress).
        on_demonstration: ``callback(demonstration)`` after each confirmation.
        on_finished: ``callback(result: EpisodeResult)`` once the reproduction is sent.
        title: heading above the episode (default: the skill's title; "" for none).
        show_description: show the skill's description (its formula) under the title.
        reproduce: play the learnt skill when the episode is complete (False: drawing only, as a
            practice round; the phase still becomes "finished", ``result`` stays None).
        panel_size: pixels of each of the canvas's views.
    """

    phase = Unicode("teaching", help="One of 'teaching', 'guidance', 'finished'.")
    state_index = Int(0, help="Index of the query state shown (the number of demonstrations given).")
    error = Float(None, allow_none=True, help="Teaching error once the episode is finished.")

    def __init__(self, skill="ur5-reach", query_states=None, seed: int | None = 0, guidance: bool = True,
                 guidance_modality: str = "arrows+words", lam: float | None = None, theme=None,
                 duration: float | None = None, episode_index: int = 0, episodes_total: int = 1,
                 on_demonstration: Callable | None = None, on_finished: Callable | None = None,
                 title: str | None = None, show_description: bool = True, reproduce: bool = True,
                 panel_size: int = 260):
        arrows, words = guidance_parts(guidance_modality)
        self.guidance_modality = guidance_modality
        episode = episode_to_show(skill, query_states, seed, lam, duration)
        #: The ``TeachingEpisode`` shown (the one place its demonstrations live).
        self.episode = episode
        self.guidance = as_bool("guidance", guidance) and (arrows or words)
        self.reproduce = as_bool("reproduce", reproduce)
        show_description = as_bool("show_description", show_description)
        self.episode_index = as_count("episode_index", episode_index, minimum=0)
        self.result: EpisodeResult | None = None
        self._demonstration_callbacks = Callbacks()
        self._finished_callbacks = Callbacks()
        if on_demonstration is not None:
            self.on_demonstration(on_demonstration)
        if on_finished is not None:
            self.on_finished(on_finished)
        self._confirmed_at = None
        #: The 3-D canvas (``SpaceTeachingCanvas``): views, arrows, keyboard, typed numbers, replay.
        self.canvas = _EpisodeCanvas(episode, theme=theme, guidance=self.guidance, play=False,
                                     panel_size=panel_size, after_advance=self._after_advance)
        self.theme = self.canvas.theme
        self.progress = EffortProgress(episode.n_states, max(int(episodes_total), self.episode_index + 1),
                                       episodes_done=self.episode_index)
        heading = title if title is not None else self.skill.title
        description = f"<div style='max-width:760px'>{self.skill.description}</div>" if show_description else ""
        self.header = HTML(f"<h3 style='margin:4px 0'>{heading}</h3>{description}" if heading or description else "")
        #: Where a page puts what comes after the episode (a study's Continue), under the canvas.
        self.next_actions = VBox(layout=Layout(margin="8px 0 0 0"))
        self.canvas.on_confirm(self._on_confirm)
        super().__init__([self.header, self.progress, self.canvas, self.next_actions])
        self.add_class("mt-focus")
        self.state_index = len(episode.demonstrations)
        self.progress.demonstrations_done = len(episode.demonstrations)
        if episode.complete:  # resumed with every demonstration given: what it learnt, at once
            self.finish()

    # -- the episode's facts ---------------------------------------------------------------------------
    @property
    def skill(self) -> Skill:
        return self.episode.skill

    @property
    def records(self):
        """The confirmed demonstrations: the episode's own list."""
        return self.episode.demonstrations

    @property
    def query_states(self):
        return self.episode.query_states

    # -- callbacks -------------------------------------------------------------------------------------
    def on_demonstration(self, callback: Callable, remove: bool = False) -> None:
        """Register ``callback(demonstration)``, called after each confirmed demonstration is recorded."""
        self._demonstration_callbacks.register_callback(callback, remove=remove)

    def on_finished(self, callback: Callable[[EpisodeResult], None], remove: bool = False) -> None:
        """Register ``callback(result)``, called when the episode is learnt and its reproduction sent."""
        self._finished_callbacks.register_callback(callback, remove=remove)

    # -- driving it from code --------------------------------------------------------------------------
    def demonstrate(self, action):
        """Set and confirm ``action`` (3,) at the current state, as if drawn (method "code")."""
        if self.phase != "teaching":
            raise RuntimeError(f"demonstrate: expected phase 'teaching', the episode is in {self.phase!r}"
                               + ("; call next() after guidance" if self.phase == "guidance" else ""))
        self.canvas.set_action(action)
        return self.canvas.confirm()

    def next(self) -> None:
        """Leave the guidance of the current state: the next state, or the reproduction."""
        if self.phase != "guidance":
            raise RuntimeError(f"next: expected phase 'guidance', the episode is in {self.phase!r}")
        self.canvas.advance()

    def finish(self) -> EpisodeResult | None:
        """Show what the robot learnt: play the reproduction in every view (when ``reproduce``)."""
        if not self.episode.complete:
            raise RuntimeError(f"finish: expected {self.episode.n_states} demonstrations, "
                               f"got {len(self.episode.demonstrations)}")
        self.progress.episodes_done = min(self.episode_index + 1, self.progress.episode_budget)
        if not self.reproduce:
            self.phase = "finished"
            return None
        started = time.perf_counter()
        self.canvas.play()
        self.result = EpisodeResult(self.episode, feedback_latency_s=time.perf_counter() - started)
        self.error = self.episode.error
        self.phase = "finished"
        self._finished_callbacks(self.result)
        return self.result

    # -- internals -------------------------------------------------------------------------------------
    def _on_confirm(self, demonstration) -> None:
        self._demonstration_callbacks(demonstration)
        done = len(self.episode.demonstrations)
        self.progress.demonstrations_done = done
        self.state_index = done
        if self.guidance:
            # The canvas shows the optimal arrow once this returns; its button then says where it goes.
            self.canvas.next_button.description = "Finish and watch" if self.episode.complete else "Next state"
            self.phase = "guidance"

    def _after_advance(self) -> None:
        if self.phase == "finished":
            return
        if self.episode.complete:
            self.finish()
        else:
            self.phase = "teaching"
