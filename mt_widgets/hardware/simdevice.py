"""A simulated uArm Swift Pro: the device model, pure Python, no serial port.

It answers every command of the firmware's command table, for the 4.x profile (grbl-based,
default) and the 3.x profile (Marlin-based), in their formats and with their faults, as
``docs/uarm-protocol.md`` ("The command table" and "What the simulated device does")
describes. Time is passed in explicitly (``now``, seconds on any monotonic clock), so the
model is deterministic; the pyserial adapter
(:mod:`mt_widgets.hardware.urlhandler.protocol_uarmsim`) and the pseudo-terminal test server
drive it with ``time.monotonic``.

Host side: :meth:`SimulatedSwiftPro.write` takes bytes from the host,
:meth:`SimulatedSwiftPro.read_available` gives the bytes due by ``now``, and
:meth:`SimulatedSwiftPro.next_due` says when something will next happen. A person's hand is
simulated by :meth:`SimulatedSwiftPro.hand_move`: it moves the tool only while the three
steppers are released, as on the real arm.

This module is the device: its settings, its state, the host's and the hand's side of it,
and the faults tests inject. The rest is in modules of one concern each, which the device
composes: the arm's geometry and reach (sim_kinematics.py), how each firmware reads numbers
(sim_grammar.py), the firmware's clock, output and input dispatch (sim_firmware.py), the
commands both firmwares know (sim_commands.py), the EEPROM (sim_eeprom.py), and each
firmware's own line reader, moves and commands (sim_commands_4x.py, sim_commands_3x.py).

Approximations, on purpose: moves are straight lines at constant speed (4.x G0 is
joint-space on the real arm, and acceleration, M204, is stored but not simulated);
reachability and the coordinate conversions follow the 4.x rule for the suction mode in
every mode and in both profiles (see :func:`~mt_widgets.hardware.sim_kinematics.is_reachable`);
the queued 4.x commands run one after the other (the firmware plans the next one while the
current one moves, which only changes when a query queued behind a move is evaluated).
"""

from __future__ import annotations

import dataclasses
import heapq
import math
import random
import re
import threading
from collections import deque
from dataclasses import dataclass, field

from .sim_commands import SharedCommands
from .sim_commands_3x import Commands3x
from .sim_commands_4x import QUEUE_SIZE, Commands4x
from .sim_eeprom import Eeprom
from .sim_firmware import Command, FirmwareLoop, Motion
from .sim_grammar import grbl_read_float, marlin_float, marlin_int, scan4
from .sim_kinematics import (
    BASE_LIMIT_DEG,
    BETWEEN_ARMS_LIMITS_DEG,
    EFFECTOR_FRONT_MM,
    EFFECTOR_HEIGHT_MM,
    LOWER_ARM_LIMITS_DEG,
    LOWER_ARM_MM,
    SHOULDER_HEIGHT_MM,
    SHOULDER_OFFSET_MM,
    STEPPERS,
    UPPER_ARM_LIMITS_DEG,
    UPPER_ARM_MM,
    angles_legal,
    is_reachable,
    joint_angles,
    reachable_towards,
    tool_position,
)

# The names this module has always offered: the device, and (from the modules it is made of)
# the geometry, the reach and the number grammars.
__all__ = [
    "BASE_LIMIT_DEG", "BETWEEN_ARMS_LIMITS_DEG", "EFFECTOR_FRONT_MM", "EFFECTOR_HEIGHT_MM", "LOWER_ARM_LIMITS_DEG",
    "LOWER_ARM_MM", "QUEUE_SIZE", "SHOULDER_HEIGHT_MM", "SHOULDER_OFFSET_MM", "UPPER_ARM_LIMITS_DEG", "UPPER_ARM_MM",
    "SimulatedSwiftPro", "angles_legal", "grbl_read_float", "is_reachable", "joint_angles", "marlin_float",
    "marlin_int", "scan4", "tool_position",
]

_REALTIME = frozenset(b"?!~@\x18")


@dataclass
class _Profile:
    firmware: str
    hardware: str
    api: str
    newline: bytes
    decimals: int


_PROFILES = {
    # 4.x: uart_printf lines end in "\n" (boot lines in "\r\n"); dtostrf(v, 5, 4): 4 decimals.
    4: _Profile("V4.10.0", "V3.3.1", "V4.0.5", b"\n", 4),
    # 3.x: Marlin's println ends in "\r\n"; msprintf's %f is dtostrf(v, 4, 2): 2 decimals.
    3: _Profile("V3.2.0", "V3.3.1", "V3.2.0", b"\r\n", 2),
}


@dataclass
class SimulatedSwiftPro(FirmwareLoop, Commands4x, Commands3x, SharedCommands, Eeprom):
    """The simulated arm.

    Args:
        firmware: 4 (grbl-based, default) or 3 (Marlin-based).
        version: the firmware version P2203 reports, ``"4.2"`` or ``"4.2.0"`` (default 4.10.0
            on 4.x, 3.2.0 on 3.x); its major number must be ``firmware``. Before 4.5 there is
            no ``S1100`` (E20): ``S1000 V0`` pauses, the cut move stays at the head of the
            queue, every G/M command queues behind it unanswered, and ``S1000 V1`` carries
            the cut move on to its target before anything queued after it.
        boot_delay: seconds from power-on to the banner; input before it is dropped.
        latency: seconds added to every line the arm sends.
        motion_scale: factor on move durations (1 = distance / speed; tests use 0.01).
        chatter: if set, seconds between random unsolicited ``@3/@5/@6/@9`` lines.
        baud: if set, each sent line also takes its time on the wire (10 bits a byte).
        device_name: what P2201 answers (``"Swift"`` makes a non-Pro arm).
        start: tool position at power-on, mm.
        seed: seed of the chatter's random choices.
    """

    firmware: int = 4
    version: str | None = None
    boot_delay: float = 0.3
    latency: float = 0.0
    motion_scale: float = 1.0
    chatter: float | None = None
    baud: float | None = None
    device_name: str = "SwiftPro"
    start: tuple[float, float, float] = (200.0, 0.0, 100.0)
    seed: int = 0
    # What the host sent, for tests: complete lines, and real-time bytes 4.x swallowed.
    received_lines: list[str] = field(default_factory=list)
    realtime_received: bytearray = field(default_factory=bytearray)
    beeps: list[tuple[float, float]] = field(default_factory=list)
    disconnected: bool = False

    def __post_init__(self):
        if self.firmware not in _PROFILES:
            raise ValueError(f"firmware: expected 3 or 4, got {self.firmware!r}")
        for name in ("boot_delay", "latency", "motion_scale"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0 (seconds), got {v!r}")
        if self.chatter is not None and not self.chatter > 0:
            raise ValueError(f"chatter: expected None or a number > 0 of seconds, got {self.chatter!r}")
        self.lock = threading.RLock()
        self._profile = _PROFILES[self.firmware]
        if self.version is not None:
            parts = str(self.version).lstrip("vV").split(".")
            if not (1 <= len(parts) <= 3 and all(p.isdigit() for p in parts) and int(parts[0]) == self.firmware):
                raise ValueError(f"version: expected {self.firmware}.2 or {self.firmware}.2.0 (major = firmware "
                                 f"= {self.firmware}), got {self.version!r}")
            numbers = tuple(int(p) for p in parts) + (0,) * (3 - len(parts))
            self._profile = dataclasses.replace(self._profile, firmware="V" + ".".join(map(str, numbers)))
        self.version_tuple = tuple(int(p) for p in self._profile.firmware[1:].split("."))
        self._rng = random.Random(self.seed)
        self._drop_replies = 0
        self._drop_line: int | None = None
        self._disconnect_after: int | None = None
        self.powered = False
        # Non-volatile: the EEPROM (blank = 0xFF) and the serial number survive a power cycle.
        self._eeprom: dict[int, bytearray] = {}
        self.uid = "".join(f"{self._rng.randrange(256):02X}" for _ in range(6))
        self.hand_refusals = 0
        self._handlers = self._table_4x() if self.firmware == 4 else self._table_3x()

    # ------------------------------------------------------------------ host interface
    def power_on(self, now: float) -> None:
        """(Re)start the arm, as opening the port does through DTR: state is reset and the
        banner comes after ``boot_delay``."""
        with self.lock:
            self.powered = True
            self.disconnected = False
            self._boot_end = now + self.boot_delay
            self._booted = False
            self._out: list[tuple[float, int, bytes]] = []
            self._seq = 0
            self._wire_free = now
            self._inbuf = b""
            self._lines_since_boot = 0
            self._queue: deque[Command] = deque()
            self._sync_waiters: list[Command] = []
            self._motion: Motion | None = None
            self._hand: Motion | None = None
            self._t_free = now
            self._paused = False
            self._pos = tuple(float(v) for v in self.start)
            self._last_target = self._pos   # 4.x target_step / 3.x current_position
            self._speed_set: float | None = None
            self._bits = 0x0F              # 4.x motor_state_bits
            self._enabled = set(STEPPERS)  # stepper drivers enabled (physical)
            self._servo_attached = True
            self._wrist = 90.0
            self._mode = 0
            self._report_interval: float | None = None
            self._next_report = math.inf
            self._report_stop = False
            self._next_chatter = math.inf  # set when the banner is out
            self._pump = 0
            self._gripper = 0
            self._laser = 0
            self._pins_out: dict[int, int] = {}
            self._pins_mode: dict[int, str] = {}
            self._acceleration: float | None = None
            self._offsets = {"height": None, "front": None, "effect_angle": None}
            self._flags = {"position_check": False, "beep": True, "keys": False, "bluetooth": True}
            self._relative = False          # 3.x G90/G91
            self._joint_offset = [0.0, 0.0, 0.0]  # 3.x: measured minus believed joint angles
            self._serial_moved = False      # 3.x M2500 moves the command port to Serial2
            self._grove: dict[int, int] = {}  # 3.x: port -> Grove module type initialised
            self.bt_name = "uArm"

    def write(self, data: bytes, now: float) -> None:
        """Bytes from the host arriving at ``now``."""
        with self.lock:
            if not self.powered:
                self.power_on(now)
            self._advance(now)
            if self.disconnected:
                return
            if self.firmware == 4:
                # grbl's serial interrupt takes these as real-time commands (docs/uarm-protocol.md "Link").
                self.realtime_received.extend(b for b in data if b in _REALTIME)
                data = bytes(b for b in data if b not in _REALTIME)
            if now < self._boot_end:
                return  # the board is still resetting: input is lost
            self._inbuf += data
            while True:
                m = re.search(rb"[\r\n]", self._inbuf)
                if not m:
                    break
                raw, self._inbuf = self._inbuf[: m.start()], self._inbuf[m.end():]
                self._line(raw.decode("ascii", "replace"), now)
                if self.disconnected:
                    return

    def read_available(self, now: float) -> bytes:
        """Everything the arm has sent by ``now``."""
        with self.lock:
            if not self.powered:
                return b""
            self._advance(now)
            chunks = []
            while self._out and self._out[0][0] <= now:
                chunks.append(heapq.heappop(self._out)[2])
            return b"".join(chunks)

    def next_due(self, now: float) -> float | None:
        """The next time (on the clock of ``now``) something may be sent, or None."""
        with self.lock:
            if not self.powered:
                return None
            self._advance(now)
            times = [self._out[0][0]] if self._out else []
            times.append(self._next_internal())
            t = min(times)
            return None if math.isinf(t) else t

    # ------------------------------------------------------------------ a person's hand
    def hand_move(self, target: tuple[float, float, float], now: float, duration: float = 1.0) -> bool:
        """A person moves the tool by hand towards ``target`` (mm) over ``duration`` seconds.

        The hand moves the arm only while all three steppers are released (M2019, M2202
        N0..N2): a powered stepper holds its joint. The tool stops where a joint reaches its
        limit; re-attaching a stepper stops the hand where it is.

        Returns:
            Whether the arm gave way (False: a stepper held it, counted in ``hand_refusals``).
        """
        if not (isinstance(duration, (int, float)) and math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration: expected a finite number >= 0 of seconds, got {duration!r}")
        target = tuple(float(v) for v in target)
        if len(target) != 3 or not all(math.isfinite(v) for v in target):
            raise ValueError(f"target: expected three finite numbers (x, y, z mm), got {target!r}")
        with self.lock:
            if not self.powered:
                self.power_on(now)
            self._advance(now)
            if self._enabled or self._motion is not None:
                self.hand_refusals += 1
                return False
            start = self._actual(now)
            end = reachable_towards(start, target)
            self._hand = Motion(None, start, end, now, now + duration)
            return True

    def hand_is_moving(self, t: float) -> bool:
        """Whether a hand move is under way at ``t``."""
        with self.lock:
            return self._hand is not None and self._hand.t0 <= t < self._hand.t1

    # ------------------------------------------------------------------ faults
    def drop_next_reply(self, count: int = 1) -> None:
        """Lose the replies to the next ``count`` command lines (they are never sent)."""
        with self.lock:
            self._drop_replies += int(count)

    def drop_reply_to_line(self, nth: int) -> None:
        """Lose the reply to the ``nth`` command line received since power-on (1-based)."""
        with self.lock:
            self._drop_line = int(nth)

    def disconnect_on_command(self, nth: int = 1) -> None:
        """Close the port when the ``nth`` next command line arrives, before answering it."""
        with self.lock:
            self._disconnect_after = int(nth)

    def pull_cable(self) -> None:
        """The USB cable is pulled now: the port closes; the arm keeps its state (a
        released arm stays released, so a hand move can go on)."""
        with self.lock:
            self.disconnected = True

    def moving_at(self, t: float) -> bool:
        """Whether the tool is moving under power at ``t`` (for tests that wait for a move)."""
        with self.lock:
            self._advance(t)
            return self._motion is not None and self._motion.t0 <= t < self._motion.t1

    def position_at(self, t: float) -> tuple[float, float, float]:
        """Where the tool is at ``t`` (encoder truth, whatever the profile reports)."""
        with self.lock:
            self._advance(t)
            return self._actual(t)

    def steppers_released(self) -> bool:
        """Whether all three steppers are released (the hand can move the arm)."""
        with self.lock:
            return not self._enabled
