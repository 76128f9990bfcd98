"""One teaching episode's state machine, held once, headless: every view of every arm renders it.

A view (the planar ``TeachingCanvas``, the 3-D ``SpaceTeachingCanvas``) takes input and draws; the
``EpisodeController`` decides. Its phases and moves::

    teaching --confirm--> guidance --next--> teaching (the next state) ... --> finished
    teaching --confirm--> teaching (the next state)          (no guidance: no pause)
    the last confirm (or its guidance's next) ---------------> finished

``confirm`` does, in this one order, for every arm:

1. analyse the pending arrow into a ``Demonstration`` carrying the episode's index
   (``episode_index``: the class progress and the study log read that field);
2. call the ``on_demonstration`` callbacks: the durable writers (the study log, the class
   progress). An error in one reaches the caller of ``confirm`` and nothing below happens: the
   arrow stays pending, nothing is recorded, no guidance is shown, no state follows. So nothing
   the person saw as accepted is missing from disk after a crash: a reload rebuilds the episode
   from the log (``restore``) and shows exactly what was written;
3. record it in the ``TeachingEpisode`` (idempotent: a callback may have recorded it itself);
4. pause for guidance, or show the next state, or finish.

Views follow it through ``observe(listener)``: ``listener(event)`` with one of ``EVENTS``:
``"state"`` (a state awaits a demonstration: at the start, after ``next``, after ``restore``),
``"recorded"`` (a demonstration was recorded), ``"guidance"`` (the pause after one),
``"reproduce"`` (the episode is complete: play what was learnt) and ``"finished"`` (its
``result`` is ready). The same events, in the same order, whatever the arm.

No widget library here: it is tested without a kernel (tests/widgets/test_episode_controller.py).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mt_widgets.core import Demonstration, EpisodeResult, TeachingEpisode
from mt_widgets.core.validation import as_bool, as_count

from .callbacks import Callbacks

#: The episode's phases: drawing an arrow, looking at guidance, done.
PHASES = ("teaching", "guidance", "finished")
#: What a view is told, in the order they can come (see the module's docstring).
EVENTS = ("state", "recorded", "guidance", "reproduce", "finished")


@dataclass
class InputTiming:
    """When the user acted on one query state (``time.monotonic()`` seconds)."""

    shown_at: float
    first_input_at: float | None = None
    last_input_at: float | None = None
    method: str | None = None
    redraws: int = 0


class EpisodeController:
    """The state machine of one teaching episode.

    Args:
        episode: the ``TeachingEpisode`` the demonstrations go to (the one place they live).
        guidance: whether the optimal arrow is shown after each confirmation (recorded with each
            ``Demonstration`` as ``guidance_shown``).
        pause: whether the episode stops after each confirmation until ``next()`` (phase
            "guidance"); default: ``guidance``.
        episode_index: the episode's index, passed with every ``Demonstration``.
        reproduce: whether finishing builds the ``EpisodeResult`` (the reproduction, rolled out
            once) and calls ``on_finished``; False: drawing only (a practice round).
    """

    def __init__(self, episode: TeachingEpisode, *, guidance: bool = False, pause: bool | None = None,
                 episode_index: int = 0, reproduce: bool = True):
        if not isinstance(episode, TeachingEpisode):
            raise TypeError(f"episode: expected a TeachingEpisode, got {type(episode).__name__}")
        self.episode = episode
        self.guidance = as_bool("guidance", guidance)
        self.pause = self.guidance if pause is None else as_bool("pause", pause)
        self.episode_index = as_count("episode_index", episode_index, minimum=0)
        self.reproduce = as_bool("reproduce", reproduce)
        self.phase = "teaching"
        self.result: EpisodeResult | None = None
        self._pending: np.ndarray | None = None
        self.timing = InputTiming(time.monotonic())
        self._demonstration_callbacks = Callbacks()
        self._finished_callbacks = Callbacks()
        self._listeners = Callbacks()

    # -- what is shown ------------------------------------------------------------------------------
    @property
    def n_states(self) -> int:
        return self.episode.n_states

    @property
    def state_index(self) -> int:
        """The query state shown: the one awaiting a demonstration, the one whose guidance is shown,
        or N when finished."""
        given = len(self.episode.demonstrations)
        return given - 1 if self.phase == "guidance" else given

    @property
    def current_state(self) -> np.ndarray | None:
        """The query state shown, or None when every state has its demonstration (and no guidance is shown)."""
        index = self.state_index
        return self.episode.query_states[index] if index < self.n_states else None

    @property
    def accepting(self) -> bool:
        """Whether an arrow may be drawn and confirmed now."""
        return self.phase == "teaching" and self.current_state is not None

    @property
    def demonstrations(self) -> list[list[float]]:
        """The confirmed actions so far, a list of floats each (the episode's)."""
        return [[float(a) for a in action] for action in self.episode.actions]

    @property
    def pending_action(self) -> np.ndarray | None:
        """The arrow drawn and not confirmed, (R,) floats (a copy), or None; during guidance the confirmed one."""
        return None if self._pending is None else self._pending.copy()

    # -- callbacks ----------------------------------------------------------------------------------
    def on_demonstration(self, callback: Callable[[Demonstration], None], remove: bool = False) -> None:
        """Register ``callback(demonstration)``, called at each confirmation BEFORE it is recorded.

        An error in a callback reaches the caller of ``confirm``; later callbacks are not called
        and the arrow stays pending and unrecorded (confirm it again once the cause is fixed).
        """
        self._demonstration_callbacks.register_callback(callback, remove=remove)

    def on_finished(self, callback: Callable[[EpisodeResult], None], remove: bool = False) -> None:
        """Register ``callback(result)``, called once the reproduction was handed to the views.

        An error reaches the caller of ``finish`` (``next`` or ``confirm``); nothing is undone: the
        reproduction is a function of the demonstrations, all recorded.
        """
        self._finished_callbacks.register_callback(callback, remove=remove)

    def observe(self, listener: Callable[[str], None], remove: bool = False) -> None:
        """Register a view's ``listener(event)`` (one of ``EVENTS``); listeners run in order of registration."""
        self._listeners.register_callback(listener, remove=remove)

    def _emit(self, event: str) -> None:
        self._listeners(event)

    # -- input --------------------------------------------------------------------------------------
    def note_input(self, method: str) -> None:
        """An input on the current state (a press, a key, typed numbers): for the demonstration's timings."""
        if not isinstance(method, str):
            raise TypeError(f"method: expected text (how the action was given), got {type(method).__name__}")
        now = time.monotonic()
        if self.timing.first_input_at is None and method != "code":
            self.timing.first_input_at = now
        self.timing.last_input_at = now
        self.timing.method = method
        self.timing.redraws += 1

    def hold(self, action, method: str | None = None) -> np.ndarray:
        """Take ``action`` (R finite numbers) as the pending arrow; returns it as floats.

        ``method``: how it was given ("pointer", "keyboard", "numeric", "code", ...) when this is
        a new input; None while a drag already noted goes on.
        """
        try:
            u = np.array(action, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            u = None
        if u is None or u.shape != (self.episode.action_dim,) or not np.all(np.isfinite(u)):
            raise ValueError(f"action: expected {self.episode.action_dim} finite numbers in "
                             f"{self.episode.skill.action_units}, got {action!r}"[:300])
        if not self.accepting:
            raise RuntimeError(f"set_action: no query state awaits a demonstration (the episode is in "
                               f"{self.phase!r})")
        if method is not None:
            self.note_input(method)
        self._pending = u
        return u.copy()

    def clear(self) -> None:
        """Forget the pending arrow (not during guidance: the confirmed arrow stays shown)."""
        if self.phase == "teaching":
            self._pending = None

    # -- the moves ----------------------------------------------------------------------------------
    def confirm(self) -> Demonstration:
        """The pending arrow becomes the demonstration at the current state (the module's order)."""
        if self.phase != "teaching" or self.current_state is None:
            raise RuntimeError("confirm: input is locked (guidance is shown or the episode is over)")
        if self._pending is None:
            raise RuntimeError("confirm: draw an arrow first (pending_action is None)")
        now = time.monotonic()
        timing = self.timing
        demonstration = self.episode.analyse(
            self._pending, method=timing.method or "code",
            time_to_first_input_s=None if timing.first_input_at is None else timing.first_input_at - timing.shown_at,
            drawing_duration_s=None if timing.first_input_at is None else now - timing.first_input_at,
            redraws=timing.redraws, confirmed_at=time.time(), guidance_shown=self.guidance,
            episode_index=self.episode_index)
        self._demonstration_callbacks(demonstration)  # the durable writers first: an error stops here
        self.episode.record(demonstration)
        self._emit("recorded")
        if self.pause:
            self.phase = "guidance"
            self._emit("guidance")
        else:
            self._go_on()
        return demonstration

    def next(self) -> None:
        """Leave the guidance: the next state, or the end of the episode."""
        if self.phase != "guidance":
            raise RuntimeError(f"next: expected phase 'guidance', the episode is in {self.phase!r}")
        self._go_on()

    def _go_on(self) -> None:
        if self.episode.complete:
            self.finish()
        else:
            self._show_state()

    def _show_state(self) -> None:
        self.phase = "teaching"
        self._pending = None
        self.timing = InputTiming(time.monotonic())
        self._emit("state")

    def resume(self) -> None:
        """Show the episode as it stands: its demonstrations given, the next state awaiting one;
        finishes at once when every demonstration is there."""
        if self.episode.complete:
            self.finish()
        else:
            self._show_state()

    def restore(self, actions, name: str = "demonstrations") -> None:
        """Take already-given demonstrations (k, R) as confirmed, without callbacks (after a reload:
        they are on disk already), then ``resume``.

        The episode's own demonstrations must be the first of them (``TeachingEpisode.extend_to``);
        ``name`` is the argument named in errors.
        """
        self.episode.extend_to(actions, name=name)
        self.resume()

    def finish(self) -> EpisodeResult | None:
        """The episode is complete: the views play the reproduction, then ``result`` and ``on_finished``."""
        episode = self.episode
        if not episode.complete:
            raise RuntimeError(f"finish: expected {episode.n_states} demonstrations, got {len(episode.demonstrations)}")
        started = time.perf_counter()
        self.phase = "finished"
        self._pending = None
        self._emit("reproduce")
        if self.reproduce:
            self.result = EpisodeResult(episode, feedback_latency_s=time.perf_counter() - started)
        self._emit("finished")
        if self.result is not None:
            self._finished_callbacks(self.result)
        return self.result
