"""The physical experiment: teaching episodes and the study runner on the uArm Swift Pro.

``UArmTeaching`` wires an ``EpisodeWidget`` to the arm through :class:`UArmBridge`:

- each query state is shown on the arm (the arm moves there) and on the true-scale
  screen view (:mod:`.uarm_screen`) as the black dot, the target as the red dot or line;
- each confirmed demonstration sounds the effort cue (:mod:`.uarm_audio`) in the browser
  and on the arm's buzzer;
- the learnt skill's reproduction is executed on the arm step by step;
- the **Stop** button halts the arm at once (stop command, no further moves) until
  **Resume arm**; a connector error shows a message, never a traceback: the demonstrations
  are logged by the study runner before the arm is asked to do anything;
- an arm outside the safety envelope (after power-up) is brought in once, slowly, as the
  first job (``UArmBridge.home_if_outside``); Stop cuts it like any move;
- with ``demonstration_modality="hand"``, **Teach by hand** (or the H key on the canvas)
  releases the arm at the query state and the person moves its tip: the measured
  displacement, limited to the step limit, is the pending arrow on the screen until it is
  confirmed; the arm then holds itself again and goes back to the query state before it
  moves on (:mod:`mt_widgets.hardware.kinesthetic`). With the simulated arm a
  :class:`~.uarm_hand.SimulatedHand` stands in for the hand.

Arm work runs on one worker thread, in order, so the kernel stays free for the Stop button.

``UArmStudyApp`` is the participant app of ``mt_widgets.apps.study_app`` with every episode
(practice included) wired this way; ``UArmEpisodePage`` is one episode on the arm, for
tutorials and tests.
"""

from __future__ import annotations

import logging
import threading
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
from ipywidgets import HTML, VBox

from mt_widgets.core import UArmPlant
from mt_widgets.core.validation import as_bool
from mt_widgets.hardware import SwiftPro, SwiftProError, SwiftProStopped, UnsafeMoveError
from mt_widgets.hardware.bridge import UArmBridge, connect_arm, describe_error, is_simulated, simulated_device
from mt_widgets.hardware.kinesthetic import HandMove
from mt_widgets.widgets import EpisodeWidget

from .arm_panel import ArmPanel
from .study_app import StudyApp
from .uarm_audio import AudioCues
from .uarm_hand import SimulatedHand
from .uarm_screen import ScreenGeometry, fit_episode

log = logging.getLogger(__name__)

#: How a demonstration is given: drawn on the screen, or shown by moving the arm by hand.
DEMONSTRATION_MODALITIES = ("drawn", "hand")
HAND_KEYS = ("h", "H")


class UArmTeaching:
    """Connects teaching episodes to the arm, the screen and the audio cues.

    Args:
        arm: a connected ``SwiftPro`` (see :func:`connect_arm`).
        geometry: the screen under the arm (default: the paper's 518 x 325 mm display).
        show_player: also animate the reproduction on screen (default: only with the
            simulated arm; a real arm plays it itself).
        audio: play the effort cues in the browser (the buzzer sounds regardless).
        buzzer: sound the cues on the arm's buzzer.
        demonstration_modality: "drawn" (arrows on the screen) or "hand" (also by moving the
            arm by hand; logged per demonstration as the input method "hand").
    """

    def __init__(self, arm: SwiftPro, geometry: ScreenGeometry | None = None, show_player: bool | None = None,
                 audio: bool = True, buzzer: bool = True, demonstration_modality: str = "drawn"):
        audio, buzzer = as_bool("audio", audio), as_bool("buzzer", buzzer)
        if not isinstance(demonstration_modality, str):
            raise TypeError(f"demonstration_modality: expected one of {DEMONSTRATION_MODALITIES} (text), got "
                            f"{type(demonstration_modality).__name__}")
        if demonstration_modality not in DEMONSTRATION_MODALITIES:
            raise ValueError(f"demonstration_modality: expected one of {DEMONSTRATION_MODALITIES}, got "
                             f"{demonstration_modality!r}")
        self.bridge = UArmBridge(arm)
        self.geometry = geometry if geometry is not None else ScreenGeometry()
        if not isinstance(self.geometry, ScreenGeometry):
            raise ValueError(f"geometry: expected a ScreenGeometry, got {type(geometry).__name__}")
        self.simulated = is_simulated(arm)
        self.show_player = self.simulated if show_player is None else as_bool("show_player", show_player)
        where = f"{arm.port_used} (simulated arm)" if self.simulated else f"Swift Pro on {arm.port_used}"
        self.panel = ArmPanel(f"{where}, firmware {'.'.join(map(str, arm.firmware_version or ()))}")
        self.panel.stop_button.on_click(lambda _: self.stop())
        self.panel.resume_button.on_click(lambda _: self.resume())
        self.panel.hand_button.on_click(lambda _: self.teach_by_hand())
        device = simulated_device(arm)
        #: The stand-in for a hand on the simulated arm (None on a real arm).
        self.hand_view = SimulatedHand(device, floating=bool(self.geometry.pinned)) if device is not None else None
        self._hand_stop = threading.Event()
        # stop() (kernel thread) and a hand move (worker) both say what a stop means; the
        # worker's words, which know the arm is released, must come after stop()'s.
        self._stop_words = threading.Lock()
        self._stop_error: str | None = None
        self._reattach_on_resume = False
        self._hand_job: Future | None = None
        self.demonstration_modality = "drawn"
        self.set_demonstration_modality(demonstration_modality)
        self.cues = AudioCues(arm_beep=self._beep if buzzer else None, enabled=audio)
        self.css = self.geometry.css()
        self.episode: EpisodeWidget | None = None
        self.last_report = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="uarm")
        self._update_position()
        self._submit(self._home_if_outside)

    def _home_if_outside(self) -> None:
        if not self.bridge.envelope.contains(*self.bridge.position_mm()):
            self.panel.say("The arm is slowly moving into its workspace...")
            self.bridge.home_if_outside()
            self._update_position()
            self.panel.say("")

    # ------------------------------------------------------------------ episodes
    def attach(self, episode: EpisodeWidget) -> EpisodeWidget:
        """Wire an episode: true-scale view, query states on the arm, cues, reproduction on the arm."""
        if not isinstance(episode.skill.plant, UArmPlant):
            raise ValueError(f"episode: expected an episode of a skill on the uArm's plant (UArmPlant), got skill "
                             f"{episode.skill.key!r} on {type(episode.skill.plant).__name__}")
        self.episode = episode
        fit_episode(episode, self.geometry, show_player=self.show_player)
        total = len(episode.query_states)

        def on_state(change):
            if episode is self.episode and change["new"] < total:
                self._show_state(episode.query_states[change["new"]])

        episode.teaching.observe(on_state, names="state_index")
        episode.teaching.view.canvas.on_key_down(self._on_key_down)
        episode.on_demonstration(lambda record: self._hand_stop.set())
        episode.on_demonstration(lambda record: self.cues.demonstration(record.index + 1, total))
        episode.on_finished(self._on_finished)
        if episode.phase != "finished":
            self._show_state(episode.query_states[min(episode.state_index, total - 1)])
        return episode

    def _on_finished(self, result) -> None:
        self.cues.episode_end()
        self.execute(result.trajectory)

    # ------------------------------------------------------------------ teaching by hand
    def set_demonstration_modality(self, modality: str) -> None:
        """Show ("hand") or hide ("drawn") the way to teach by hand."""
        if modality not in DEMONSTRATION_MODALITIES:
            raise ValueError(f"modality: expected one of {DEMONSTRATION_MODALITIES}, got {modality!r}")
        self.demonstration_modality = modality
        self.panel.hand_button.layout.display = None if modality == "hand" else "none"
        if self.hand_view is not None:
            self.hand_view.layout.display = None if modality == "hand" else "none"

    def _on_key_down(self, key, *modifiers) -> None:
        if key in HAND_KEYS:
            self.teach_by_hand()

    @property
    def hand_move_active(self) -> bool:
        """Whether a hand move is under way (or queued)."""
        return self._hand_job is not None and not self._hand_job.done()

    def teach_by_hand(self) -> Future | None:
        """Start a demonstration by hand at the current query state (queued after the arm's
        earlier work). Does nothing outside the teaching phase, while a hand move is under
        way, after a stop, or when the modality is "drawn"."""
        episode = self.episode
        if (self.demonstration_modality != "hand" or episode is None or episode.phase != "teaching"
                or self.hand_move_active):
            return None
        if self.bridge.stop_requested:
            self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
            return None
        if not self.bridge.arm.connected:
            self.panel.say("The robot arm is disconnected: draw the arrow on the screen instead, or call the "
                           "experimenter. Your demonstrations are saved; nothing is lost.", error=True)
            return None
        index = episode.state_index
        self._hand_stop.clear()
        self.panel.hand_button.disabled = True
        self._hand_job = self._submit(self._hand_move, episode, index, np.array(episode.query_states[index]))
        return self._hand_job

    def _still_teaching(self, episode, index) -> bool:
        return (not self._hand_stop.is_set() and episode is self.episode and episode.phase == "teaching"
                and episode.state_index == index and not self.bridge.stop_requested)

    def _hand_move(self, episode, index, state) -> None:
        move = HandMove(self.bridge, state)
        try:
            self.panel.say("The arm is moving to the situation, then it lets go...")
            move.begin()
            self.panel.say("The arm is released: hold its tip and move it to show the robot its step. The arrow "
                           "shows your demonstration; press Confirm (or Enter) when it is right.")
            self._refresh_hand_view()
            last = None
            while self._still_teaching(episode, index):
                action = move.poll(0.1)
                # checked again: a confirmation during the poll must not put this arrow on the next state
                if not self._still_teaching(episode, index):
                    break
                if last is None or float(np.max(np.abs(action - last))) > 0.005:
                    episode.teaching.set_action(action, method="hand")
                    last = action
            if self.bridge.stop_requested:
                # Stopped mid-move: the arm stays released (it cannot move by itself); Resume
                # attaches it again before anything moves it (on 4.0-4.4 nothing is sent while paused).
                self._reattach_on_resume = True
                with self._stop_words:  # after stop() has said its words
                    words = ("The arm is stopped and released. Press Resume arm when it is safe: it will hold "
                             "itself again and go back to the situation.")
                    error = self._stop_error
                    self.panel.say(f"{error} {words}" if error else words, error=bool(error))
                return
            self.panel.say("The arm holds itself again and goes back to the situation...")
            move.end()
            self._update_position()
            self.panel.say("")
        except SwiftProError as exc:
            if move.released:
                log.warning("hand move at state %d failed with the arm released: %r", index, exc)
                self.panel.say("The robot arm was lost during the move by hand. It is released, so it cannot "
                               "move by itself: it is safe. " + describe_error(exc), error=True)
                return
            raise
        finally:
            self.panel.hand_button.disabled = False
            self._refresh_hand_view()

    def _refresh_hand_view(self) -> None:
        if self.hand_view is not None:
            self.hand_view.refresh()

    # ------------------------------------------------------------------ arm work, in order
    def _submit(self, job, *args) -> Future:
        return self._worker.submit(self._run, job, *args)

    def _run(self, job, *args):
        try:
            return job(*args)
        except SwiftProStopped:
            self.panel.resume_button.layout.display = None
            self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
        except (SwiftProError, UnsafeMoveError) as exc:
            log.warning("arm job %s failed: %r", getattr(job, "__name__", job), exc)
            self.panel.say(describe_error(exc), error=True)
        except Exception as exc:  # noqa: BLE001 - a worker thread has no one else to tell
            log.exception("arm job failed")
            self.panel.say(describe_error(exc), error=True)
        return None

    def _show_state(self, state) -> Future:
        state = np.array(state, dtype=float)
        return self._submit(self._show_state_now, state)

    def _show_state_now(self, state) -> None:
        if self.bridge.stop_requested:
            raise SwiftProStopped("stopped")
        self.panel.say("The arm is moving to the next situation...")
        self.bridge.return_to(state)  # from wherever a hand may have left it: homing first if outside
        self._update_position()
        self.panel.say("")

    def execute(self, trajectory) -> Future:
        """Play a reproduction on the arm (queued after the arm's earlier work)."""
        def run():
            self.panel.say("The robot is reproducing what it learnt...")
            report = self.bridge.execute(trajectory, on_step=lambda k, xy: self.panel.show_position(*xy))
            self.last_report = report
            if report.error:
                self.panel.say(report.error, error=True)
            elif report.stopped:
                self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
            else:
                self.panel.say("The robot has finished its reproduction.")
            self._update_position()
            return report

        return self._submit(run)

    def _beep(self, frequency_hz: float, duration_ms: float) -> None:
        self._submit(self.bridge.beep, frequency_hz, duration_ms)

    def _update_position(self) -> None:
        try:
            x, y, _ = self.bridge.position_mm()
        except SwiftProError as exc:
            self.panel.say(describe_error(exc), error=True)
            return
        self.panel.show_position(x, y)

    # ------------------------------------------------------------------ stop / resume
    def stop(self) -> None:
        """Halt the arm now (called from the kernel, not queued): no move starts until resume."""
        with self._stop_words:
            message = self.bridge.stop()
            self._stop_error = message
            self._hand_stop.set()
            self.panel.resume_button.layout.display = None
            if message:
                self.panel.say(message, error=True)
            else:
                self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")

    def resume(self) -> Future:
        """Let the arm move again and bring it back to the current query state.

        Queued on the worker (on firmware 4.0-4.4 resuming waits for the move the stop cut
        short to end), so the kernel stays free for the Stop button, which wins meanwhile.
        """
        self.panel.resume_button.layout.display = "none"
        self.panel.say("The arm is getting ready to move again...")

        def resume_and_show():
            try:
                self.bridge.resume()
                if self._reattach_on_resume:  # a hand move was stopped with the arm released
                    self.bridge.arm.attach()
                    self.bridge.arm.set_position_reports(None)
                    self._reattach_on_resume = False
            except BaseException:
                self.panel.resume_button.layout.display = None
                raise
            self._update_position()
            self.panel.say("")
            episode = self.episode
            if episode is not None and episode.phase != "finished":
                self._show_state_now(episode.query_states[min(episode.state_index, len(episode.query_states) - 1)])

        return self._submit(resume_and_show)

    def wait(self, timeout: float | None = None) -> None:
        """Block until the arm's queued work is done (for scripts and tests)."""
        self._submit(lambda: None).result(timeout)

    def close(self) -> None:
        """Stop the arm, drop the queued work (a reproduction waiting in the queue never
        starts, a running one is cut short) and close the connection."""
        self._hand_stop.set()
        message = self.bridge.stop()
        if message:
            log.info("stop on close: %s", message)
        self._worker.shutdown(wait=True, cancel_futures=True)
        self.bridge.arm.close()


class UArmEpisodePage(VBox):
    """One teaching episode on the arm: the arm panel, then the episode at true scale.

    Args:
        teaching: a :class:`UArmTeaching`.
        skill: "uarm-point" or "uarm-line" (or a uArm ``Skill``).
        demonstration_modality: if given, set on ``teaching`` ("drawn" or "hand").
        **episode_options: passed to ``EpisodeWidget`` (``seed``, ``guidance``, ``theme``, ...).
    """

    def __init__(self, teaching: UArmTeaching, skill="uarm-point", demonstration_modality: str | None = None,
                 **episode_options):
        episode_options.setdefault("theme", "paper-uarm")
        if demonstration_modality is not None:
            teaching.set_demonstration_modality(demonstration_modality)
        self.teaching = teaching
        self.episode = teaching.attach(EpisodeWidget(skill, **episode_options))
        hand = [teaching.hand_view] if teaching.hand_view is not None else []
        super().__init__([teaching.css, teaching.panel, teaching.cues, self.episode, *hand])


class UArmStudyApp(StudyApp):
    """The study runner's participant app on the uArm (protocol ``paper-uarm`` by default).

    Args:
        protocol, log_folder, practice_seed: as for ``StudyApp``.
        theme: the widgets' theme (default ``"paper-uarm"``: the paper's screen colours).
        arm: a connected ``SwiftPro``; if None, :func:`connect_arm` with ``port``.
        port: None or "auto" (a plugged-in Swift Pro, else the simulated arm), a device path
            or a pyserial URL.
        geometry: the screen under the arm (default: the paper's).
        show_player: as for :class:`UArmTeaching`.
    """

    def __init__(self, protocol: str = "paper-uarm", log_folder=None, theme="paper-uarm", practice_seed: int = 12345,
                 arm: SwiftPro | None = None, port: str | None = None, geometry: ScreenGeometry | None = None,
                 show_player: bool | None = None):
        self.arm_teaching = UArmTeaching(arm if arm is not None else connect_arm(port), geometry, show_player)
        super().__init__(protocol=protocol, log_folder=log_folder, theme=theme, practice_seed=practice_seed)
        arm_view = self.arm_teaching
        hand = [arm_view.hand_view] if arm_view.hand_view is not None else []
        self.participant_view.children = [arm_view.css, arm_view.panel, arm_view.cues, *self.participant_view.children,
                                          *hand]
        self.arm_status = HTML(f"<div><b>Arm:</b> {arm_view.panel.port.value}</div>")
        self.children = [self.arm_status, *self.children]

    def prepare_episode(self, episode: EpisodeWidget) -> EpisodeWidget:
        # StudyApp builds the episode (blinding, hidden labels); the arm is wired around it,
        # with the protocol's demonstration modality (drawn, or by hand).
        protocol = self.session.protocol if self.session is not None else None
        self.arm_teaching.set_demonstration_modality(getattr(protocol, "demonstration_modality", "drawn"))
        return self.arm_teaching.attach(episode)


__all__ = ["DEMONSTRATION_MODALITIES", "ArmPanel", "UArmEpisodePage", "UArmStudyApp", "UArmTeaching"]
