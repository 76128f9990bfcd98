"""The teaching canvas: query states one after another, an arrow drawn for each.

Input, three ways to the same pending action:

- pointer: press on the end-effector (or on the tip of the arrow being drawn) and drag;
  a rubber band follows the pointer and the readout gives the arrow in the action's units;
- touch: a finger pressed on the hand (or the tip) and dragged, as with the mouse; a finger
  landing elsewhere, and two fingers, scroll or zoom the page (``canvas_access.py`` says how);
- keyboard on the canvas (Tab to it, or click it): arrow keys nudge the arrow (Shift: finer),
  Enter confirms (and, while guidance is shown, goes on: ``on_enter_when_locked``), Escape or
  Backspace clears; Tab and Shift+Tab leave it;
- numbers: components (u1, u2) or angle (degrees, counter-clockwise from +x) and magnitude.

An arrow can be redrawn any number of times; ``Confirm`` records it as the demonstration
for the current state, a ``mt_widgets.core.Demonstration`` (the action, how it was given and
when) kept by the canvas's ``TeachingEpisode`` (``canvas.episode``): the one place it lives.
The canvas is the planar view of an ``EpisodeController`` (``canvas.controller``,
episode_controller.py), which holds the episode's state machine for every arm: the canvas takes
input, hands it to the controller and draws what the controller says. Everything observable is
a trait, following the controller: ``state_index``, ``demonstrations`` (the episode's actions,
in order) and ``pending_action``. A screen reader reads
the canvas as its ``description`` says: the state, the velocity, the arrow and the guidance.
"""

from __future__ import annotations

import html
import math
import re
import time
from collections.abc import Callable

import numpy as np
from ipywidgets import HTML, Button, FloatText, HBox, Layout, ToggleButtons, ToggleButtonsStyle, VBox
from traitlets import Any, Bool, Int, List

from mt_widgets.core import Demonstration, TeachingEpisode
from mt_widgets.core.validation import as_bool, as_count

from .arm_view import ArmView
from .arrows import draw_arrow_pair
from .callbacks import Callbacks
from .canvas_access import CanvasDescription
from .episode_controller import EpisodeController
from .looks import plain, shared_layout, shared_style
from .pointer_drag import ARROW_KEY_SIGNS, PointerDrag, confirm_or_clear
from .redraw import drawing_batch

#: How often the text readout follows a drag, at most (seconds): the canvas follows every
#: move, the readout is a second message per update and need not.
READOUT_INTERVAL_S = 0.08
#: A finger's grab radius, in grab radii: the kernel accepts a touch this far from the hand (in
#: canvas pixels); the page's script lets through only touches within the finger's own zone
#: (canvas_access.FINGER_RADIUS_CSS_PX, at most this), so a canvas shown small still gets a
#: finger-sized target.
TOUCH_RADIUS_FACTOR = 2.0


def describe_action(action, units: str) -> str:
    """The arrow in words: components, magnitude and direction (degrees from +x, anticlockwise)."""
    u = np.asarray(action, dtype=float)
    angle = math.degrees(math.atan2(u[1], u[0]))
    return (f"({u[0]:+.2f}, {u[1]:+.2f}) {units}, |u| = {np.hypot(*u):.2f} {units}, "
            f"direction {angle:+.0f}&deg;")


def arrow_in_words(action, units: str) -> str:
    """The arrow for a screen reader: "1.82 N left and 1.52 N up, size 2.37 N at 140 degrees".

    Worded unlike the readout's "(-1.82, +1.52) N", so a search of the page for the readout
    finds the readout alone.
    """
    u = np.asarray(action, dtype=float)
    angle = math.degrees(math.atan2(u[1], u[0]))
    return (f"{abs(u[0]):.2f} {units} {'right' if u[0] >= 0 else 'left'} and {abs(u[1]):.2f} {units} "
            f"{'up' if u[1] >= 0 else 'down'}, size {np.hypot(*u):.2f} {units} at {angle:.0f} degrees")


class TeachingCanvas(VBox):
    """Draw one action arrow at each query state.

    Args:
        skill: The skill being taught (its robot, units and target are drawn), or the
            ``TeachingEpisode`` to demonstrate into (then ``query_states`` is None).
        query_states: (N, state_dim) the states to demonstrate at, shown in order (a new
            ``TeachingEpisode`` of them holds the demonstrations); None (the default) draws the
            skill's S well-conditioned query states with seed 0, as ``EpisodeWidget`` does.
        theme: A ``Theme`` or theme name.
        grab_radius: Pixels around the end-effector (and the arrow tip) where a press starts
            a drag (a finger gets at least a 48 CSS px target, up to ``TOUCH_RADIUS_FACTOR``
            times this).
        auto_advance: Move to the next state as soon as an arrow is confirmed (standalone
            use); the episode widget turns this off to show guidance first.
        guidance: whether the optimal arrow is shown after each confirmation (recorded with each
            ``Demonstration`` as ``guidance_shown``; the episode widget shows it).
        episode_index: the episode's index, recorded with each ``Demonstration``.
        width, height, css_width, action_length: As for ``ArmView``.
        controller: the ``EpisodeController`` to render (an episode widget's); then ``skill`` is
            its episode and ``query_states``, ``auto_advance``, ``guidance``, ``episode_index``
            are the controller's (leave them at their defaults). None: the canvas makes its own.
    """

    state_index = Int(0, help="Index of the query state shown (== number confirmed; N when done).")
    demonstrations = List(help="Confirmed actions, one [u1, u2] list per state so far (the episode's).")
    pending_action = Any(None, allow_none=True, help="The arrow drawn but not confirmed: [u1, u2] or None.")
    locked = Bool(False, help="True while input is disabled (guidance shown, episode over).")

    def __init__(self, skill, query_states=None, theme=None, grab_radius: float = 28.0, auto_advance: bool = True,
                 width=None, height=None, css_width=None, action_length=None, target_label: str | None = "goal",
                 guidance: bool = False, episode_index: int = 0, controller: EpisodeController | None = None):
        if controller is not None:
            if not isinstance(controller, EpisodeController):
                raise TypeError(f"controller: expected an EpisodeController, got {type(controller).__name__}")
            if skill is not controller.episode or query_states is not None:
                raise ValueError("skill, query_states: expected the controller's episode and None with a controller")
        if isinstance(skill, TeachingEpisode):
            if query_states is not None:
                raise ValueError("query_states: expected None when a TeachingEpisode is given (it has its own), "
                                 "got states")
            episode = skill
        elif query_states is None:
            episode = TeachingEpisode(skill, seed=0)
        else:
            states = np.array(query_states, dtype=float)
            if states.ndim != 2 or states.shape[1] != skill.state_dim or len(states) == 0:
                raise ValueError(f"query_states: expected shape (N, {skill.state_dim}) with N >= 1, "
                                 f"got {states.shape}")
            episode = TeachingEpisode(skill, states)
        #: The ``TeachingEpisode`` the confirmed demonstrations go to (the one place they live).
        self.episode = episode
        skill, states = episode.skill, episode.query_states
        self.auto_advance = as_bool("auto_advance", auto_advance)
        made_here = controller is None
        if made_here:
            controller = EpisodeController(episode, guidance=as_bool("guidance", guidance),
                                           pause=not self.auto_advance,
                                           episode_index=as_count("episode_index", episode_index, minimum=0),
                                           reproduce=False)
        #: The episode's state machine (episode_controller.py); this canvas draws it.
        self.controller = controller
        self.guidance = controller.guidance
        self.episode_index = controller.episode_index
        self.skill = skill
        #: R, the number of action components.
        self.action_dim = int(skill.plant.action_dim)
        self.query_states = states
        self.grab_radius = float(grab_radius)
        self.view = ArmView(skill, width=width, height=height, theme=theme, action_length=action_length,
                            css_width=css_width, target_label=target_label)
        self.theme = self.view.theme
        self._pointer = PointerDrag(self._press, self._drag_to, lambda pointer: self._drag_to(pointer, final=True),
                                    self._accepting)
        self._last_readout = 0.0
        self._guidance = None
        self._guidance_words = ""
        self._enter_when_locked = Callbacks()

        units = skill.action_units
        # Parts built with the shared layouts and styles (looks.py): 28 models fewer a canvas.
        self.readout = plain(HTML, value="")
        self.hint = plain(HTML, value="")
        self.scale_label = plain(HTML, value=f"<small>Scale: {self.view.scale_text}</small>")
        self.entry_mode = plain(ToggleButtons, options=[("u1, u2", "components"), ("angle, size", "polar")],
                                        value="components", style=shared_style(ToggleButtonsStyle, button_width="90px"),
                                        tooltips=["Components of the action",
                                                  "Angle in degrees from +x (anticlockwise) and magnitude"])
        self.first_entry = plain(FloatText, description=f"u1 ({units})", step=0.1, layout=shared_layout(width="170px"))
        self.second_entry = plain(FloatText, description=f"u2 ({units})", step=0.1,
                                  layout=shared_layout(width="170px"))
        self.set_button = plain(Button, description="Set arrow", tooltip="Draw the arrow from the numbers")
        self.confirm_button = plain(Button, description="Confirm", button_style="success", icon="check", disabled=True,
                                     tooltip="Record this arrow as your demonstration (Enter on the canvas)")
        self.clear_button = plain(Button, description="Clear", icon="eraser", disabled=True,
                                   tooltip="Remove the arrow and draw again (Escape on the canvas)")
        self.entry_mode.observe(self._on_entry_mode, names="value")
        self.set_button.on_click(lambda _: self._set_from_entries())
        self.confirm_button.on_click(lambda _: self.confirm())
        self.clear_button.on_click(lambda _: self.clear_action())

        canvas = self.view.canvas
        self._pointer.connect(canvas, lambda: self.grab_radius, lambda: TOUCH_RADIUS_FACTOR * self.grab_radius,
                              self._on_key_down)
        #: The canvas's text alternative and grab zones (a hidden widget; canvas_access.py).
        self.description = CanvasDescription(canvas)

        self.view.legend.add("user_arrow")
        # The legend beside the canvas under the controls, where the eyes go from a mark to its
        # meaning; under the canvas it would push what follows below the fold. (An episode places
        # ``controls`` and ``view.legend`` in its own side column.)
        self.view.legend.layout.max_width = "100%"
        self.controls = controls = VBox([
            self.readout,
            plain(HBox, [self.confirm_button, self.clear_button]),
            plain(HTML, "<small>Or type the arrow:</small>"),
            self.entry_mode,
            plain(HBox, [self.first_entry, self.second_entry]),
            self.set_button,
            self.hint,
            self.scale_label,
            plain(HTML, "<small>Keyboard: Tab to the canvas (or click it), then arrow keys move the arrow tip "
                 "(Shift: finer), Enter confirms, Escape clears, Tab moves on.</small>"),
            self.description,
        ], layout=Layout(min_width="300px", max_width="380px"))   # its own: an episode hides it
        super().__init__([plain(HBox, [canvas, plain(VBox, [controls, self.view.legend],
                                                     layout=shared_layout(max_width="400px"))],
                                layout=shared_layout(flex_flow="row wrap", align_items="flex-start"))])
        self.add_class("mt-focus")  # a visible focus on each control (canvas_access.py)
        controller.observe(self._on_event)
        if made_here:
            controller.resume()   # the episode as it stands (a resumed one: its demonstrations given)
        else:
            self._show_given()

    # -- public API ---------------------------------------------------------------------------------
    @property
    def n_states(self) -> int:
        return len(self.query_states)

    @property
    def current_state(self) -> np.ndarray | None:
        """The query state being demonstrated, or None when all are done."""
        return self.query_states[self.state_index] if self.state_index < self.n_states else None

    def on_confirm(self, callback: Callable[[Demonstration], None], remove: bool = False) -> None:
        """Register ``callback(demonstration: Demonstration)``, called when an arrow is confirmed.

        The controller's ``on_demonstration`` (episode_controller.py): callbacks run before the
        demonstration is recorded in the episode (and ``demonstrations``), and an exception in
        one reaches the caller of ``confirm``: the arrow is then not recorded and stays pending,
        to be confirmed again (a demonstration the study log could not write is not counted).
        """
        self.controller.on_demonstration(callback, remove=remove)

    def on_enter_when_locked(self, callback: Callable[[], None], remove: bool = False) -> None:
        """Register ``callback()``, called when Enter is pressed on the canvas while input is locked
        (the episode goes on to the next state with it, as its "Next state" button does)."""
        self._enter_when_locked.register_callback(callback, remove=remove)

    def describe_guidance(self, words: str) -> None:
        """The guidance shown in words (HTML allowed), for the canvas's text alternative until the
        next state."""
        self._guidance_words = words
        self._describe()

    def set_action(self, action, method: str = "code") -> None:
        """Draw ``action`` (R,) in ``action_units`` as the pending arrow at the current state."""
        if self.current_state is None:
            raise RuntimeError("set_action: every query state already has a demonstration")
        self._hold(action, method)
        self._draw_arrows()
        self._update_readout()
        self._sync_entries()

    def _hold(self, action, method: str | None) -> None:
        """The pending arrow, given to the controller (which checks it) and shown in the trait."""
        u = self.controller.hold(action, method)
        self.pending_action = [float(c) for c in u]

    def clear_action(self) -> None:
        """Remove the pending (unconfirmed) arrow."""
        self._pointer.cancel()  # Escape mid-drag: the pointer still moving must not redraw it
        self.controller.clear()
        self.pending_action = None
        self._draw_arrows()
        self._update_readout()
        self._sync_entries()

    def confirm(self) -> Demonstration:
        """Record the pending arrow as the demonstration at the current state; returns its ``Demonstration``."""
        if self.locked:
            raise RuntimeError("confirm: input is locked (guidance is shown or the episode is over)")
        # Enter mid-drag: the drag ends with the confirmation, so later moves of the still
        # pressed pointer cannot change the confirmed arrow or draw one at the next state.
        self._pointer.cancel()
        return self.controller.confirm()

    def _show_demonstrations(self) -> None:
        """The ``demonstrations`` trait, from the episode: the one place it is written."""
        actions = self.controller.demonstrations
        if actions != self.demonstrations:
            self.demonstrations = actions

    def show_guidance(self, optimal_action, legend: bool = True) -> None:
        """Draw the optimal arrow (R,) beside the confirmed one at the current state.

        ``legend``: name it in the canvas legend too (a replication of the paper shows the
        arrows and no words).
        """
        self._guidance = np.array(optimal_action, dtype=float)
        if as_bool("legend", legend):
            self.view.legend.add("optimal_arrow")
        self._draw_arrows()
        self._describe()

    def advance(self) -> None:
        """Move on to the next query state (after a confirmation, while the episode pauses)."""
        if self.controller.phase != "guidance":
            raise RuntimeError("advance: confirm the current arrow first")
        self.controller.next()

    def restore(self, actions) -> None:
        """Take already-given demonstrations (k, R) as confirmed, without callbacks (resuming).

        The episode's own demonstrations must be the first of them (``TeachingEpisode.extend_to``).
        """
        self.controller.restore(actions, name="actions")

    def _on_event(self, event: str) -> None:
        """What the controller says (episode_controller.EVENTS), drawn."""
        if event == "recorded":
            self._show_demonstrations()
        elif event == "guidance":
            self._set_locked(True)
        elif event == "state":
            self._show_given()
        elif event == "reproduce":
            if self.controller.reproduce:
                # An episode widget plays the reproduction where this canvas was: no need to draw here.
                self.state_index = self.controller.state_index
                self._set_locked(True)
            else:
                self._show_given()   # drawing only: the canvas says every demonstration is given

    def _show_given(self) -> None:
        """Show the episode as the controller holds it: its demonstrations confirmed, the state shown."""
        self._pointer.cancel()
        self._show_demonstrations()
        controller = self.controller
        self.state_index = controller.state_index
        pending = controller.pending_action
        self.pending_action = None if pending is None else [float(c) for c in pending]
        self._guidance = None
        self._guidance_words = ""
        self._set_locked(controller.phase != "teaching", update=False)
        self._show_current_state()

    # -- drawing --------------------------------------------------------------------------------------
    def _show_current_state(self) -> None:
        state = self.current_state
        # Confirm closes before the new state is drawn: a page that shows the new state never
        # offers the previous arrow's Confirm (a quick press would have confirmed nothing).
        self.confirm_button.disabled = True
        with drawing_batch():
            if state is None:
                self.view.show(None, "robot")
            else:
                self.view.show_state(state)
            self._draw_arrows()
        self._sync_entries()  # before the readout names the new state: typed numbers never lag behind it
        self._update_readout()

    def _draw_arrows(self, rubber_band: bool = False) -> None:
        state = self.current_state
        if state is None:
            self.view.show(None, "arrows")
            return
        view, theme = self.view, self.theme
        origin, _ = view.painter.end_effector(state)
        start = view.transform.to_pixel(origin)
        user = None if self.pending_action is None else view.transform.action_tip(origin, self.pending_action)
        optimal = None if self._guidance is None else view.transform.action_tip(origin, self._guidance)
        style = theme.rubber_band if rubber_band else theme.user_arrow

        def paint(canvas):
            # Both stay visible when aligned, whichever is shorter (see draw_arrow_pair).
            draw_arrow_pair(canvas, start, user, optimal, style, theme.optimal_arrow)

        view.show(paint, "arrows")

    def _update_readout(self) -> None:
        units = self.skill.action_units
        n = self.state_index
        if self.current_state is None:
            self.readout.value = f"<b>All {self.n_states} demonstrations given.</b>"
        elif self.pending_action is None:
            # "the robot's hand (the yellow dot)": novices and visitors do not know "end-effector";
            # the colour is the one the theme draws the marker in.
            marker = self.theme.marker_words(self.view.drawing)
            self.readout.value = (f"<b>State {n + 1} of {self.n_states}</b>: press on the robot's hand ({marker}) "
                                  f"and drag to draw the action.")
        else:
            self.readout.value = (f"<b>State {n + 1} of {self.n_states}</b>: your arrow "
                                  f"{describe_action(self.pending_action, units)}")
        can_confirm = self.pending_action is not None and not self.locked and self.current_state is not None
        self.confirm_button.disabled = not can_confirm
        self.clear_button.disabled = not can_confirm
        if not self._pointer.active:  # mid-drag the words would change 12 times a second: said on release
            self._describe()

    def _describe(self) -> None:
        """The canvas in words (its text alternative) and where a press starts a drag."""
        units = self.skill.action_units
        state = self.current_state
        if state is None:
            self.description.update(f"Teaching canvas: all {self.n_states} demonstrations given.")
            return
        view = self.view
        position, velocity = view.painter.end_effector(state)
        length = view.drawing.units
        words = [f"Teaching canvas, state {self.state_index + 1} of {self.n_states}: the robot's hand is at "
                 f"({position[0]:.2f}, {position[1]:.2f}) {length}, moving at ({velocity[0]:+.2f}, "
                 f"{velocity[1]:+.2f}) {length}/s."]
        if self.pending_action is None:
            words.append("No arrow yet: arrow keys draw one.")
        else:
            words.append(f"Your arrow: {arrow_in_words(self.pending_action, units)}.")
            if not self.locked:
                words.append("Enter confirms it.")
        if self._guidance is not None:
            words.append(f"The best arrow: {arrow_in_words(self._guidance, units)}.")
        if self._guidance_words:
            words.append(re.sub(r"<[^>]+>", " ", self._guidance_words))
        if self.locked and len(self._enter_when_locked):
            words.append("Enter goes on.")
        text = " ".join(" ".join(html.unescape(word).split()) for word in words)
        zones = ()
        if self._accepting():
            origin, _ = view.painter.end_effector(state)
            touch = TOUCH_RADIUS_FACTOR * self.grab_radius
            starts = [view.transform.to_pixel(origin)]
            if self.pending_action is not None:
                starts.append(view.transform.action_tip(origin, self.pending_action))
            zones = tuple((float(x), float(y), self.grab_radius, touch) for x, y in starts)
        self.description.update(text, zones)

    def _sync_entries(self) -> None:
        u = self.pending_action
        if u is None:
            # No arrow (a new state, or the arrow cleared): empty fields, so "Set arrow" never
            # re-applies the previous state's numbers.
            self.first_entry.value = self.second_entry.value = 0.0
            return
        if self.entry_mode.value == "components":
            self.first_entry.value, self.second_entry.value = round(u[0], 4), round(u[1], 4)
        else:
            self.first_entry.value = round(math.degrees(math.atan2(u[1], u[0])), 2)
            self.second_entry.value = round(float(np.hypot(*u)), 4)

    # -- input ----------------------------------------------------------------------------------------
    def _accepting(self) -> bool:
        return not self.locked and self.current_state is not None

    def _on_mouse_down(self, x, y) -> None:
        self._pointer.mouse_down(x, y, self.grab_radius)

    def _press(self, x, y, radius: float) -> bool:
        """A mouse button or a finger down at canvas pixel (x, y): True when it starts a drag (on a grab zone)."""
        if not self._accepting():
            return False
        state = self.current_state
        view = self.view
        pointer = np.array([x, y], dtype=float)
        origin, _ = view.painter.end_effector(state)
        near_origin = np.hypot(*(pointer - view.transform.to_pixel(origin))) <= radius
        near_tip = (self.pending_action is not None and np.hypot(
            *(pointer - view.transform.action_tip(origin, self.pending_action))) <= radius)
        if not (near_origin or near_tip):
            self.hint.value = (f"<small>Press on the robot's hand ({self.theme.marker_words(self.view.drawing)}) "
                               f"to start an arrow.</small>")
            return False
        self.hint.value = ""
        self._pointer.active = True   # from here on a drag: the readout's words wait for the release
        self.controller.note_input("pointer")
        if near_tip and not near_origin:
            return True  # keep the arrow; the drag moves its tip
        self._drag_to(pointer)
        return True

    def _drag_to(self, pointer, final: bool = False) -> None:
        origin, _ = self.view.painter.end_effector(self.current_state)
        action = self.view.transform.action_from_drag(origin, pointer)
        self._hold(action, None)
        self._draw_arrows(rubber_band=not final)
        now = time.monotonic()
        if final or now - self._last_readout >= READOUT_INTERVAL_S:
            self._last_readout = now
            self._update_readout()
        if final:
            self._sync_entries()

    def _on_key_down(self, key, shift_key, ctrl_key, meta_key) -> None:
        if key == "Enter" and self.locked and self.current_state is not None:
            self._enter_when_locked()  # e.g. the episode's "Next state" while guidance is shown
            return
        if not self._accepting():
            return
        if key in ARROW_KEY_SIGNS:
            step = ARROW_KEY_SIGNS[key] * self.view.transform.nice_action_step() / (50.0 if shift_key else 10.0)
            action = np.zeros(2) if self.pending_action is None else np.array(self.pending_action, dtype=float)
            action[1 if key in ("ArrowUp", "ArrowDown") else 0] += step
            self.set_action(action, method="keyboard")
        else:
            confirm_or_clear(key, self.pending_action is not None, self.confirm, self.clear_action)

    def _on_entry_mode(self, change) -> None:
        units = self.skill.action_units
        if change["new"] == "components":
            self.first_entry.description, self.second_entry.description = f"u1 ({units})", f"u2 ({units})"
        else:
            self.first_entry.description, self.second_entry.description = "angle (deg)", f"size ({units})"
        self._sync_entries()

    def _set_from_entries(self) -> None:
        if not self._accepting():
            return
        a, b = float(self.first_entry.value), float(self.second_entry.value)
        if self.entry_mode.value == "components":
            action = (a, b)
        else:
            if b < 0:
                self.hint.value = "<small>The size must be zero or more.</small>"
                return
            action = (b * math.cos(math.radians(a)), b * math.sin(math.radians(a)))
        self.hint.value = ""
        self.set_action(action, method="numeric")

    def _set_locked(self, locked: bool, update: bool = True) -> None:
        if locked:
            self._pointer.cancel()
        self.locked = locked
        for widget in (self.set_button, self.first_entry, self.second_entry, self.entry_mode):
            widget.disabled = locked
        if update:
            self._update_readout()
