"""One teaching episode on screen: query states, demonstrations, guidance, reproduction, error.

Three lines give a full episode in a notebook::

    from mt_widgets.widgets import EpisodeWidget
    episode = EpisodeWidget("sim-point", guidance=True)
    episode

The same three lines serve every arm: ``EpisodeWidget("ur5-reach")`` teaches the UR5 in 3-D.

The episode itself is a ``mt_widgets.core.TeachingEpisode`` (``widget.episode``): it holds the
query states, the optimal actions, the demonstrations (each a ``mt_widgets.core.Demonstration``:
the action, its analysis, how and when it was given), what the robot learnt, the error and the
reproduction (rolled out once). Its state machine (pending arrow, confirm, the callbacks, record,
guidance, next, finish, restore) is one ``EpisodeController`` (``widget.controller``,
episode_controller.py), the same for every arm. This widget only shows it, with the renderer the
plant's drawing asks for (``mt_widgets.core.drawing``): a ``PlantDrawing`` gets the planar
``TeachingCanvas`` and ``ReproductionPlayer``, a ``SpaceDrawing`` the 3-D ``SpaceTeachingCanvas``
(three linked views, the reproduction played in them). No page asks which one it gets.
Nothing here keeps a second list: ``records`` and the ``demonstrations`` trait read the episode.

A study runner drives it through constructor arguments, the observable traits
(``phase``, ``state_index``, ``demonstrations``, ``theta_error``, ``policy_risk``) and the two callbacks
``on_demonstration`` and ``on_finished``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from ipywidgets import HTML, Button, HBox, Layout, VBox
from traitlets import Float, Int, List, Unicode

from mt_widgets.core import DEFAULT_LAMBDA, SKILLS, Demonstration, EpisodeResult, Skill, TeachingEpisode
from mt_widgets.core.drawing import SpaceDrawing
from mt_widgets.core.guidance import guidance_parts
from mt_widgets.core.validation import as_bool, as_count, as_positive

from .cells import VIEWS
from .episode_controller import PHASES, EpisodeController
from .guidance import GuidancePanel, explain_difference
from .looks import plain, shared_layout
from .progress import EffortProgress
from .reproduction import ReproductionPlayer
from .space_teaching import SpaceTeachingCanvas
from .teaching import TeachingCanvas

__all__ = ["PHASES", "DemonstrationRecord", "EpisodeResult", "EpisodeWidget", "episode_to_show", "keep_canvas_size",
           "stage_css"]


#: The name of a confirmed demonstration's record in the widget API (``on_demonstration``'s
#: argument): the core ``Demonstration`` the episode keeps (action, optimal action, method,
#: timings, ``guidance_shown``, ``episode_index``).
DemonstrationRecord = Demonstration


#: Vertical room (CSS px) a canvas leaves in the window: for a page's heading above it (the demo's
#: welcome and choices, the episode's title and progress) and the replay line under it, so that
#: at 1400 x 1000 the whole reproduction is on screen without scrolling; the side column's
#: width; the widest a canvas grows.
_ROOM_Y_PX, _SIDE_PX, _MAX_CANVAS_PX = 350, 420, 760
#: On a narrow page (a tablet upright) the side column is under the canvas, after the replay line
#: and the reproduction's words: room for those and for the result and the next action.
_NARROW_EXTRA_Y_PX = 360
#: Up to this width (CSS px) a page is a phone's: the canvas takes the whole width less the page's
#: margins, and the person scrolls to what is under it.
_PHONE_MAX_PX, _PHONE_SLACK_PX = 600, 36


def _canvas_class(view) -> str:
    """A CSS class per canvas aspect ratio (width / height, in hundredths)."""
    return f"mt-stage-canvas-{round(100 * view.transform.width / view.transform.height)}"


def keep_canvas_size(view) -> None:
    """Stops an ``ArmView``'s canvas from growing with the window (e.g. a true-size screen under the arm)."""
    for name in list(view.canvas._dom_classes):
        if name.startswith("mt-stage-canvas-"):
            view.canvas.remove_class(name)


def stage_css(*views) -> str:
    """A style element sizing the episode's canvases to the window.

    A canvas is as wide as the page allows beside the side column (below it on a narrow page,
    where the column wraps under the canvas), but never taller than the window minus a little
    room, so the whole reproduction is in view where the person is looking, on a laptop as on
    a large screen. Pointer input is mapped through the element's box, so any size works.
    """
    rules = []
    for view in views:
        ratio = view.transform.width / view.transform.height
        by_height = f"calc((100vh - {_ROOM_Y_PX}px) * {ratio:.4f})"
        name = _canvas_class(view)
        rules.append(f".{name} {{width: max(260px, min(calc(100vw - {_SIDE_PX + 60}px), {by_height}, "
                     f"{_MAX_CANVAS_PX}px)) !important; height: auto !important}}")
        # A narrow page puts the side column under the canvas: the canvas leaves room for its
        # first lines (the result and the next action) in the window too.
        narrow_by_height = f"calc((100vh - {_ROOM_Y_PX + _NARROW_EXTRA_Y_PX}px) * {ratio:.4f})"
        rules.append(f"@media (max-width: 860px) {{.{name} {{width: max(260px, min(calc(100vw - 40px), "
                     f"{narrow_by_height}, {_MAX_CANVAS_PX}px)) !important}}}}")
        # A phone: the canvas fills the width (a finger needs all of it); what follows is below it.
        rules.append(f"@media (max-width: {_PHONE_MAX_PX}px) {{.{name} {{width: calc(100vw - {_PHONE_SLACK_PX}px) "
                     f"!important}}}}")
    return "<style>" + "\n".join(dict.fromkeys(rules)) + "</style>"


def _resolve_skill(skill) -> Skill:
    if isinstance(skill, str):
        if skill not in SKILLS:
            raise ValueError(f"skill: expected a Skill, a TeachingEpisode or one of {sorted(SKILLS)}, got {skill!r}")
        return SKILLS[skill]
    if not isinstance(skill, Skill):
        raise TypeError(f"skill: expected a Skill, a TeachingEpisode or a skill key, got {type(skill).__name__}")
    return skill


def episode_to_show(skill, query_states, seed, lam, duration) -> TeachingEpisode:
    """The ``TeachingEpisode`` an ``EpisodeWidget`` shows.

    ``skill`` is a ``TeachingEpisode`` (shown as it is: ``query_states`` and ``duration`` must then
    be None, and ``lam`` None or its own) or a ``Skill`` or skill key, taught on ``query_states``
    (or states drawn with ``seed``) with ridge parameter ``lam`` (None: ``DEFAULT_LAMBDA``).
    """
    if isinstance(skill, TeachingEpisode):
        for name, value in (("query_states", query_states), ("duration", duration)):
            if value is not None:
                raise ValueError(f"{name}: expected None when a TeachingEpisode is shown (it has its own), "
                                 f"got {value!r}"[:200])
        if lam is not None and as_positive("lam", lam, allow_zero=True) != skill.lam:
            raise ValueError(f"lam: expected None or the shown TeachingEpisode's own ({skill.lam}), got {lam}")
        return skill
    return TeachingEpisode(_resolve_skill(skill), query_states, seed=None if query_states is not None else seed,
                           lam=DEFAULT_LAMBDA if lam is None else lam, duration=duration)


def _drawn_in_space(skill: Skill) -> bool:
    """Whether the skill's plant draws itself in space (a ``SpaceDrawing``): the 3-D renderer, else the planar one."""
    return isinstance(skill.plant.drawing(), SpaceDrawing)


class EpisodeWidget(VBox):
    """A full teaching episode, for any arm: planar or in space, as its plant is drawn.

    Args:
        skill: A ``Skill``, a key of ``mt_widgets.SKILLS`` ("sim-point", "sim-line",
            "uarm-point", "uarm-line", "ur5-reach", ...), or a ``TeachingEpisode`` to show (then
            leave ``query_states`` and ``duration`` unset; its demonstrations so far are shown).
        query_states: (N, state_dim) states to demonstrate at; default
            ``skill.query_states(seed=seed)`` (N = S: the fewest that satisfy the rank condition on given query states).
        seed: Seed for the default query states.
        guidance: Show guidance after each demonstration (how: ``guidance_modality``).
        guidance_modality: what guidance shows: "arrows+words" (the optimal arrow beside the
            user's, and words on how they differ), "arrows" (the arrows only, as in the paper's
            study), "words" (the words only) or "none" (``mt_widgets.core.guidance``). A plant
            drawn in space shows the arrows in its three views and says both in its words.
        lam: The learner's ridge parameter (also used for the optimal actions); default
            ``DEFAULT_LAMBDA``, or the shown ``TeachingEpisode``'s own (any other is refused).
        theme: A ``Theme`` or theme name ("okabe-ito", "paper", "paper-uarm").
        duration: Reproduction length in seconds (default ``skill.default_duration``).
        ghost: Draw the target skill's own motion faintly during the reproduction (planar views).
        demonstrations: Already-given actions (k, R) to restore when resuming (k <= N), e.g. read
            back from a log after a reload; if all N are given the episode finishes at once. A
            shown ``TeachingEpisode``'s own demonstrations must be the first of them.
        episode_index: This episode's index, for the progress bar and every ``Demonstration``.
        episodes_total: Episodes in the phase, for the progress bar.
        on_demonstration: ``callback(record: Demonstration)`` at each confirmation, before the
            episode records it (``DemonstrationRecord`` is the same class; see ``on_demonstration``).
        on_finished: ``callback(result: EpisodeResult)`` when the reproduction is sent (the
            ``mt_widgets.core.EpisodeResult``: the episode, read, never copied).
        title: Heading shown above the episode (default: the skill's title).
        fps: Reproduction frames per second (planar views; the 3-D views play at their own rate).
        width, height, css_width, action_length: As for ``ArmView`` (planar views).
        target_label: the word beside the target on the canvas (None for none), as for ``ArmView``
            (planar views).
        show_description: show the skill's description (its formula) under the title.
        show_outcome: show the teaching error and where the robot ended after the reproduction
            (planar views; the 3-D views show neither). A blinded study sets both to False: the
            paper's participants saw the reproduction only.
        reproduce: learn and play the reproduction when the episode is complete (False: drawing
            only, as a practice round: the phase still becomes "finished", ``result`` stays None).
        panel_size: pixels of each of the 3-D canvas's views (a plant drawn in space).
    """

    phase = Unicode("teaching", help="One of 'teaching', 'guidance', 'finished'.")
    state_index = Int(0, help="Index of the query state shown.")
    demonstrations = List(help="Confirmed actions so far, one list of R floats each.")
    theta_error = Float(None, allow_none=True,
                        help="||Theta_hat - Theta|| once the episode is finished, where the learner has a Theta.")
    policy_risk = Float(None, allow_none=True, help="The learnt policy's risk once the episode is finished.")

    def __init__(self, skill="sim-point", query_states=None, seed: int | None = 0, guidance: bool = True,
                 lam: float | None = None, theme=None, duration: float | None = None, ghost: bool = True,
                 demonstrations=None, episode_index: int = 0, episodes_total: int = 1,
                 on_demonstration: Callable | None = None, on_finished: Callable | None = None,
                 title: str | None = None, fps: float = 60.0, width=None, height=None, css_width=None,
                 action_length=None, target_label: str | None = "goal", show_description: bool = True,
                 show_outcome: bool = True, guidance_modality: str = "arrows+words", reproduce: bool = True,
                 panel_size: int = 260):
        self.guidance_arrows, self.guidance_words = guidance_parts(guidance_modality)
        self.guidance_modality = guidance_modality
        episode = episode_to_show(skill, query_states, seed, lam, duration)
        #: The ``TeachingEpisode`` shown: the science of this episode lives there.
        self.episode = episode
        # Guidance that shows nothing is no guidance: the episode does not stop after each arrow.
        self.guidance = as_bool("guidance", guidance) and (self.guidance_arrows or self.guidance_words)
        self.show_ghost = as_bool("ghost", ghost)
        show_description = as_bool("show_description", show_description)
        self.episode_index = as_count("episode_index", episode_index, minimum=0)
        self.reproduce = as_bool("reproduce", reproduce)
        #: The episode's state machine, the same for every arm (episode_controller.py).
        self.controller = EpisodeController(episode, guidance=self.guidance, episode_index=self.episode_index,
                                            reproduce=self.reproduce)
        if on_demonstration is not None:
            self.on_demonstration(on_demonstration)
        if on_finished is not None:
            self.on_finished(on_finished)
        #: Whether the plant is drawn in space (its ``drawing()`` a ``SpaceDrawing``): the 3-D renderer.
        self.in_space = _drawn_in_space(episode.skill)
        self.progress = EffortProgress(len(self.query_states), max(int(episodes_total), self.episode_index + 1),
                                       episodes_done=self.episode_index)
        heading = title if title is not None else self.skill.title
        # The description states the skill's formula, i.e. the answer: a study hides it.
        description = f"<div style='max-width:760px'>{self.skill.description}</div>" if show_description else ""
        self.header = plain(HTML, f"<h3 style='margin:4px 0'>{heading}</h3>{description}"
                            if heading or description else "")
        #: Where a page puts what comes after the episode (the demo: its result and "Try again"); it
        #: sits beside the canvas, where the person is looking when the reproduction plays.
        self.next_actions = plain(VBox, layout=shared_layout(margin="8px 0 0 0"))
        if self.in_space:
            children = self._space_stage(theme, panel_size)
        else:
            children = self._planar_stage(theme, fps, show_outcome, dict(
                theme=theme, width=width, height=height, css_width=css_width, action_length=action_length,
                target_label=target_label))
        # Enter on the canvas while guidance is shown: what "Next state" does (keyboard users).
        if not self.in_space:
            self.teaching.on_enter_when_locked(lambda: self.next() if self.phase == "guidance" else None)
        self.controller.observe(self._on_event)
        super().__init__(children)
        self.add_class("mt-focus")  # a visible focus on each control (canvas_access.py)
        self._sync()
        if demonstrations is not None and len(demonstrations):
            self.restore(demonstrations)
        elif self.episode.demonstrations:  # an episode resumed in core: show what it holds
            self.controller.resume()
        # A cell run again (or deleted) retires this view once nothing of the user's reaches it (cells.py).
        VIEWS.own(self)

    def _repr_mimebundle_(self, **kwargs):
        VIEWS.shown(self)
        return super()._repr_mimebundle_(**kwargs)

    # -- the two renderers ------------------------------------------------------------------------------
    def _planar_stage(self, theme, fps, show_outcome, view_args) -> list:
        """The planar views: the teaching canvas, the reproduction player, the guidance in words."""
        # The canvas demonstrates into this widget's episode, through its controller.
        self.teaching = TeachingCanvas(self.episode, controller=self.controller, **view_args)
        self.theme = self.teaching.theme
        self.player = ReproductionPlayer(self.skill, fps=fps, show_outcome=show_outcome, **view_args)
        self.guidance_panel = GuidancePanel(self.theme, self.skill.action_units)
        self.next_button = Button(description="Next state", icon="arrow-right", button_style="primary",
                                  layout=Layout(display="none"))
        self.next_button.on_click(lambda _: self.next())
        # The stage: one canvas on the left (the teaching canvas; the reproduction takes its
        # place when the episode finishes), and on the right what to do now: the arrow's
        # controls, the guidance, "Next state" / "Finish and watch", then the page's next actions.
        self.player.layout.display = "none"
        # Each canvas's legend goes to the side column too, under what to do now: it explains every
        # mark, and under the canvas it would push the reproduction's Replay line off the screen.
        player_legend = self.player.view.legend
        # So do the reproduction's words (where the hand ended): under the canvas their second line
        # fell below the window at 1400 x 1000; beside it they sit with the result.
        moved = (player_legend, self.player.status)
        self.player.children = tuple(child for child in self.player.children if child not in moved)
        player_legend.layout.display = "none"
        self._show_status = self.player.status.layout.display != "none"   # hidden for a blinded study
        self.player.status.layout.display = "none"                        # until the reproduction plays
        # The boxes share their layouts (looks.py): no view changes them.
        self.side = plain(VBox, [self.teaching.controls, self.guidance_panel, self.next_button, self.player.status,
                                 self.next_actions, self.teaching.view.legend, player_legend],
                          layout=shared_layout(min_width="300px", max_width="400px", flex="1 1 300px"))
        # Drawing only (a practice round): no reproduction, so no player canvas on the page and no
        # effort to count.
        shown = [self.teaching.view.canvas, self.player] if self.reproduce else [self.teaching.view.canvas]
        canvases = plain(VBox, shown, layout=shared_layout(flex="0 1 auto"))
        self.stage = plain(HBox, [canvases, self.side],
                           layout=shared_layout(flex_flow="row wrap", align_items="flex-start",
                                                grid_gap="4px 16px", width="100%"))
        children = [self.header, self.progress, self.stage] if self.reproduce else [self.header, self.stage]
        if view_args["css_width"] is None:  # the canvases grow with the page (see stage_css)
            for view in (self.teaching.view, self.player.view):
                view.canvas.add_class(_canvas_class(view))
            # The column is as wide as its canvas: long lines under it (the reproduction's
            # status) wrap instead of widening it and pushing the side column under it.
            canvases.add_class(_canvas_class(self.teaching.view))
            children.append(plain(HTML, stage_css(self.teaching.view, self.player.view)))
        return children

    def _space_stage(self, theme, panel_size) -> list:
        """The 3-D views: one canvas of three linked views that also plays the reproduction."""
        #: The renderer (a ``SpaceTeachingCanvas`` here): views, arrows, keyboard, typed numbers, replay.
        self.teaching = SpaceTeachingCanvas(self.episode, controller=self.controller, theme=theme,
                                            panel_size=panel_size)
        self.theme = self.teaching.theme
        self.player = None
        self.guidance_panel = None
        # The canvas's own "Next state" (it sits with its Confirm): the label says where it goes.
        self.next_button = self.teaching.next_button
        self.stage = self.teaching
        return [self.header, self.progress, self.teaching, self.next_actions]

    # -- the episode's facts, as the widget's attributes ------------------------------------------------
    @property
    def records(self) -> list[Demonstration]:
        """The confirmed demonstrations: the episode's own list (``episode.demonstrations``), not a copy."""
        return self.episode.demonstrations

    @property
    def result(self) -> EpisodeResult | None:
        """The finished episode's ``EpisodeResult`` (None before, and for a drawing-only episode)."""
        return self.controller.result

    @property
    def pending_action(self) -> list[float] | None:
        """The arrow drawn and not confirmed (the confirmed one while guidance is shown), or None."""
        pending = self.controller.pending_action
        return None if pending is None else [float(c) for c in pending]

    @property
    def skill(self) -> Skill:
        return self.episode.skill

    @property
    def query_states(self) -> np.ndarray:
        """(N, state_dim) the episode's query states."""
        return self.episode.query_states

    @property
    def features(self) -> np.ndarray:
        """(N, S) Phi."""
        return self.episode.features

    @property
    def optimal(self) -> np.ndarray:
        """(N, R) the optimal actions U_bar."""
        return self.episode.optimal_actions

    @property
    def exact(self) -> bool:
        return self.episode.exact

    @property
    def lam(self) -> float:
        return self.episode.lam

    @property
    def duration(self) -> float:
        """Seconds of the reproduction."""
        return self.episode.duration

    # -- callbacks --------------------------------------------------------------------------------------
    def on_demonstration(self, callback: Callable[[Demonstration], None], remove: bool = False) -> None:
        """Register ``callback(record)``, called for each confirmed demonstration, with this episode's index.

        Callbacks run before the demonstration is recorded and counted and before guidance is
        shown or the next state appears (the study log and the class progress write it there);
        if one raises, the error reaches the caller of ``confirm`` (or ``demonstrate``), later
        callbacks are not called, and the arrow stays pending and unconfirmed so that it can be
        confirmed again. The same order for every arm (``EpisodeController.confirm``).
        """
        self.controller.on_demonstration(callback, remove=remove)

    def on_finished(self, callback: Callable[[EpisodeResult], None], remove: bool = False) -> None:
        """Register ``callback(result)``, called when the episode is learnt and its reproduction sent.

        An error in a callback reaches the caller of ``finish`` (the reproduction is a function
        of the demonstrations, already recorded, so nothing is undone).
        """
        self.controller.on_finished(callback, remove=remove)

    # -- driving it from code ------------------------------------------------------------------------------
    def set_action(self, action, method: str = "code") -> None:
        """Draw ``action`` (R,) as the pending arrow at the current state, as if drawn."""
        self.teaching.set_action(action, method=method)

    def demonstrate(self, action) -> Demonstration:
        """Set and confirm ``action`` (R,) at the current state, as if drawn (method "code")."""
        if self.phase == "guidance":
            raise RuntimeError("demonstrate: expected phase 'teaching', the episode is in 'guidance'; "
                               "call next() after guidance")
        if self.phase != "teaching":
            raise RuntimeError(f"demonstrate: expected phase 'teaching', the episode is {self.phase} (all "
                               f"{len(self.query_states)} demonstrations given); start a new EpisodeWidget to "
                               f"teach again")
        self.teaching.set_action(action)
        return self.teaching.confirm()

    def next(self) -> None:
        """Leave the guidance of the current state: show the next state, or finish the episode."""
        if self.phase != "guidance":
            raise RuntimeError(f"next: expected phase 'guidance', the episode is in {self.phase!r}")
        self.controller.next()

    def restore(self, demonstrations) -> None:
        """Take already-given demonstrations (k, R) when resuming; finishes if all are there.

        Args:
            demonstrations: (k, R) actions, k <= N, R = ``skill.plant.action_dim``. The episode's
                own demonstrations must be the first of these (``TeachingEpisode.extend_to``).
        """
        self.controller.restore(demonstrations)

    def finish(self) -> EpisodeResult | None:
        """Show what the robot learnt: play the episode's reproduction and show the error."""
        return self.controller.finish()

    # -- internals -----------------------------------------------------------------------------------------
    def _sync(self, index: bool = True) -> None:
        """The traits, from the controller (``index``: the state shown too)."""
        controller = self.controller
        if index:
            self.state_index = controller.state_index
        demonstrations = controller.demonstrations
        if demonstrations != self.demonstrations:
            self.demonstrations = demonstrations
        self.progress.demonstrations_done = len(demonstrations)

    def _on_event(self, event: str) -> None:
        """What the controller says (episode_controller.EVENTS), shown; the renderer drew its part first."""
        if event == "recorded":
            # With guidance the controller pauses at this state next, and "guidance" syncs the index:
            # synced here, it would show the next state for a moment and come back.
            self._sync(index=not self.controller.pause)
        elif event == "guidance":
            self._show_guidance()
        elif event == "state":
            if not self.in_space:
                self.guidance_panel.hide()
                self.next_button.layout.display = "none"
            self._sync()
            self.phase = "teaching"
        elif event == "reproduce":
            self._sync()
            self._reproduce()
            self.progress.episodes_done = min(self.episode_index + 1, self.progress.episode_budget)
        elif event == "finished":
            if self.result is not None:
                self.theta_error, self.policy_risk = self.episode.theta_error, self.episode.policy_risk
            self.phase = "finished"

    def _show_guidance(self) -> None:
        index = self.controller.state_index
        last = index + 1 >= len(self.query_states)
        self.next_button.description = "Finish and watch" if last else "Next state"
        if not self.in_space:
            demonstration = self.episode.demonstrations[index]
            if self.guidance_arrows:
                self.teaching.show_guidance(self.optimal[index], legend=self.guidance_words)
            if self.guidance_words:
                # The arrows' legend is under the canvas (legend.py), with every other mark.
                self.guidance_panel.show(demonstration.action, self.optimal[index], exact=self.exact, legend=False)
                self.teaching.describe_guidance(explain_difference(demonstration.action, self.optimal[index],
                                                                   self.skill.action_units))
            self.next_button.layout.display = None
        self._sync()
        self.phase = "guidance"

    def _reproduce(self) -> None:
        """The episode is complete: the reproduction plays where the teaching canvas was (planar; the
        3-D canvas plays it in its own views)."""
        if self.in_space or not self.reproduce:
            return
        episode = self.episode
        ghost = episode.target_reproduction if self.show_ghost else None
        self.player.play(episode.reproduction, theta_error=episode.theta_error, policy_risk=episode.policy_risk,
                         ghost=ghost)
        # The reproduction plays where the teaching canvas was: the person's eyes are there.
        self.teaching.view.canvas.layout.display = "none"
        self.teaching.controls.layout.display = "none"
        self.teaching.view.legend.layout.display = "none"
        self.player.view.legend.layout.display = None
        if self._show_status:
            self.player.status.layout.display = None
        self.guidance_panel.hide()
        self.next_button.layout.display = "none"
        self.player.layout.display = None
