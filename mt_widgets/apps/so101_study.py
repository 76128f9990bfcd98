"""Teaching the SO-101 by hand in a page, and the study runner on it.

``SO101Teaching`` wires an ``EpisodeWidget`` (the 3-D renderer: the SO-101's plant is drawn in
space) to the arm:

- at each query state the arm drives itself there (a goal the envelope checks), then its torque
  goes off and the person moves it: the gripper's displacement, read 50 times a second
  (:class:`mt_widgets.hardware.feetech.hand.HandDemonstration`), is the pending arrow in the
  three views until it is confirmed; the arm then holds itself again and goes back to the query
  state; guidance follows as the episode's settings say (MT's optimal arrow beside the person's);
- with a leader arm (a second SO-101 bus, LeRobot's ``so101_leader``), the leader's joints are the
  hand-held input and the arm itself holds the query state throughout;
- a query state the arm's envelope refuses (an arm calibrated narrower than the skill allows
  for) is said in words; the arm stays put and the person draws the arrow for that state;
- the learnt skill's reproduction is played on the arm through waypoints the envelope checks
  (:mod:`mt_widgets.hardware.feetech.reproduction`); the simulated hand's views are redrawn at
  every waypoint and whenever the arm has moved by itself;
- **Stop the arm** holds every servo at once and lets nothing move until **Resume arm**;
- a fault (a pulled cable, a servo that stops answering, an overload) stops the arm and is said in
  words; the confirmed demonstrations are the episode's (a study logs them before the arm does
  anything) and the arrow shown so far stays on screen to confirm: nothing recorded is lost.

Arm work runs on one worker thread, in order, so the kernel stays free for the Stop button.
:func:`open_so101` connects to a real arm (a port and LeRobot's calibration file) or builds the
simulated one, with a :class:`~.so101_hand.SimulatedHandView` standing in for the hand.
``SO101EpisodePage`` is one episode on the arm; ``SO101StudyApp`` the participant app of
``mt_widgets.apps.study_app`` with every episode wired this way.
"""

from __future__ import annotations

import logging
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
from ipywidgets import HTML, VBox

from mt_widgets.core.validation import as_bool
from mt_widgets.hardware.errors import UnsafeMoveError
from mt_widgets.hardware.feetech import ARM_JOINTS, SO101, SO101Error, SO101Stopped
from mt_widgets.hardware.feetech.hand import HandDemonstration
from mt_widgets.hardware.feetech.reproduction import PlayReport, play_on_arm
from mt_widgets.hardware.feetech.sim_bus import SIMULATED_CALIBRATION, calibrated_bus
from mt_widgets.hardware.feetech.sim_hand import SimulatedHand
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort
from mt_widgets.widgets import EpisodeWidget

from .arm_panel import ArmPanel
from .so101_hand import SimulatedHandView
from .study_app import StudyApp

log = logging.getLogger(__name__)

#: How a demonstration is given: drawn in the 3-D views, or shown by moving the arm by hand.
DEMONSTRATION_MODALITIES = ("drawn", "hand")
#: Readings of the hand a second (LeRobot's teleoperation runs at 30-60).
HAND_RATE_HZ = 50.0
#: The arrow follows the hand when the tool has moved this far (m) since the arrow last drawn.
ARROW_STEP_M = 0.002
#: What a fault during a demonstration by hand means for the person.
_SAFE_AND_SAVED = ("Your demonstrations so far are saved, and the arrow you showed is still on the screen: "
                   "confirm it, or draw one.")


class SO101Teaching:
    """Connects teaching episodes to the SO-101.

    Args:
        arm: a connected ``SO101`` (calibrated).
        leader: a connected leader ``SO101`` whose joints are the hand-held input, or None.
        hands: ``SimulatedHand``s to show as views (the simulated arm's, the simulated leader's).
        demonstration_modality: "hand" (the arm, or the leader, moved by hand; logged as the
            method "hand") or "drawn" (arrows drawn in the views; the arm shows the states).
        release_at_each_state: in "hand", release the arm for the hand as soon as it has reached
            each query state (False: only on "Teach by hand").
        play_on_arm: play each reproduction on the arm.
        hand_rate: readings of the hand a second.
    """

    def __init__(self, arm: SO101, *, leader: SO101 | None = None, hands=(), demonstration_modality: str = "hand",
                 release_at_each_state: bool = True, play_on_arm: bool = True, hand_rate: float = HAND_RATE_HZ,
                 port_text: str | None = None):
        if not isinstance(arm, SO101):
            raise TypeError(f"arm: expected a connected SO101, got {type(arm).__name__}")
        if arm.envelope is None:
            raise ValueError("arm: expected a calibrated arm (run lerobot-calibrate and give its file, or call "
                             "arm.calibrate()), got one without a calibration")
        if leader is not None and (not isinstance(leader, SO101) or leader.calibration is None):
            raise ValueError(f"leader: expected a connected, calibrated SO101 or None, got {leader!r}")
        self.arm, self.leader = arm, leader
        self.release_at_each_state = as_bool("release_at_each_state", release_at_each_state)
        self.play_on_arm = as_bool("play_on_arm", play_on_arm)
        if not (isinstance(hand_rate, (int, float)) and not isinstance(hand_rate, bool) and 0 < hand_rate <= 200):
            raise ValueError(f"hand_rate: expected readings a second in (0, 200], got {hand_rate!r}")
        self.hand_rate = float(hand_rate)
        port = port_text if port_text is not None else f"SO-101 on {arm.bus.port}"
        if leader is not None:
            port += f", leader arm on {leader.bus.port}"
        self.panel = ArmPanel(port)
        self.panel.stop_button.on_click(lambda _: self.stop())
        self.panel.resume_button.on_click(lambda _: self.resume())
        self.panel.hand_button.on_click(lambda _: self.teach_by_hand())
        self.hand_views = [SimulatedHandView(h, title) for h, title in hands]
        self.demonstration_modality = "hand"
        self.set_demonstration_modality(demonstration_modality)
        self.episode: EpisodeWidget | None = None
        self.last_report: PlayReport | None = None
        #: The hand demonstration under way (or the last one): its readings are kept there.
        self.hand_demonstration: HandDemonstration | None = None
        #: Seconds from a reading of the hand to its arrow drawn, one per arrow drawn (for the benchmark).
        self.arrow_latencies: list[float] = []
        #: The query state the envelope refused to go to (the person draws its arrow), or None.
        self._refused_state: np.ndarray | None = None
        self._hand_stop = threading.Event()
        # Set once by close(): unlike _hand_stop, which each new query state clears, it ends any hand
        # loop for good (a close while the arm drives to a state must not leave the loop waiting on the hand).
        self._closing = threading.Event()
        self._hand_job: Future | None = None
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="so101")
        self._submit(self._update_position)

    # ------------------------------------------------------------------ episodes
    def attach(self, episode: EpisodeWidget) -> EpisodeWidget:
        """Wire an episode: the query states on the arm, the hand's arrow, the reproduction on the arm."""
        joints = tuple(getattr(getattr(episode.skill.plant, "chain", None), "joint_names", ()))
        if joints != ARM_JOINTS:
            raise ValueError(f"episode: expected an episode of a skill on the SO-101's arm (the joints {ARM_JOINTS}), "
                             f"got skill {episode.skill.key!r} on {type(episode.skill.plant).__name__} with joints "
                             f"{joints}")
        self.episode = episode
        total = len(episode.query_states)

        def on_event(event):
            # The controller's "state": a state awaits a demonstration (the widget's state_index
            # trait passes through the next index while a confirmation is recorded).
            index = episode.controller.state_index
            if event == "state" and episode is self.episode and index < total:
                self._show_state(episode.query_states[index])

        episode.controller.observe(on_event)
        episode.on_demonstration(lambda record: self._hand_stop.set())
        episode.on_finished(self._on_finished)
        if episode.phase != "finished":
            self._show_state(episode.query_states[min(episode.state_index, total - 1)])
        return episode

    def _on_finished(self, result) -> None:
        if result is not None and self.play_on_arm:
            self.execute(result.trajectory)

    def set_demonstration_modality(self, modality: str) -> None:
        """Show ("hand") or hide ("drawn") the way to teach by hand."""
        if not isinstance(modality, str) or modality not in DEMONSTRATION_MODALITIES:
            raise ValueError(f"demonstration_modality: expected one of {DEMONSTRATION_MODALITIES}, got {modality!r}")
        self.demonstration_modality = modality
        self.panel.hand_button.layout.display = None if modality == "hand" else "none"
        for view in self.hand_views:
            view.layout.display = None if modality == "hand" else "none"

    # ------------------------------------------------------------------ arm work, in order
    def _submit(self, job, *args) -> Future:
        return self._worker.submit(self._run, job, *args)

    def _run(self, job, *args):
        try:
            return job(*args)
        except SO101Stopped:
            self.panel.resume_button.layout.display = None
            self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
        except (SO101Error, UnsafeMoveError) as error:
            log.warning("arm job %s failed: %r", getattr(job, "__name__", job), error)
            self.panel.say(f"The robot arm stopped: {error}", error=True)
        except Exception as error:  # noqa: BLE001 - a worker thread has no one else to tell
            log.exception("arm job failed")
            self.panel.say(f"Something went wrong with the arm: {error}", error=True)
        return None

    def _show_state(self, state) -> Future:
        return self._submit(self._show_state_now, np.array(state, dtype=float))

    def _show_state_now(self, state) -> None:
        if self.arm.stopped:
            raise SO101Stopped("stopped")
        self.panel.say("The arm is moving to the next situation...")
        self.arm.torque(True)
        episode = self.episode
        try:
            self.arm.move_joints(dict(zip(ARM_JOINTS, (float(v) for v in state[:len(ARM_JOINTS)]))))
        except UnsafeMoveError as error:
            # A situation this arm's envelope refuses (its calibrated range may be narrower than the
            # skill allowed for): the person draws the arrow for it and goes on; the arm stays put.
            self._refused_state = state.copy()
            self._update_position()
            self.panel.say(f"The arm cannot go to this situation: {error}. It stays where it is. Draw your arrow "
                           f"for this situation in the views, confirm it and go on.", error=True)
            return
        self._refused_state = None
        self._update_position()
        self.panel.say("")
        if (self.release_at_each_state and self.demonstration_modality == "hand" and episode is not None
                and episode.phase == "teaching"):
            self._hand_stop.clear()
            self._hand_move(episode, episode.state_index, state)

    def _update_position(self) -> None:
        """Show where the arm is: after every move it makes by itself (a query state, each waypoint of a
        reproduction, back from the hand), in the panel and in the simulated hand's views."""
        try:
            self.panel.show_position(*(1000 * v for v in self.arm.tool_point()))
        except SO101Error as error:
            self.panel.say(f"The robot arm cannot be read: {error}", error=True)
        # The stand-in hand's views draw the simulated servos: the arm moved them, not the hand.
        self._refresh_hand_views()

    # ------------------------------------------------------------------ teaching by hand
    @property
    def hand_move_active(self) -> bool:
        """Whether a demonstration by hand is under way (or queued)."""
        return self._hand_job is not None and not self._hand_job.done()

    def teach_by_hand(self) -> Future | None:
        """Start a demonstration by hand at the current query state (queued after the arm's work).
        Does nothing outside the teaching phase, while one is under way, after a stop, or when
        the modality is "drawn"."""
        episode = self.episode
        if (self.demonstration_modality != "hand" or episode is None or episode.phase != "teaching"
                or self.hand_move_active
                or (self.hand_demonstration is not None and self.hand_demonstration.released)):
            return None
        if self.arm.stopped:
            self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
            return None
        index = episode.state_index
        if self.state_refused(np.asarray(episode.query_states[index], dtype=float)):
            self.panel.say("The arm cannot go to this situation (it is outside its safe range), so it cannot be "
                           "shown by hand: draw your arrow for it in the views, confirm it and go on.", error=True)
            return None
        self._hand_stop.clear()
        self._hand_job = self._submit(self._hand_move, episode, index, np.array(episode.query_states[index]))
        return self._hand_job

    def state_refused(self, state) -> bool:
        """Whether the arm's envelope refused to go to ``state`` (the last query state it was sent to)."""
        return self._refused_state is not None and np.array_equal(self._refused_state, state)

    def _still_teaching(self, episode, index) -> bool:
        return (not self._hand_stop.is_set() and not self._closing.is_set() and episode is self.episode
                and episode.phase == "teaching"
                and episode.state_index == index and not self.arm.stopped)

    def _hand_move(self, episode, index, state) -> None:
        move = HandDemonstration(self.arm, state[:len(ARM_JOINTS)], episode.skill.plant.drawing().action_length,
                                 leader=self.leader)
        self.hand_demonstration = move
        self.panel.hand_button.disabled = True
        try:
            self.panel.say("The arm is moving to the situation, then it lets go...")
            move.begin()
            who = "the leader arm" if self.leader is not None else "the arm"
            self.panel.say(f"The torque is off: hold {who}'s gripper and move it to show the robot how its gripper "
                           f"should move from here. The arrow shows your demonstration; press Confirm when it is "
                           f"right.")
            self._refresh_hand_views()
            drawn_at = None
            period = 1.0 / self.hand_rate
            next_tick = time.monotonic()
            while self._still_teaching(episode, index):
                action = move.poll()
                read_at = time.monotonic()
                # checked again: a confirmation during the reading must not put this arrow on the next state
                if not self._still_teaching(episode, index):
                    break
                if drawn_at is None or float(np.linalg.norm(move.displacement - drawn_at)) > ARROW_STEP_M:
                    try:
                        episode.set_action(action, method="hand")
                    except RuntimeError:  # confirmed in the meantime: the state awaits no arrow now
                        break
                    self.arrow_latencies.append(time.monotonic() - read_at)
                    drawn_at = move.displacement
                    self._refresh_hand_views()
                next_tick += period
                time.sleep(max(0.0, next_tick - time.monotonic()))
                next_tick = max(next_tick, time.monotonic() - period)  # a missed tick is skipped, not caught up
            if self.arm.stopped:
                self.panel.say("The arm is stopped; its torque is off, so it cannot move by itself. Press Resume "
                               "arm when it is safe: it will hold itself again and go back to the situation.")
                return
            self.panel.say("The arm holds itself again and goes back to the situation...")
            move.end()
            self._update_position()
            self.panel.say("")
        except SO101Stopped:
            raise
        except SO101Error as error:
            log.warning("hand demonstration at state %d failed: %r", index, error)
            limp = " Its torque is off, so it cannot move by itself: it is safe." if move.released else ""
            self.panel.say(f"The robot arm stopped during your demonstration: {error}{limp} {_SAFE_AND_SAVED}",
                           error=True)
            self.panel.resume_button.layout.display = None
        except UnsafeMoveError as error:
            self.panel.say(f"The arm cannot go back to the situation from where it was left: {error}. It holds "
                           f"where it is. {_SAFE_AND_SAVED}", error=True)
        finally:
            self.panel.hand_button.disabled = False
            self._refresh_hand_views()

    def _refresh_hand_views(self) -> None:
        for view in self.hand_views:
            try:
                view.refresh()
            except Exception:  # noqa: BLE001 - a drawing of the stand-in hand must never stop the arm's work
                log.exception("refreshing the simulated hand failed")

    # ------------------------------------------------------------------ reproduction
    def execute(self, trajectory) -> Future:
        """Play a reproduction on the arm (queued after the arm's earlier work)."""
        def run():
            self.panel.say("The robot is reproducing what it learnt...")
            report = play_on_arm(self.arm, trajectory.times, trajectory.states,
                                 on_waypoint=lambda k, q: self._update_position())
            self.last_report = report
            if report.error:
                self.panel.say(report.error, error=True)
            elif report.stopped:
                self.panel.resume_button.layout.display = None
                self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")
            else:
                self.panel.say("The robot has finished its reproduction.")
            self._refresh_hand_views()
            return report

        return self._submit(run)

    # ------------------------------------------------------------------ stop / resume
    def stop(self) -> None:
        """Hold the arm now (called from the kernel, not queued): nothing moves until resume."""
        self._hand_stop.set()
        try:
            self.arm.stop()
        except SO101Error as error:
            self.panel.say(f"The robot arm cannot be reached: {error}", error=True)
        self.panel.resume_button.layout.display = None
        self.panel.say("The arm is stopped. Press Resume arm when it is safe to move it again.")

    def resume(self) -> Future:
        """Let the arm move again: it holds itself and goes back to the current query state."""
        self.panel.resume_button.layout.display = "none"
        self.panel.say("The arm is getting ready to move again...")
        self.arm.resume()
        episode = self.episode
        if episode is not None and episode.phase != "finished":
            return self._show_state(episode.query_states[min(episode.state_index, len(episode.query_states) - 1)])
        return self._submit(self._update_position)

    def wait(self, timeout: float | None = None) -> None:
        """Block until the arm's queued work is done (for scripts and tests)."""
        self._submit(lambda: None).result(timeout)

    def close(self) -> None:
        """Stop the hand, drop the queued work, hold the arm and close its port (and the leader's)."""
        self._closing.set()
        self._hand_stop.set()
        self._worker.shutdown(wait=True, cancel_futures=True)
        for arm in (self.arm, self.leader):
            if arm is not None:
                try:
                    arm.stop()
                except SO101Error:
                    pass
                arm.close()


def open_so101(port: str = "sim", calibration=None, *, leader_port: str | None = None, leader_calibration=None,
               speed_scale: float = 4.0, **options) -> SO101Teaching:
    """Connect to an SO-101 (and its leader arm) for teaching by hand.

    Args:
        port: the arm's serial port, or "sim" for the simulated arm (six simulated STS3215 on a
            pseudo-terminal, calibrated as LeRobot leaves them) with a simulated hand.
        calibration: LeRobot's calibration file of the arm (None: the one in its servos).
        leader_port: a leader arm's port, "sim" for a simulated leader, or None (no leader).
        leader_calibration: the leader's calibration file.
        speed_scale: how much faster than the real servos the simulated ones move.
        **options: passed to :class:`SO101Teaching`.
    """
    if not isinstance(port, str) or not port:
        raise ValueError(f"port: expected a serial port (e.g. /dev/ttyACM0) or 'sim', got {port!r}")
    if leader_port is not None and (not isinstance(leader_port, str) or not leader_port
                                    or (leader_port == port and port != "sim")):
        raise ValueError(f"leader_port: expected the leader arm's own serial port, 'sim' or None, got {leader_port!r}")
    hands, servers = [], []

    def connect(which, where, calib, title):
        if where != "sim":
            return SO101(where, calib)
        bus = calibrated_bus(speed_scale=speed_scale)
        server = SimulatedArmPort(bus)
        servers.append(server)
        # The simulated servos answer from a thread of this process: under load they wait for the
        # interpreter, so the answer timeout is longer than a real bus needs.
        arm = SO101(server.path, SIMULATED_CALIBRATION, timeout=0.25)
        hands.append((SimulatedHand(bus, arm.calibration, arm.kinematics), title))
        return arm

    arm = connect("arm", port, calibration, "Your hand on the simulated arm")
    leader = None
    if leader_port is not None:
        leader = connect("leader", leader_port, leader_calibration, "Your hand on the simulated leader arm")
        # With a leader, the hand moves the leader only: the arm's own stand-in hand is left out.
        hands = [h for h in hands if h[1].endswith("leader arm")]
    where = "simulated SO-101" if port == "sim" else f"SO-101 on {port}"
    if leader_port is not None:
        where += ", leader arm " + ("(simulated)" if leader_port == "sim" else f"on {leader_port}")
    teaching = SO101Teaching(arm, leader=leader, hands=hands, port_text=where, **options)
    teaching.simulated_ports = servers
    return teaching


class SO101EpisodePage(VBox):
    """One teaching episode on the SO-101: the arm panel, the episode in 3-D, the simulated hand.

    Args:
        teaching: a :class:`SO101Teaching`.
        skill: "so101-reach" or "so101-place" (or a ``Skill`` on the SO-101).
        **episode_options: passed to ``EpisodeWidget`` (``seed``, ``guidance``, ``theme``, ...).
    """

    def __init__(self, teaching: SO101Teaching, skill="so101-reach", **episode_options):
        if not isinstance(teaching, SO101Teaching):
            raise TypeError(f"teaching: expected an SO101Teaching, got {type(teaching).__name__}")
        self.teaching = teaching
        self.episode = teaching.attach(EpisodeWidget(skill, **episode_options))
        super().__init__([teaching.panel, self.episode, *teaching.hand_views])


class SO101StudyApp(StudyApp):
    """The study runner's participant app on the SO-101 (protocol ``paper-so101`` by default).

    Args:
        protocol, log_folder, theme, practice_seed: as for ``StudyApp``.
        teaching: an :class:`SO101Teaching`; if None, :func:`open_so101` with ``port``.
        port: the arm's port, or "sim" for the simulated arm.
    """

    def __init__(self, protocol: str = "paper-so101", log_folder=None, theme=None, practice_seed: int = 12345,
                 teaching: SO101Teaching | None = None, port: str = "sim"):
        self.arm_teaching = teaching if teaching is not None else open_so101(port)
        super().__init__(protocol=protocol, log_folder=log_folder, theme=theme, practice_seed=practice_seed)
        arm_view = self.arm_teaching
        self.participant_view.children = [arm_view.panel, *self.participant_view.children, *arm_view.hand_views]
        self.arm_status = HTML(f"<div><b>Arm:</b> {arm_view.panel.port.value}</div>")
        self.children = [self.arm_status, *self.children]

    def prepare_episode(self, episode: EpisodeWidget) -> EpisodeWidget:
        # StudyApp builds the episode (blinding, hidden labels); the arm is wired around it, with the
        # protocol's demonstration modality. A practice round (no reproduction) is drawn on screen.
        protocol = self.session.protocol if self.session is not None else None
        modality = getattr(protocol, "demonstration_modality", "drawn") if episode.reproduce else "drawn"
        self.arm_teaching.set_demonstration_modality(modality)
        chain = getattr(episode.skill.plant, "chain", None)
        if not episode.reproduce and tuple(getattr(chain, "joint_names", ())) != ARM_JOINTS:
            return episode
        return self.arm_teaching.attach(episode)


__all__ = ["DEMONSTRATION_MODALITIES", "SO101EpisodePage", "SO101StudyApp", "SO101Teaching", "open_so101"]
