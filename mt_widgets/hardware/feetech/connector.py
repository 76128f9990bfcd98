"""The SO-101 arm over its Feetech bus: discovery, calibration, moves inside the envelope, the
gripper, torque, teaching by hand, faults and the emergency stop.

``SO101(port, calibration=..., kinematics=...)`` opens the port and pings the six servos
(ids 1..6, model 777 = STS3215). The calibration is LeRobot's (a ``lerobot-calibrate`` file,
or, with none given, what LeRobot wrote into the servos' EEPROM), so an arm calibrated with
LeRobot needs no second calibration; :meth:`SO101.calibrate` calibrates an arm that has none.

Every goal goes through :class:`~.envelope.SO101Envelope` before a byte is sent, and all the
joints of a move go in one SYNC_WRITE with speeds and accelerations scaled so that they arrive
together: the arm follows the straight line in joint space the envelope checked. While a move
runs the connector reads every servo's position and error byte; a servo that reports an error,
stops answering or answers garbage stops the move: the other servos hold where they are, and
the exception says what happened in words (:mod:`.errors`).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

from mt_widgets.arms import so101_chain

from ..errors import UnsafeMoveError
from .arm import ARM_JOINTS, GRIPPER, SO101_IDS
from .bus import FeetechBus
from .calibration import JointCalibration, calibration_from_dict, read_calibration, write_calibration
from .control_table import REGISTERS, STEPS_PER_TURN, STS3215_MODEL, decode, encode
from .envelope import SO101Envelope
from .errors import (
    BusDisconnected,
    CalibrationError,
    CorruptReply,
    ServoFault,
    ServoNotAnswering,
    SO101Error,
    WrongServo,
    describe,
)
from .kinematics import ArmKinematics

#: One sync read from present_position (56) to moving (66) gives a servo's whole state.
_STATE_START, _STATE_SIZE = 56, 11
_NAMES = {servo_id: name for name, servo_id in SO101_IDS.items()}
#: Steps a second for one radian a second (4096 steps a turn).
_STEPS_PER_RAD = STEPS_PER_TURN / (2 * math.pi)


class SO101Stopped(SO101Error):
    """A move was cut short, or refused, by :meth:`SO101.stop` (until :meth:`SO101.resume`)."""


def _register(name: str, value: int) -> tuple[int, bytes]:
    register = REGISTERS[name]
    return register.address, encode(register, value)


class SO101:
    """An SO-101 arm (six STS3215 servos) on one serial port.

    Args:
        port: the serial device (``/dev/ttyACM0``, ``COM3``; the simulated arm's
            :attr:`~.sim_pty.SimulatedArmPort.path`).
        calibration: a LeRobot calibration file's path, its mapping, or None to use the
            calibration LeRobot wrote into the servos.
        kinematics: the arm's serial chain (:class:`mt_widgets.core.serial_chain.SerialChain`
            of the five arm joints to ``gripper_frame_link``) or an :class:`ArmKinematics`; None:
            the SO-101's own, from the URDF the package ships (``mt_widgets.arms.shipped``).
            It is what keeps every link above the table.
        timeout: seconds a servo may take to answer (a USB adapter's latency timer is often 16 ms).
        envelope: keyword arguments of :class:`SO101Envelope` (table_height, clearance, margin,
            max_speed, max_acceleration).
    """

    def __init__(self, port, calibration=None, kinematics=None, *, timeout: float = 0.05, **envelope):
        if isinstance(calibration, dict):
            self._calibration_source: dict | None = calibration_from_dict(
                {k: (v.__dict__ if isinstance(v, JointCalibration) else v) for k, v in calibration.items()})
        elif calibration is None:
            self._calibration_source = None
        else:
            self._calibration_source = read_calibration(calibration)
        if kinematics is None:
            kinematics = so101_chain()
        if not isinstance(kinematics, ArmKinematics):
            kinematics = ArmKinematics(kinematics)
        self.kinematics = kinematics
        self._envelope_options = envelope
        self._lock = threading.RLock()
        self._stopped = threading.Event()
        self.bus = FeetechBus(port, timeout=timeout)
        #: Faults met, oldest first: (time.time(), message), kept whatever happens next.
        self.faults: list[tuple[float, str]] = []
        try:
            self._discover()
            self._configure()
        except BaseException:
            self.bus.close()
            raise

    # ------------------------------------------------------------------ life cycle
    def close(self) -> None:
        """Close the port (the servos keep their torque state: a held arm stays held)."""
        self.bus.close()

    def __enter__(self) -> SO101:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _discover(self) -> None:
        found, missing, wrong = {}, [], []
        for name, servo_id in SO101_IDS.items():
            try:
                # PING, then the model number (what the SDK's ping and LeRobot's handshake do).
                self.bus.ping(servo_id)
                data, _ = self.bus.read(servo_id, REGISTERS["model_number"].address, 2)
            except (ServoNotAnswering, CorruptReply):
                missing.append(f"{name} (id {servo_id})")
                continue
            found[name] = model = decode(REGISTERS["model_number"], data)
            if model != STS3215_MODEL:
                wrong.append(f"{name} (id {servo_id}) is model {model}, not an STS3215 ({STS3215_MODEL})")
        if not found:
            raise WrongServo(f"no servo answers on {self.bus.port!r}: is this the arm's port, and is its power "
                             f"supply plugged in and on?")
        if missing:
            raise WrongServo(f"the servos {', '.join(missing)} do not answer: check their cables (each servo "
                             f"passes the bus on to the next) and their ids (lerobot-setup-motors)")
        if wrong:
            raise WrongServo("; ".join(wrong) + ": this is not an SO-101's servo")

    def _read_register(self, servo_id: int, name: str) -> int:
        register = REGISTERS[name]
        data, _ = self.bus.read(servo_id, register.address, register.size)
        return decode(register, data)

    def _configure(self) -> None:
        for servo_id in SO101_IDS.values():
            # Answer at once (factory: 500 us), as LeRobot's configure_motors does; written with
            # the lock on, it lasts until power-off and leaves the EEPROM as it was.
            self.bus.write(servo_id, *_register("return_delay", 0))
        stored = {name: JointCalibration(
            id=servo_id, drive_mode=0, homing_offset=self._read_register(servo_id, "homing_offset"),
            range_min=self._read_register(servo_id, "min_position_limit"),
            range_max=self._read_register(servo_id, "max_position_limit")) for name, servo_id in SO101_IDS.items()}
        if self._calibration_source is None:
            if all(c.homing_offset == 0 and (c.range_min, c.range_max) == (0, 4095) for c in stored.values()):
                # Factory values: nothing to read angles with until calibrate() (read_steps works).
                self.calibration = None
                self.envelope = None
                return
            self._set_calibration(stored)
        else:
            if any((stored[j].homing_offset, stored[j].range_min, stored[j].range_max) !=
                   (c.homing_offset, c.range_min, c.range_max) for j, c in self._calibration_source.items()):
                self._write_calibration(self._calibration_source)
            self._set_calibration(self._calibration_source)

    def _set_calibration(self, calibration: dict[str, JointCalibration]) -> None:
        self.calibration = dict(calibration)
        self.envelope = SO101Envelope(self.calibration, self.kinematics, **self._envelope_options)

    def _write_eeprom(self, servo_id: int, values: dict[str, int]) -> None:
        self.bus.write(servo_id, *_register("lock", 0))
        try:
            for name, value in values.items():
                self.bus.write(servo_id, *_register(name, value))
        finally:
            self.bus.write(servo_id, *_register("lock", 1))

    def _write_calibration(self, calibration: dict[str, JointCalibration]) -> None:
        """Into the servos' EEPROM, as LeRobot's write_calibration does (torque off first)."""
        with self._lock:
            self.torque(False)
            for c in calibration.values():
                self._write_eeprom(c.id, {"homing_offset": c.homing_offset, "min_position_limit": c.range_min,
                                          "max_position_limit": c.range_max})

    # ------------------------------------------------------------------ reading
    def _states(self) -> dict[int, tuple[int, int, int]]:
        """{id: (present position, moving, error byte)} of every servo, one SYNC_READ."""
        answers = self.bus.sync_read(list(SO101_IDS.values()), _STATE_START, _STATE_SIZE)
        states = {}
        for servo_id, (data, error) in answers.items():
            position = decode(REGISTERS["present_position"], data[0:2])
            states[servo_id] = (position, data[66 - _STATE_START], error)
        return states

    def read_steps(self) -> dict[str, int]:
        """Every servo's present position (steps), one SYNC_READ (the fast path for teaching)."""
        with self._lock:
            try:
                answers = self.bus.sync_read(list(SO101_IDS.values()), REGISTERS["present_position"].address, 2)
            except SO101Error as error:
                raise self._fault(error) from error
        return {_NAMES[i]: decode(REGISTERS["present_position"], data) for i, (data, _) in answers.items()}

    def _calibrated(self) -> None:
        if self.calibration is None:
            raise CalibrationError("the arm is not calibrated: run lerobot-calibrate and give its file as "
                                   "SO101(port, calibration=...), or call calibrate()")

    def positions(self) -> dict[str, float]:
        """Every joint's angle (rad), the gripper's included."""
        self._calibrated()
        return {joint: self.calibration[joint].to_radians(steps) for joint, steps in self.read_steps().items()}

    def tool_point(self) -> tuple[float, float, float]:
        """Where the gripper frame is (m, base frame)."""
        q = self.positions()
        return tuple(float(v) for v in self.kinematics.tool_point([q[j] for j in ARM_JOINTS]))

    def follow_by_hand(self, seconds: float, rate: float = 50.0, into: list | None = None,
                       on_sample: Callable[[float, dict[str, float]], None] | None = None) -> list:
        """Torque off, then read the joints ``rate`` times a second for ``seconds`` while a person
        moves the arm: [(seconds since start, {joint: rad})]. The samples go into ``into`` as they
        come, so a fault (raised) loses none of them."""
        if not (isinstance(seconds, (int, float)) and not isinstance(seconds, bool) and 0 < seconds < 3600):
            raise ValueError(f"seconds: expected a duration in (0, 3600) s, got {seconds!r}")
        if not (isinstance(rate, (int, float)) and not isinstance(rate, bool) and 0 < rate <= 1000):
            raise ValueError(f"rate: expected readings a second in (0, 1000], got {rate!r}")
        samples = into if into is not None else []
        self.torque(False)
        start = time.monotonic()
        while time.monotonic() - start <= seconds:
            sample = (time.monotonic() - start, self.positions())
            samples.append(sample)
            if on_sample is not None:
                on_sample(*sample)
            # The next tick of the clock start + k / rate; a tick missed is skipped, not caught up.
            elapsed = time.monotonic() - start
            time.sleep(max(0.0, (math.floor(elapsed * rate) + 1) / rate - elapsed))
        return samples

    # ------------------------------------------------------------------ torque
    def torque(self, on: bool) -> None:
        """Torque on (the servos hold, then move) or off (the arm is free to move by hand; it
        falls under its weight if nobody holds it)."""
        if not isinstance(on, bool):
            raise ValueError(f"on: expected a bool, got {on!r}")
        with self._lock:
            try:
                self.bus.sync_write(REGISTERS["torque_enable"].address,
                                    {i: bytes((int(on),)) for i in SO101_IDS.values()})
                # SYNC_WRITE has no answer: read back that every servo took it.
                answers = self.bus.sync_read(list(SO101_IDS.values()), REGISTERS["torque_enable"].address, 1)
            except SO101Error as error:
                raise self._fault(error) from error
            refused = [_NAMES[i] for i, (data, _) in answers.items() if data[0] != int(on)]
            if refused:
                raise self._fault(SO101Error(f"the servos {refused} did not turn their torque {'on' if on else 'off'}"))

    # ------------------------------------------------------------------ moves
    def _check_ready(self) -> None:
        """Every servo has its torque on and reports no error, or nothing is sent."""
        try:
            answers = self.bus.sync_read(list(SO101_IDS.values()), REGISTERS["torque_enable"].address, 1)
        except SO101Error as error:
            raise self._fault(error) from error
        for servo_id, (_, error) in answers.items():
            if error:
                raise self._fault(ServoFault(f"the {_NAMES[servo_id]} servo (id {servo_id}) cannot move: "
                                             f"{describe(error)}", servo_id=servo_id, error=error))
        off = [_NAMES[i] for i, (data, _) in answers.items() if data[0] != 1]
        if off:
            raise SO101Error(f"the torque is off on {', '.join(off)}: call torque(True) first (the arm then "
                             f"holds where it is), so nobody's hand is surprised by a move")

    def move_joints(self, goal: dict[str, float], speed: float = 0.5, acceleration: float = 2.0,
                    wait: bool = True, timeout: float = 30.0) -> None:
        """Move the joints named in ``goal`` to their angles (rad), the others staying.

        Args:
            speed: the fastest joint's speed (rad/s); the others are slowed to arrive with it.
            acceleration: the fastest joint's acceleration (rad/s^2).
            wait: return when the arm has arrived (watching every servo for faults).
        """
        if not isinstance(goal, dict) or not goal:
            raise ValueError(f"goal: expected a non-empty dict of joint angles (rad), got {goal!r}")
        if not isinstance(wait, bool):
            raise ValueError(f"wait: expected a bool, got {wait!r}")
        self._calibrated()
        self.envelope.check_speed(speed, acceleration)
        self.envelope.check_joints(goal)
        with self._lock:
            if self._stopped.is_set():
                raise SO101Stopped("the arm is stopped: call resume() before moving it")
            self._check_ready()
            current = self.positions()
            full = {**current, **{j: float(v) for j, v in goal.items()}}
            moving = list(goal)
            if any(j in goal for j in ARM_JOINTS):
                self.envelope.check_path(current, full)
                # A new move replaces the last one whole: the joints not named stop where they
                # are, so the arm follows the line checked, whatever it was doing.
                moving = list(dict.fromkeys([*ARM_JOINTS, *goal]))
            steps = {j: self.calibration[j].to_steps(full[j]) for j in moving}
            travel = {j: abs(steps[j] - self.calibration[j].to_steps(current[j])) for j in moving}
            longest = max(travel.values()) or 1
            blocks = {}
            for j, target in steps.items():
                share = travel[j] / longest
                joint_speed = max(1, round(speed * _STEPS_PER_RAD * share))
                joint_acceleration = max(1, min(254, round(acceleration * _STEPS_PER_RAD * share / 100)))
                blocks[SO101_IDS[j]] = (encode(REGISTERS["acceleration"], joint_acceleration)
                                        + encode(REGISTERS["goal_position"], target)
                                        + encode(REGISTERS["goal_time"], 0)
                                        + encode(REGISTERS["goal_speed"], joint_speed))
            try:
                self.bus.sync_write(REGISTERS["acceleration"].address, blocks)
            except SO101Error as error:
                raise self._fault(error) from error
        if wait:
            self._wait_arrival(timeout)

    def move_to(self, x: float, y: float, z: float, speed: float = 0.5, acceleration: float = 2.0,
                wait: bool = True) -> None:
        """Move the gripper frame to (x, y, z) (m, base frame) by a joint move."""
        target = []
        for name, value in (("x", x), ("y", y), ("z", z)):
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)):
                raise ValueError(f"{name}: expected a finite number of metres, got {value!r}")
            target.append(float(value))
        self._calibrated()
        floor = self.envelope.table_height + self.envelope.clearance
        if target[2] < floor:
            raise UnsafeMoveError(f"z {target[2]:.3f} m is below the table's {floor:.3f} m", coordinate="z",
                                  value=target[2], limit=floor)
        current = self.positions()
        q = self.kinematics.solve(target, [current[j] for j in ARM_JOINTS])
        if q is None:
            raise UnsafeMoveError(f"({x:.3f}, {y:.3f}, {z:.3f}) m is out of the arm's reach", coordinate="reach",
                                  value=float(math.dist(target, (0.0, 0.0, 0.0))), limit=None)
        self.move_joints(dict(zip(ARM_JOINTS, (float(v) for v in q))), speed, acceleration, wait)

    def gripper(self, opening: float, speed: float = 0.5, wait: bool = True) -> None:
        """Move the gripper's jaw to ``opening`` (rad, the gripper joint's angle)."""
        self.move_joints({GRIPPER: opening}, speed=speed, wait=wait)

    def _wait_arrival(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while True:
            with self._lock:
                if self._stopped.is_set():
                    raise SO101Stopped("the move was cut short by stop(): the arm holds where it is")
                try:
                    states = self._states()
                except SO101Error as error:
                    raise self._fault(error) from error
                faulty = {i: e for i, (_, _, e) in states.items() if e}
                if faulty:
                    servo_id, error = next(iter(faulty.items()))
                    raise self._fault(ServoFault(f"the {_NAMES[servo_id]} servo (id {servo_id}) stopped the move: "
                                                 f"{describe(error)}", servo_id=servo_id, error=error))
                if not any(moving for _, moving, _ in states.values()):
                    return
            if time.monotonic() > deadline:
                raise self._fault(SO101Error(f"the arm did not arrive within {timeout} s"))
            time.sleep(0.005)

    # ------------------------------------------------------------------ stop and faults
    def _hold(self) -> str:
        """Every servo that answers holds where it is; say what was done."""
        try:
            blocks = {}
            for servo_id in SO101_IDS.values():
                try:
                    data, _ = self.bus.read(servo_id, REGISTERS["present_position"].address, 2)
                except (ServoNotAnswering, CorruptReply):
                    continue
                blocks[servo_id] = data
            if blocks:
                self.bus.sync_write(REGISTERS["goal_position"].address, blocks)
            return "the arm holds where it is" if len(blocks) == len(SO101_IDS) else \
                "the servos that still answer hold where they are"
        except BusDisconnected:
            return "the computer can no longer reach the arm: its servos keep their last goal; switch its power off " \
                   "if it still moves"

    def _fault(self, error: SO101Error) -> SO101Error:
        """Stop the arm after ``error``, note it, and return the error to raise, in words."""
        if isinstance(error, BusDisconnected):
            message = f"{error} The arm's servos keep their last goal; switch its power off if it still moves."
            result: SO101Error = BusDisconnected(message)
        else:
            held = self._hold()
            if isinstance(error, ServoNotAnswering):
                name = _NAMES.get(error.servo_id, "?")
                message = (f"the {name} servo (id {error.servo_id}) stopped answering: check the cable into it and "
                           f"the arm's power supply; {held}.")
                result = ServoNotAnswering(message, servo_id=error.servo_id)
            elif isinstance(error, CorruptReply):
                name = _NAMES.get(error.servo_id, "?")
                message = (f"the {name} servo's (id {error.servo_id}) answers arrive damaged: check the cable into it; "
                           f"{held}.")
                result = CorruptReply(message, servo_id=error.servo_id)
            elif isinstance(error, ServoFault):
                message = f"{error}; {held}."
                result = ServoFault(message, servo_id=error.servo_id, error=error.error)
            else:
                message = f"{error}; {held}."
                result = type(error)(message) if type(error) is SO101Error else error
        self.faults.append((time.time(), message))
        return result

    def stop(self) -> None:
        """Emergency stop: every servo holds where it is, now, and no move is sent until
        :meth:`resume`. Safe from any thread."""
        self._stopped.set()
        with self._lock:
            self._hold()

    def resume(self) -> None:
        """Allow moves again after :meth:`stop`."""
        self._stopped.clear()

    @property
    def stopped(self) -> bool:
        return self._stopped.is_set()

    # ------------------------------------------------------------------ calibration of its own
    def calibrate(self, path, seconds: float = 15.0, rate: float = 50.0) -> dict[str, JointCalibration]:
        """Calibrate as ``lerobot-calibrate`` does, for an arm without a calibration.

        Before the call, put the arm by hand in the middle of its range (LeRobot's picture:
        upper arm up, forearm forward, gripper closed). The call takes that pose as the middle
        of every joint (present position 2047), then for ``seconds`` reads the joints while you
        move each one slowly through its whole range; the wrist roll turns all the way round, so
        its range is the whole turn. The result goes into the servos' EEPROM and, in LeRobot's
        format, into ``path``.
        """
        with self._lock:
            self.torque(False)
            middle = {}
            for name, servo_id in SO101_IDS.items():
                # Present position with the old offset, plus the old offset: the raw position.
                raw = self._read_register(servo_id, "present_position") + self._read_register(servo_id, "homing_offset")
                middle[name] = (raw % STEPS_PER_TURN) - (STEPS_PER_TURN - 1) // 2
                self._write_eeprom(servo_id, {"homing_offset": middle[name], "min_position_limit": 0,
                                              "max_position_limit": STEPS_PER_TURN - 1})
        low = dict.fromkeys(SO101_IDS, STEPS_PER_TURN)
        high = dict.fromkeys(SO101_IDS, -1)
        start = time.monotonic()
        while time.monotonic() - start < seconds:
            for joint, steps in self.read_steps().items():
                low[joint], high[joint] = min(low[joint], steps), max(high[joint], steps)
            time.sleep(1.0 / rate)
        calibration = {}
        for joint, servo_id in SO101_IDS.items():
            if joint == "wrist_roll":
                low[joint], high[joint] = 0, STEPS_PER_TURN - 1
            if high[joint] <= low[joint]:
                raise CalibrationError(f"calibrate: {joint} did not move: move every joint through its range "
                                       f"during the {seconds} s")
            calibration[joint] = JointCalibration(servo_id, 0, middle[joint], low[joint], high[joint])
        self._write_calibration(calibration)
        write_calibration(path, calibration)
        self._set_calibration(calibration)
        return calibration
