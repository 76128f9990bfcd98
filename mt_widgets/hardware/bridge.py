"""The uArm teaching plant on the real arm: cm <-> mm, query states shown, reproductions executed.

The kinematic plant of ``mt_widgets.core`` (``SKILLS["uarm-point"]``, ``SKILLS["uarm-line"]``)
works in centimetres in the arm's own horizontal frame: ``(r1, r2) = (X, Y) / 10``, X forward,
Y left, origin on the base axis. The arm works in millimetres at the fixed teaching height
(``mt_widgets.hardware.TEACHING_HEIGHT_MM``). This module is the only place the two meet:

- :func:`plant_to_arm_mm` / :func:`arm_to_plant_cm` map positions;
- :meth:`UArmBridge.show_state` moves the arm to a query state before the participant
  demonstrates there, so the real arm shows the state the screen shows;
- :meth:`UArmBridge.execute` plays a reproduction (a core ``Trajectory``) on the arm, one
  plant step per move, each step within the plant's per-step limit and the envelope's speed
  limit, every move through ``SwiftPro.move_to`` (which checks the safety envelope and asks
  the arm M2222 before sending anything);
- :meth:`UArmBridge.stop` halts at once: the connector's stop, through the arm's one
  :class:`~mt_widgets.hardware.stop.StopSwitch`, and no further moves: each job (showing a
  state, a reproduction) refuses to start while the switch is held and reads its
  generation when it starts, passing it to every ``move_to``, so a stop at any moment since
  the job began makes its moves refuse to be sent; :meth:`UArmBridge.resume` releases the
  switch (``SwiftPro.resume``, which on firmware 4.0-4.4, whose stop is a pause, un-pauses);
- an arm outside the safety envelope (after power-up) is brought in once, by
  :meth:`UArmBridge.home_if_outside` (``SwiftPro.home``), which the app calls at connection;
- a connector error never escapes :meth:`execute`: it comes back as a message in the
  :class:`ExecutionReport` (the study runner has logged the demonstrations already, so
  nothing is lost).

Everything here runs without Jupyter; :mod:`mt_widgets.apps.uarm_study` puts it on a page.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mt_widgets.core import SKILLS
from mt_widgets.core.validation import as_positive

from .connector import SIMULATOR_URL, SwiftPro
from .envelope import TEACHING_RADIUS_MM, SafetyEnvelope, polar_waypoints
from .errors import (
    SwiftProDisconnected,
    SwiftProError,
    SwiftProNotFound,
    SwiftProPortBusy,
    SwiftProStopped,
    SwiftProTimeout,
    SwiftProUnreachable,
    UnsafeMoveError,
)

log = logging.getLogger(__name__)

#: Millimetres per centimetre: the plant's unit to the arm's.
MM_PER_CM = 10.0
#: How much faster than real time the simulated arm of tests and short runs moves (``FAST_SIMULATOR_URL``).
FAST_SIMULATOR_SPEED = 50.0

#: The plant a bridge follows (step period, per-step limit, workspace): the paper's uArm skills'.
_PLANT = SKILLS["uarm-point"].plant


def plant_to_arm_mm(points_cm) -> np.ndarray:
    """Plant positions (..., 2) in cm -> arm positions (..., 2) in mm (same axes: X forward, Y left)."""
    points = np.asarray(points_cm, dtype=float)
    if points.shape[-1:] != (2,):
        raise ValueError(f"points_cm: expected an array of shape (..., 2) in cm, got shape {points.shape}")
    return points * MM_PER_CM


def arm_to_plant_cm(points_mm) -> np.ndarray:
    """Arm positions (..., 2) in mm (or (..., 3) with z, which is dropped) -> plant positions in cm."""
    points = np.asarray(points_mm, dtype=float)
    if points.shape[-1:] not in ((2,), (3,)):
        raise ValueError(f"points_mm: expected an array of shape (..., 2) or (..., 3) in mm, got shape {points.shape}")
    return points[..., :2] / MM_PER_CM


def default_simulator_url(speed: float = 1.0) -> str:
    """The simulated arm's URL (firmware 4.x) moving ``speed`` times faster than real time.

    At ``speed`` 1 it is ``SIMULATOR_URL``, which boots and moves as a real arm does; faster, it also
    boots in 10 ms. The caller says the speed: nothing here asks whether it runs under test.
    """
    speed = as_positive("speed", speed)
    if speed == 1.0:
        return SIMULATOR_URL
    return f"{SIMULATOR_URL}&boot=0.01&motion_scale={1.0 / speed:g}"


#: The simulated arm 50x faster than real time, booting in 10 ms: for tests and short runs.
FAST_SIMULATOR_URL = default_simulator_url(FAST_SIMULATOR_SPEED)


def connect_arm(port: str | None = None, *, simulator_url: str | None = None, simulator_speed: float = 1.0,
                **arm_options) -> SwiftPro:
    """A connected arm: the given port, else a plugged-in Swift Pro, else the simulated arm.

    Args:
        port: a device path or pyserial URL to use as is; None or ``"auto"`` to look for a
            Swift Pro by its USB id and fall back on the simulated arm when none answers.
        simulator_url: the fallback (default: the simulated arm, ``default_simulator_url(simulator_speed)``).
        simulator_speed: how much faster than real time the fallback simulated arm moves (1: real
            time, as a real arm; tests pass ``FAST_SIMULATOR_SPEED``). Not used with ``simulator_url``.
        **arm_options: passed to ``SwiftPro`` (``timeout``, ``envelope``, ...).

    Returns:
        A connected ``SwiftPro``; ``arm.port_used`` says which port it is on.

    Raises:
        SwiftProError: the given port could not be opened, or the arm did not answer.
    """
    if port not in (None, "auto"):
        arm = SwiftPro(port, **arm_options)
        arm.connect()
        return arm
    try:
        arm = SwiftPro("auto", **arm_options)
        arm.connect()
        return arm
    except SwiftProNotFound as exc:
        log.info("no Swift Pro plugged in (%s): using the simulated arm", exc)
    arm = SwiftPro(simulator_url or default_simulator_url(simulator_speed), **arm_options)
    arm.connect()
    return arm


def is_simulated(arm: SwiftPro) -> bool:
    """Whether the arm is the simulated one (its port is a ``uarm-sim://`` URL)."""
    port = arm.port_used or arm.port or ""
    return port.lower().startswith(("uarm-sim://", "uarmsim://"))


def simulated_device(arm: SwiftPro):
    """The ``SimulatedSwiftPro`` behind an arm on a ``uarm-sim://`` port (for a simulated
    hand, or a pulled cable, in a tutorial), or None for a real arm or a closed port."""
    serial_port = getattr(arm._link, "serial", None) if is_simulated(arm) else None
    return getattr(serial_port, "device", None)


def describe_error(error: BaseException) -> str:
    """A sentence for the screen about a connector error: what happened, and that nothing is lost."""
    safe = "Your demonstrations are saved; nothing is lost. Please call the experimenter."
    if isinstance(error, SwiftProPortBusy):
        what = "Another program is using the robot arm's port."
    elif isinstance(error, SwiftProDisconnected):
        what = "The robot arm is disconnected (cable or power)."
    elif isinstance(error, SwiftProTimeout):
        what = "The robot arm stopped answering."
    elif isinstance(error, SwiftProUnreachable):
        what = "The robot arm cannot reach that place."
    elif isinstance(error, UnsafeMoveError):
        what = "A move was refused by the safety limits, so the arm did not move."
    elif isinstance(error, SwiftProError):
        what = "The robot arm reported a problem."
    else:
        what = "Something went wrong while driving the robot arm."
    return f"{what} {safe} ({type(error).__name__}: {error})"


@dataclass
class ExecutionReport:
    """What happened when a reproduction was played on the arm.

    Attributes:
        steps_planned: plant steps in the trajectory (moves after the approach).
        steps_done: of those, how many the arm completed.
        stopped: True if :meth:`UArmBridge.stop` cut it short.
        error: a sentence for the screen if a connector error ended it, else None.
        positions_mm: (x, y) in mm the arm was sent to and reached, in order (approach included).
        duration_s: wall-clock seconds.
    """

    steps_planned: int
    steps_done: int = 0
    stopped: bool = False
    error: str | None = None
    positions_mm: list = field(default_factory=list)
    duration_s: float = 0.0

    @property
    def completed(self) -> bool:
        return not self.stopped and self.error is None and self.steps_done == self.steps_planned


class UArmBridge:
    """Drive a connected Swift Pro from the kinematic teaching plant.

    Args:
        arm: a connected ``SwiftPro`` (real or simulated).
        step_period_s: seconds per plant step (default: the plant's, 0.5 s); a reproduction
            step of d mm is sent at d / step_period_s mm/s, so it takes one step period.
        max_step_mm: the longest reproduction step accepted (default: the plant's
            ``max_step_cm`` in mm, 50 mm); a longer one means the trajectory did not come
            from the plant, and execution stops with a message.
        approach_speed_mm_s: speed of moves to a query state or to a reproduction's start.
        waypoint_mm: longest straight segment of those moves (they follow a polar path).
        min_move_mm: steps shorter than this are not sent (the arm's repeatability is 0.2 mm;
            a converged skill makes hundreds of tiny steps that would only make it buzz); the
            next step is then measured from where the arm is, so skipped steps never add up
            to a drift.
        z_mm: the teaching height (default: the arm's ``teaching_height_mm``).
    """

    def __init__(self, arm: SwiftPro, *, step_period_s: float | None = None, max_step_mm: float | None = None,
                 approach_speed_mm_s: float = 60.0, waypoint_mm: float = 40.0, min_move_mm: float = 0.5,
                 z_mm: float | None = None):
        if not isinstance(arm, SwiftPro):
            raise ValueError(f"arm: expected a connected SwiftPro, got {type(arm).__name__}")
        self.arm = arm
        self.envelope: SafetyEnvelope = arm.envelope
        self.step_period_s = as_positive("step_period_s",
                                         _PLANT.step_period if step_period_s is None else step_period_s)
        self.max_step_mm = as_positive("max_step_mm", _PLANT.max_step_cm * MM_PER_CM if max_step_mm is None
                                       else max_step_mm)
        self.approach_speed_mm_s = self.envelope.check_speed(approach_speed_mm_s)
        self.waypoint_mm = as_positive("waypoint_mm", waypoint_mm)
        if self.waypoint_mm > self.envelope.max_step_mm:
            raise ValueError(f"waypoint_mm: expected at most the envelope's max_step_mm = {self.envelope.max_step_mm}, "
                             f"got {waypoint_mm}")
        self.min_move_mm = as_positive("min_move_mm", min_move_mm, allow_zero=True)
        self.z_mm = float(arm.teaching_height_mm if z_mm is None else z_mm)
        self.envelope.check_point(self.envelope.min_radius_mm + 1.0, 0.0, self.z_mm)
        # The arm's stop switch, not one of our own: a stop by the bridge or on the arm is one stop.
        self._switch = arm.stop_switch
        # One job (showing a state, a reproduction, homing) at a time: two would interleave
        # their moves. Held for a whole job; stop() never takes it.
        self._busy = threading.Lock()
        self.moves_sent = 0

    # ------------------------------------------------------------------ positions
    def position_mm(self) -> tuple[float, float, float]:
        """Where the arm's tool is, (x, y, z) mm, as the arm reports it (P2220)."""
        return self.arm.position()

    def position_cm(self) -> np.ndarray:
        """Where the arm's tool is in the plant's frame, (r1, r2) cm."""
        return arm_to_plant_cm(self.position_mm())

    def state_to_arm_mm(self, state_cm) -> tuple[float, float, float]:
        """A plant state (2,) in cm -> the arm target (x, y, z) in mm at the teaching height."""
        state = np.asarray(state_cm, dtype=float)
        if state.shape != (2,) or not np.all(np.isfinite(state)):
            raise ValueError(f"state_cm: expected a finite (r1, r2) in cm, got {state_cm!r}")
        x, y = plant_to_arm_mm(state)
        return float(x), float(y), self.z_mm

    # ------------------------------------------------------------------ moving
    @property
    def stop_requested(self) -> bool:
        """True from a stop (here or on the arm) until :meth:`resume`."""
        return self._switch.held

    def _job_generation(self) -> int:
        """Start a job: read the switch's generation first, then whether it is held. A stop
        before this call holds the switch; one after it changes the generation, and every
        ``move_to(..., unless_stopped_since=generation)`` of the job then refuses to be sent."""
        generation = self._switch.generation
        if self._switch.held:
            raise SwiftProStopped("stop was requested; no further moves until resume")
        return generation

    def _move(self, x: float, y: float, speed: float, generation: int) -> None:
        self.moves_sent += 1
        self.arm.move_to(x, y, self.z_mm, speed=speed, unless_stopped_since=generation)

    def _travel_to(self, target, generation: int, on_point: Callable | None = None) -> None:
        """Go to ``target`` (x, y, z) mm along a polar path at the approach speed.

        An arm outside the envelope is refused by the connector (``UnsafeMoveError``):
        :meth:`home_if_outside` brings it in first.
        """
        start = self.arm.position()
        if math.dist(start, target) < self.min_move_mm:
            return  # already there: a zero-length move would only cost a round trip
        for point in polar_waypoints(start, target, self.waypoint_mm):
            self._move(float(point[0]), float(point[1]), self.approach_speed_mm_s, generation)
            if on_point is not None:
                on_point(point)

    def home_if_outside(self) -> bool:
        """Bring an arm that is outside the safety envelope (as after power-up) to the middle
        of the teaching workspace with ``SwiftPro.home`` (slowly, every leg checked). Called
        once at connection by the experimenter's app; :meth:`stop` cuts it like any move.

        Returns:
            True if the arm was outside and has been brought in, False if it was inside.
        """
        with self._busy:
            generation = self._job_generation()
            if self.envelope.contains(*self.arm.position()):
                return False
            r_mid = 0.5 * sum(TEACHING_RADIUS_MM)
            self.arm.home(r_mid, 0.0, self.z_mm, max_segment_mm=self.waypoint_mm, unless_stopped_since=generation)
            return True

    def show_state(self, state_cm) -> None:
        """Move the arm to a query state (r1, r2) cm, so the real arm shows what the screen shows.

        Raises:
            SwiftProStopped: :meth:`stop` was called (during the move, or before it and
                :meth:`resume` was not called since).
            SwiftProError, UnsafeMoveError: the connector's errors, unchanged.
        """
        target = self.state_to_arm_mm(state_cm)
        with self._busy:
            self._travel_to(target, self._job_generation())

    def return_to(self, state_cm) -> None:
        """Bring the arm to a query state from wherever it is (e.g. where a hand left it):
        into the envelope first if it is outside (:meth:`home_if_outside`), then there."""
        self.home_if_outside()
        self.show_state(state_cm)

    def execute(self, trajectory, on_step: Callable[[int, tuple[float, float]], None] | None = None
                ) -> ExecutionReport:
        """Play a reproduction on the arm, one plant step per move; never raises a connector error.

        The arm first travels to the trajectory's start at the approach speed; then each step
        ``p[k-1] -> p[k]`` (positions in cm, one row per plant step) is sent as one move at
        ``|step| / step_period_s`` mm/s, capped by the envelope's ``max_speed_mm_s``. A step
        longer than ``max_step_mm`` is refused (nothing more is sent).

        Args:
            trajectory: a core ``Trajectory`` with ``units == "cm"`` (``skill.reproduce(...)``).
            on_step: ``callback(k, (x_mm, y_mm))`` after the arm reached step k (0 = the start).

        Returns:
            An :class:`ExecutionReport`; ``stopped`` or ``error`` say why it ended early. After
            :meth:`stop`, nothing moves (``stopped``, no step done) until :meth:`resume`.
        """
        units = getattr(trajectory, "units", None)
        if units != "cm":
            raise ValueError(f"trajectory: expected a uArm Trajectory with units 'cm', got units {units!r}")
        positions = np.asarray(trajectory.positions, dtype=float)
        if positions.ndim != 2 or positions.shape[1] != 2 or len(positions) == 0:
            raise ValueError(f"trajectory.positions: expected shape (T, 2) with T >= 1, got {positions.shape}")
        report = ExecutionReport(steps_planned=len(positions) - 1)
        started = time.monotonic()
        with self._busy:
            try:
                generation = self._job_generation()
                start = self.state_to_arm_mm(positions[0])
                self._travel_to(start, generation)
                report.positions_mm.append(start[:2])
                if on_step is not None:
                    on_step(0, start[:2])
                here = np.asarray(start[:2])
                for k in range(1, len(positions)):
                    target = plant_to_arm_mm(positions[k])
                    step = float(np.linalg.norm(target - here))
                    if step > self.max_step_mm + 1e-6:
                        raise UnsafeMoveError(
                            f"reproduction step {k} is {step:.1f} mm, longer than max_step_mm = {self.max_step_mm}",
                            coordinate="step", value=step, limit=self.max_step_mm)
                    if step >= self.min_move_mm:
                        speed = min(max(step / self.step_period_s, 1.0), self.envelope.max_speed_mm_s)
                        self._move(float(target[0]), float(target[1]), speed, generation)
                        here = target
                    report.steps_done = k
                    report.positions_mm.append((float(here[0]), float(here[1])))
                    if on_step is not None:
                        on_step(k, (float(here[0]), float(here[1])))
            except SwiftProStopped:
                report.stopped = True
            except (SwiftProError, UnsafeMoveError) as exc:
                if self._switch.held:
                    report.stopped = True
                else:
                    log.warning("reproduction on the arm ended by %r", exc)
                    report.error = describe_error(exc)
            report.stopped = report.stopped or self._switch.held
        report.duration_s = time.monotonic() - started
        return report

    def stop(self) -> str | None:
        """Halt now: the arm's stop command cuts the current move, and no further move starts
        until :meth:`resume`. A move of a job that began before this call refuses to be sent
        even if its checks were under way (the connector's stop generation), so one stop
        command is enough.

        Returns:
            None, or a sentence for the screen if the stop command could not be sent (the
            link is down: the arm is not being driven by us anyway).
        """
        try:
            self.arm.stop()
        except (SwiftProError, OSError) as exc:
            return describe_error(exc)
        return None

    def resume(self) -> None:
        """Allow moves again after :meth:`stop` (a person decided it is safe).

        On firmware 4.0-4.4 the arm was paused: ``SwiftPro.resume`` un-pauses it and waits
        until the move the stop cut short has ended, so it can never run after new moves;
        this may take as long as that move's remainder. A stop meanwhile wins: the arm is
        paused again, the stop stays in force, and this raises ``SwiftProStopped``.

        Raises:
            SwiftProStopped: a stop came while resuming.
            SwiftProError: the link failed (the stop stays in force).
        """
        self.arm.resume()

    def beep(self, frequency_hz: float, duration_ms: float) -> str | None:
        """Sound the arm's buzzer (M2210); returns a message instead of raising if the link fails."""
        try:
            self.arm.beep(frequency_hz, duration_ms)
        except SwiftProError as exc:
            return describe_error(exc)
        return None


__all__ = ["ExecutionReport", "FAST_SIMULATOR_SPEED", "FAST_SIMULATOR_URL", "MM_PER_CM", "SIMULATOR_URL", "UArmBridge",
           "arm_to_plant_cm", "connect_arm", "default_simulator_url", "describe_error", "is_simulated",
           "plant_to_arm_mm", "polar_waypoints"]
