"""The simulated SO-101's bus: six STS3215 servos on one half-duplex serial line at 1 Mbit/s.

Host side, as :class:`mt_widgets.hardware.simdevice.SimulatedSwiftPro` has it: :meth:`write`
takes the host's bytes at ``now``, :meth:`read_available` gives the bytes due by ``now``,
:meth:`next_due` says when the next ones are due. The pseudo-terminal server
(:mod:`.sim_pty`) drives it with ``time.monotonic``, so any client (this suite's
:class:`~mt_widgets.hardware.feetech.bus.FeetechBus`, the SDK's ``PortHandler`` and
``PacketHandler``, LeRobot's ``FeetechMotorsBus``) talks to it through a real serial device.

Timing: a byte takes 10 us on the wire (8N1 at 1 Mbit/s). A servo starts its answer
``return_delay`` x 2 us after the instruction's last byte has arrived and after the line is
free (answers of a sync read follow each other on the one wire); the answer is delivered
when its last byte is through.

Faults (what goes wrong on a real arm): :meth:`silence` (a servo stops answering: a loose
connector between two servos), :meth:`corrupt_next_reply` (noise flips a byte of an answer),
:meth:`overload` (a joint blocked: the servo drops torque, error bit 0x20), :meth:`voltage_drop`
(the supply sags: error bit 0x01), :meth:`pull_cable` (the USB cable is pulled: the port closes).
"""

from __future__ import annotations

import heapq
import threading
from dataclasses import dataclass, field

from .arm import SO101_IDS
from .control_table import BAUD
from .packet import BROADCAST_ID, Instruction, Packet, split_packets, status_packet
from .sim_servo import SimulatedServo

#: Seconds a byte takes on the wire.
BYTE_TIME = 10.0 / BAUD

#: The simulated arm's calibration, as ``lerobot-calibrate`` writes it (a real arm's order of
#: magnitude): what :func:`calibrated_bus` flashes into the servos, as LeRobot leaves them.
SIMULATED_CALIBRATION = {
    "shoulder_pan": {"id": 1, "drive_mode": 0, "homing_offset": -1470, "range_min": 760, "range_max": 3330},
    "shoulder_lift": {"id": 2, "drive_mode": 0, "homing_offset": 120, "range_min": 900, "range_max": 3200},
    "elbow_flex": {"id": 3, "drive_mode": 0, "homing_offset": 300, "range_min": 950, "range_max": 3150},
    "wrist_flex": {"id": 4, "drive_mode": 0, "homing_offset": -50, "range_min": 950, "range_max": 3150},
    "wrist_roll": {"id": 5, "drive_mode": 0, "homing_offset": 1000, "range_min": 0, "range_max": 4095},
    "gripper": {"id": 6, "drive_mode": 0, "homing_offset": 700, "range_min": 2000, "range_max": 3400},
}


@dataclass
class SimulatedBus:
    """Servos on one simulated bus.

    Args:
        servos: the servos, by id (default: the SO-101's six STS3215 at mid-turn).
        speed_scale: passed to the default servos (tests use 10: moves ten times shorter).
    """

    servos: dict[int, SimulatedServo] | None = None
    speed_scale: float = 1.0
    #: Every valid instruction packet received (for tests).
    received: list[Packet] = field(default_factory=list)
    disconnected: bool = False

    def __post_init__(self):
        if self.servos is None:
            self.servos = {i: SimulatedServo(i, speed_scale=self.speed_scale) for i in SO101_IDS.values()}
        self.lock = threading.RLock()
        self._inbuf = b""
        self._out: list[tuple[float, int, bytes]] = []
        self._seq = 0
        self._wire_free = 0.0
        self._silent: set[int] = set()
        self._corrupt = 0
        self._pending: dict[int, tuple[int, bytes]] = {}

    # ------------------------------------------------------------------ host side
    def write(self, data: bytes, now: float) -> None:
        """Bytes from the host, all sent at ``now``."""
        with self.lock:
            if self.disconnected:
                return
            self._inbuf += bytes(data)
            packets, self._inbuf = split_packets(self._inbuf)
            # The instruction's last byte is on the wire len(data) byte-times after the host sent it.
            arrived = max(now, self._wire_free) + len(data) * BYTE_TIME
            self._wire_free = arrived
            for packet in packets:
                if packet.valid:   # a servo ignores a packet whose checksum fails
                    self.received.append(packet)
                    self._dispatch(packet, arrived)

    def read_available(self, now: float) -> bytes:
        """Every byte the servos have sent by ``now``."""
        with self.lock:
            chunks = []
            while self._out and self._out[0][0] <= now:
                chunks.append(heapq.heappop(self._out)[2])
            return b"".join(chunks)

    def next_due(self, now: float) -> float | None:
        """When the next bytes are due, or None."""
        with self.lock:
            return self._out[0][0] if self._out else None

    # ------------------------------------------------------------------ the servos' side
    def _answer(self, servo: SimulatedServo, parameters: bytes, now: float) -> None:
        if servo.servo_id in self._silent:
            return
        packet = status_packet(servo.servo_id, servo.error, parameters)
        if self._corrupt:
            self._corrupt -= 1
            packet = packet[:-1] + bytes((packet[-1] ^ 0x5A,))
        start = max(now + servo.value("return_delay") * 2e-6, self._wire_free)
        self._wire_free = start + len(packet) * BYTE_TIME
        self._seq += 1
        heapq.heappush(self._out, (self._wire_free, self._seq, packet))

    def _dispatch(self, packet: Packet, now: float) -> None:
        targets = list(self.servos.values()) if packet.servo_id == BROADCAST_ID else (
            [self.servos[packet.servo_id]] if packet.servo_id in self.servos else [])
        answer = packet.servo_id != BROADCAST_ID
        p = packet.parameters
        code = packet.code
        if code == Instruction.PING:
            for servo in targets:
                if answer:
                    self._answer(servo, b"", now)
        elif code == Instruction.READ and len(p) == 2:
            for servo in targets:
                if answer:
                    self._answer(servo, servo.read(p[0], p[1], now), now)
        elif code in (Instruction.WRITE, Instruction.REG_WRITE) and len(p) >= 2:
            for servo in targets:
                if servo.servo_id in self._silent:
                    continue
                if code == Instruction.WRITE:
                    servo.write(p[0], p[1:], now)
                else:
                    self._pending[servo.servo_id] = (p[0], p[1:])
                if answer:
                    self._answer(servo, b"", now)
        elif code == Instruction.ACTION:
            for servo in targets:
                if servo.servo_id in self._pending and servo.servo_id not in self._silent:
                    address, data = self._pending.pop(servo.servo_id)
                    servo.write(address, data, now)
                if answer:
                    self._answer(servo, b"", now)
        elif code == Instruction.SYNC_READ and len(p) >= 2:
            address, size = p[0], p[1]
            for servo_id in p[2:]:
                servo = self.servos.get(servo_id)
                if servo is not None:
                    self._answer(servo, servo.read(address, size, now), now)
        elif code == Instruction.SYNC_WRITE and len(p) >= 2:
            address, size = p[0], p[1]
            block = size + 1
            for k in range(2, len(p) - block + 1, block):
                servo = self.servos.get(p[k])
                if servo is not None and servo.servo_id not in self._silent:
                    servo.write(address, p[k + 1:k + block], now)

    # ------------------------------------------------------------------ a hand
    def hand_move(self, positions: dict[int, int], now: float) -> bool:
        """A hand moves joints to ``positions`` (id -> present-frame steps); True if all gave way."""
        with self.lock:
            return all([self.servos[i].hand_move(v, now) for i, v in positions.items()])

    def present_positions(self, now: float) -> dict[int, int]:
        """Where each shaft is at ``now`` (present frame), without going through the wire."""
        with self.lock:
            for servo in self.servos.values():
                servo.advance(now)
            return {i: servo.value("present_position") for i, servo in self.servos.items()}

    # ------------------------------------------------------------------ faults
    def silence(self, servo_id: int) -> None:
        """Servo ``servo_id`` stops answering and obeying (its cable came loose)."""
        with self.lock:
            self._silent.add(servo_id)

    def corrupt_next_reply(self, count: int = 1) -> None:
        """The next ``count`` answers arrive with a wrong checksum."""
        with self.lock:
            self._corrupt += int(count)

    def overload(self, servo_id: int, now: float) -> None:
        """Servo ``servo_id`` is blocked: it drops its torque and reports an overload."""
        with self.lock:
            self.servos[servo_id].overload(now)

    def voltage_drop(self, volts: float, now: float) -> None:
        """The supply falls to ``volts`` for every servo."""
        with self.lock:
            for servo in self.servos.values():
                servo.advance(now)
                servo.voltage = float(volts)
                servo._refresh()

    def pull_cable(self) -> None:
        """The USB cable is pulled: nothing more is heard; the port closes."""
        with self.lock:
            self.disconnected = True
            self._out.clear()


def calibrated_bus(speed_scale: float = 1.0, calibration=None) -> SimulatedBus:
    """Six servos with ``calibration`` (default :data:`SIMULATED_CALIBRATION`) in their EEPROM, as
    LeRobot leaves a calibrated arm, each at the middle of its range, powered on with torque off.

    Args:
        speed_scale: as for :class:`SimulatedBus` (1: the STS3215's own speed).
        calibration: {joint: {"id", "drive_mode", "homing_offset", "range_min", "range_max"}}.
    """
    calibration = SIMULATED_CALIBRATION if calibration is None else calibration
    bus = SimulatedBus(speed_scale=speed_scale)
    for joint, servo_id in SO101_IDS.items():
        servo = bus.servos[servo_id]
        c = calibration[joint]
        servo.flash("homing_offset", c["homing_offset"])
        servo.flash("min_position_limit", c["range_min"])
        servo.flash("max_position_limit", c["range_max"])
        servo.position = (c["range_min"] + c["range_max"]) / 2 + c["homing_offset"]
        servo.power_on(0.0)
    return bus
