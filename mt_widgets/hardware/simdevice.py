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

Approximations, on purpose: moves are straight lines at constant speed (4.x G0 is
joint-space on the real arm, and acceleration, M204, is stored but not simulated);
reachability and the coordinate conversions follow the 4.x rule for the suction mode in
every mode and in both profiles (see :func:`is_reachable`); the queued 4.x commands run one
after the other (the firmware plans the next one while the current one moves, which only
changes when a query queued behind a move is evaluated).
"""

from __future__ import annotations

import dataclasses
import heapq
import math
import random
import re
import struct
import threading
from collections import deque
from dataclasses import dataclass, field

# 4.x firmware geometry, docs/uarm-protocol.md "Frame and workspace" (mm, degrees).
LOWER_ARM_MM = 142.07
UPPER_ARM_MM = 158.81
SHOULDER_OFFSET_MM = 13.2
SHOULDER_HEIGHT_MM = 107.4
#: Suction-cup offsets of mode 0 (4.x): the tool point is this far in front of and below the wrist.
EFFECTOR_FRONT_MM = 56.65
EFFECTOR_HEIGHT_MM = 74.55
LOWER_ARM_LIMITS_DEG = (-4.0, 135.6)
UPPER_ARM_LIMITS_DEG = (-4.0, 119.9)
BETWEEN_ARMS_LIMITS_DEG = (10.0, 151.0)
BASE_LIMIT_DEG = 90.0

#: 4.x queues this many G/M commands; the next one gets a bare ``E23 buffer full``.
QUEUE_SIZE = 20

_REALTIME = frozenset(b"?!~@\x18")
#: EEPROM size the simulated store has per device (4.x accepts addresses up to 65524).
_EEPROM_BYTES = 65536


def joint_angles(x: float, y: float, z: float) -> tuple[float, float, float, float] | None:
    """Joint angles of the 4.x arm for a tool position, or None if no triangle exists.

    Args:
        x, y, z: tool position in mm (arm frame, suction mode offsets).

    Returns:
        ``(base, lower, upper, between)`` in degrees: base yaw; lower arm above the
        horizontal; upper arm below the horizontal; angle between the two arms. This
        convention reproduces the reach table of docs/uarm-protocol.md (z = 0: 87..359 mm, z = 100: 124..353,
        nothing from z = 190).
    """
    if x <= 0:
        return None
    stretch = math.hypot(x, y)
    sw = stretch - SHOULDER_OFFSET_MM - EFFECTOR_FRONT_MM
    zw = z + EFFECTOR_HEIGHT_MM - SHOULDER_HEIGHT_MM
    d = math.hypot(sw, zw)
    a, b = LOWER_ARM_MM, UPPER_ARM_MM
    if not abs(a - b) < d < a + b:
        return None
    lower = math.degrees(math.atan2(zw, sw) + math.acos((a * a + d * d - b * b) / (2 * a * d)))
    between = math.degrees(math.acos((a * a + b * b - d * d) / (2 * a * b)))
    upper = 180.0 - lower - between
    return math.degrees(math.atan2(y, x)), lower, upper, between


def tool_position(base: float, lower: float, upper: float) -> tuple[float, float, float]:
    """The tool position (mm) of joint angles (degrees, the convention of :func:`joint_angles`):
    the forward kinematics the firmware's M2221 and position reports use."""
    sw = LOWER_ARM_MM * math.cos(math.radians(lower)) + UPPER_ARM_MM * math.cos(math.radians(upper))
    zw = LOWER_ARM_MM * math.sin(math.radians(lower)) - UPPER_ARM_MM * math.sin(math.radians(upper))
    stretch = sw + SHOULDER_OFFSET_MM + EFFECTOR_FRONT_MM
    z = zw - EFFECTOR_HEIGHT_MM + SHOULDER_HEIGHT_MM
    return stretch * math.cos(math.radians(base)), stretch * math.sin(math.radians(base)), z


def angles_legal(base: float, lower: float, upper: float) -> bool:
    """Whether joint angles are within the 4.x limits (``is_angle_legal``)."""
    between = 180.0 - lower - upper
    return (abs(base) <= BASE_LIMIT_DEG
            and LOWER_ARM_LIMITS_DEG[0] <= lower <= LOWER_ARM_LIMITS_DEG[1]
            and UPPER_ARM_LIMITS_DEG[0] <= upper <= UPPER_ARM_LIMITS_DEG[1]
            and BETWEEN_ARMS_LIMITS_DEG[0] <= between <= BETWEEN_ARMS_LIMITS_DEG[1])


def is_reachable(x: float, y: float, z: float) -> bool:
    """Whether the simulated arm can put its tool at (x, y, z) mm (4.x rule, mode 0)."""
    if not all(math.isfinite(v) for v in (x, y, z)):
        return False
    angles = joint_angles(x, y, z)
    return angles is not None and angles_legal(*angles[:3])


# ---------------------------------------------------------------------- number grammars
_GRBL_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)")
_STRTOD = re.compile(r"\s*([-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan))", re.IGNORECASE)
_STRTOL = re.compile(r"\s*([-+]?\d+)")


def grbl_read_float(text: str) -> float | None:
    """grbl's ``read_float``: sign, digits and one point, no exponent; None without a digit.
    What follows the number is left alone (the caller sees it)."""
    m = _GRBL_FLOAT.match(text)
    return float(m.group(0)) if m else None


def marlin_float(text: str) -> float:
    """Marlin's ``code_value_float``: ``strtod`` on the text, cut at the first ``E`` (Marlin's
    extruder letter), so ``1e-05`` is 1e-05 and ``1E-05`` is 1; no number reads as 0."""
    cut = text.split("E", 1)[0]
    m = _STRTOD.match(cut)
    return float(m.group(1)) if m else 0.0


def marlin_int(text: str) -> int:
    """Marlin's ``code_value_int``/``_byte``/``_ushort``: ``strtol`` base 10, 0 without a number."""
    m = _STRTOL.match(text)
    return int(m.group(1)) if m else 0


# sscanf conversions of the 4.x parsers: "f" is %[0-9-+.], "u" is %[0-9.], "d" is %d,
# "s" is %s, "h" is %[0-F.] (the serial number's characters).
_SCAN_SETS = {"f": r"[-+.0-9]+", "u": r"[.0-9]+", "d": r"[-+]?\d+", "s": r"\S+", "h": r"[0-9:;<=>?@A-F.]+"}


def scan4(pattern: list[tuple[str, str]], text: str) -> list[str]:
    """The fields ``sscanf`` fills for a 4.x pattern such as ``X%[0-9-+.]Y...``: it stops
    at the first literal or conversion that does not match, so the count says how far it got."""
    out, pos = [], 0
    for literal, kind in pattern:
        if not text.startswith(literal, pos):
            break
        pos += len(literal)
        m = re.compile(_SCAN_SETS[kind]).match(text, pos)
        if not m:
            break
        out.append(m.group(0))
        pos = m.end()
    return out


def _pattern(spec: str) -> list[tuple[str, str]]:
    """``"X f Y f Z f"`` -> ``[("X", "f"), ("Y", "f"), ("Z", "f")]``."""
    parts = spec.split()
    return list(zip(parts[0::2], parts[1::2]))


@dataclass
class _Command:
    number: int | None
    word: str
    args: str
    text: str
    arrival: float
    target: tuple[float, float, float] | None = None
    speed: float | None = None
    reply_sent: bool = False
    lose_reply: bool = False


@dataclass
class _Motion:
    command: _Command | None
    start: tuple[float, float, float]
    target: tuple[float, float, float]
    t0: float
    t1: float

    def at(self, t: float) -> tuple[float, float, float]:
        if t >= self.t1 or self.t1 <= self.t0:
            return self.target
        s = max(0.0, (t - self.t0) / (self.t1 - self.t0))
        return tuple(p + s * (q - p) for p, q in zip(self.start, self.target))


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

#: 4.x bits of ``motor_state_bits`` set/cleared by M2201/M2202 N0..N3 (base, lower, upper, wrist)...
_BIT_OF_JOINT_4X = {0: 0x04, 1: 0x01, 2: 0x02, 3: 0x08}
#: ...and the bit M2203 N0..N3 reads: the firmware's M2203 N0 reads the bit M2201 N1 sets.
_BIT_READ_4X = {0: 0x01, 1: 0x02, 2: 0x04, 3: 0x08}
_STEPPERS = frozenset({0, 1, 2})


@dataclass
class SimulatedSwiftPro:
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
            self._queue: deque[_Command] = deque()
            self._sync_waiters: list[_Command] = []
            self._motion: _Motion | None = None
            self._hand: _Motion | None = None
            self._t_free = now
            self._paused = False
            self._pos = tuple(float(v) for v in self.start)
            self._last_target = self._pos   # 4.x target_step / 3.x current_position
            self._speed_set: float | None = None
            self._bits = 0x0F              # 4.x motor_state_bits
            self._enabled = set(_STEPPERS)  # stepper drivers enabled (physical)
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
            end = self._reachable_towards(start, target)
            self._hand = _Motion(None, start, end, now, now + duration)
            return True

    def hand_is_moving(self, t: float) -> bool:
        """Whether a hand move is under way at ``t``."""
        with self.lock:
            return self._hand is not None and self._hand.t0 <= t < self._hand.t1

    @staticmethod
    def _reachable_towards(start, target):
        if is_reachable(*target) or not is_reachable(*start):
            return target if is_reachable(*target) else start
        lo, hi = 0.0, 1.0
        for _ in range(40):
            mid = (lo + hi) / 2
            p = tuple(a + mid * (b - a) for a, b in zip(start, target))
            lo, hi = (mid, hi) if is_reachable(*p) else (lo, mid)
        return tuple(a + lo * (b - a) for a, b in zip(start, target))

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

    # ------------------------------------------------------------------ output
    def _emit_raw(self, data: bytes, t: float) -> None:
        due = t + self.latency
        if self.baud:
            due = max(due, self._wire_free) + 10.0 * len(data) / self.baud
            self._wire_free = due
        self._seq += 1
        heapq.heappush(self._out, (due, self._seq, data))

    def _emit(self, line: str, t: float) -> None:
        self._emit_raw(line.encode("ascii") + self._profile.newline, t)

    def _num(self, v: float) -> str:
        """A float as the firmware prints it (dtostrf: 4 decimals on 4.x, 2 on 3.x)."""
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return f"{v:.{self._profile.decimals}f}"

    def _claim(self, cmd: _Command) -> bool:
        """Mark a command answered; False if it was already, or its reply is to be lost."""
        if cmd.reply_sent:
            return False
        cmd.reply_sent = True
        return not cmd.lose_reply

    def _r4(self, cmd: _Command, t: float, result: int | None = 0, tail: str = "") -> None:
        """A 4.x reply: ``$n ok V1`` / ``$n E21``; result None is a status grbl reports
        with nothing (``$n`` alone)."""
        if not self._claim(cmd):
            return
        head = "" if cmd.number is None else f"${cmd.number}"
        word = "" if result is None else ("ok" if result == 0 else f"E{result}")
        text = " ".join(p for p in (head, word) if p)
        self._emit(text + tail, t)

    def _r3_ok(self, cmd: _Command, t: float) -> None:
        """3.x ``ok_to_send``: ``$n ok``."""
        if self._claim(cmd):
            self._emit(("" if cmd.number is None else f"${cmd.number} ") + "ok", t)

    def _r3(self, cmd: _Command, t: float, result: int = 0, buf: str = "") -> None:
        """3.x reply of a command with a result: ``$n ok <buf>`` or ``$n E<r> <buf>``
        (Marlin prints the space even when the buffer is empty; a buffer that ends in
        ``\\r\\n`` makes the blank line hosts see)."""
        if self._claim(cmd):
            head = "" if cmd.number is None else f"${cmd.number} "
            word = "ok" if result == 0 else f"E{result}"
            self._emit_raw(f"{head}{word} {buf}".encode("ascii") + b"\r\n", t)

    # ------------------------------------------------------------------ time
    def _actual(self, t: float) -> tuple[float, float, float]:
        if self._motion:
            return self._motion.at(t)
        if self._hand:
            return self._hand.at(t)
        return self._pos

    def _freeze_hand(self, t: float) -> None:
        if self._hand is not None:
            self._pos = self._hand.at(t)
            self._hand = None

    def _next_internal(self) -> float:
        t = min(self._next_report, self._next_chatter)
        if not self._booted:
            t = min(t, self._boot_end)
        if self._motion:
            t = min(t, self._motion.t1)
        elif self._queue and not self._paused:
            t = min(t, max(self._t_free, self._queue[0].arrival))
        return t

    def _advance(self, now: float) -> None:
        while True:
            t = self._next_internal()
            if t > now:
                return
            if not self._booted and t >= self._boot_end:
                self._booted = True
                self._banner(self._boot_end)
                continue
            if self._motion and self._motion.t1 == t:
                self._finish_motion()
            elif t == self._next_report:
                self._report_position(t)
                self._next_report = t + self._report_interval
            elif t == self._next_chatter:
                self._chat(t)
                self._next_chatter = t + self.chatter
            else:
                self._execute_queued(self._queue[0], t)

    def _banner(self, t: float) -> None:
        if self.chatter:
            self._next_chatter = t + self.chatter
        if self.firmware == 4:
            # uarm_swift.c: uart_printf(... "\r\n") for the four lines, printString("@1\n").
            for line in (f"device name : {self.device_name}", f"soft ver : {self._profile.firmware}",
                         f"api ver : {self._profile.api}", f"work mode : {self._mode}"):
                self._emit_raw(line.encode("ascii") + b"\r\n", t)
            self._emit_raw(b"@1\n", t)
        else:
            for line in ("start", f"echo: {self.device_name} {self._profile.firmware}", ""):
                self._emit(line, t)

    def _report_position(self, t: float) -> None:
        """``@3``: both firmwares read the joint sensors, so it is the measured position."""
        x, y, z = self._actual(t)
        text = f"@3 X{self._num(x)} Y{self._num(y)} Z{self._num(z)} R{self._num(self._wrist)}"
        self._emit(text, t)

    def _chat(self, t: float) -> None:
        x, y, z = self._actual(t)
        line = self._rng.choice([f"@3 X{self._num(x)} Y{self._num(y)} Z{self._num(z)} R{self._num(self._wrist)}",
                                 "@5 V1", f"@6 N0 V{self._rng.randint(0, 1)}", "@9 V0"])
        self._emit(line, t)

    def _finish_motion(self) -> None:
        m = self._motion
        self._motion = None
        self._pos = m.target
        self._t_free = m.t1
        if self._queue and self._queue[0] is m.command:
            self._queue.popleft()
        if self.firmware == 4 and m.command is not None:
            self._r4(m.command, m.t1)
        if not self._queue:
            for waiter in self._sync_waiters:
                self._r3_ok(waiter, m.t1)
            self._sync_waiters.clear()
        if self._report_stop:
            self._emit("@9 V0", m.t1)

    # ------------------------------------------------------------------ input
    def _line(self, raw: str, now: float) -> None:
        self.received_lines.append(raw)
        if self._disconnect_after is not None:
            self._disconnect_after -= 1
            if self._disconnect_after <= 0:
                self._disconnect_after = None
                self.disconnected = True
                return
        if self._serial_moved:
            return  # 3.x after M2500: the firmware listens on its second serial port
        if self.firmware == 4:
            self._line_4x(raw, now)
        else:
            self._line_3x(raw, now)

    def _new_command(self, number, word, args, text, now) -> _Command:
        cmd = _Command(number, word, args, text, now)
        self._lines_since_boot += 1
        if self._drop_line == self._lines_since_boot:
            cmd.lose_reply = True
        elif self._drop_replies > 0:
            self._drop_replies -= 1
            cmd.lose_reply = True
        return cmd

    def _line_4x(self, raw: str, now: float) -> None:
        # 4.x drops white space, upper-cases, keeps 80 characters (docs/uarm-protocol.md "Link").
        text = re.sub(r"\s", "", raw).upper()[:80]
        if not text:
            return
        number = None
        m = re.match(r"#(\d*)", text)
        if m:
            number = int(m.group(1)) if m.group(1) else None
            text = text[m.end():]
        if not text or text[0] not in "GMPS":
            return  # receive_cmd_line ignores the line: no reply at all
        m = re.match(r"([GMPS])(\d+)(\.\d*)?", text)
        word = (m.group(1) + str(int(m.group(2)))) if m else text[0]
        cmd = self._new_command(number, word, text[m.end():] if m else text[1:], text, now)
        if not m:
            self._r4(cmd, now, None)  # grbl: bad number format, reported with nothing
            return
        if m.group(3):
            self._r4(cmd, now, 20)  # Gxx.x / Mxx.x: grbl's "value not integer"
            return
        if word[0] in "PS":
            self._dispatch_4x(cmd, now)
        else:
            if len(self._queue) >= QUEUE_SIZE:
                self._emit_raw(b"E23 buffer full\r\n", now)  # bare: no number (docs/uarm-protocol.md)
                return
            self._queue.append(cmd)
            self._advance(now)

    def _line_3x(self, raw: str, now: float) -> None:
        text = raw.strip()
        if not text:
            return
        number = None
        m = re.match(r"#(\d*)\s*", text)
        if m:
            number = int(m.group(1) or 0) or None  # "$0" is never printed: serialNum > 0 only
            text = text[m.end():]
        m = re.match(r"N[-+]?\d*\s*", text)
        if m and len(text) > 1 and text[1] in "-+0123456789":
            text = text[m.end():]  # Marlin skips a line number
        text = text.split("*", 1)[0].rstrip()
        m = re.match(r"([GMPT])\s*(\d+)\s*", text)
        word = (m.group(1) + str(int(m.group(2)))) if m else ""
        cmd = self._new_command(number, word, text[m.end():] if m else "", text, now)
        handler = self._handlers.get(word) if m else None
        if handler is None:
            self._emit(f'echo:Unknown command: "{text}"', now)
            return
        handler(cmd, now)

    # ------------------------------------------------------------------ 4.x execution
    def _execute_queued(self, cmd: _Command, t: float) -> None:
        """Run the command at the head of the queue: a 4.x G/M command, or a 3.x move."""
        if self.firmware == 3:
            self._execute_queued_3x(cmd, t)
            return
        if cmd.word in self._moves_4x:
            self._start_move_4x(cmd, t)
            return
        self._queue.popleft()
        self._t_free = t
        self._dispatch_4x(cmd, t)

    def _dispatch_4x(self, cmd: _Command, t: float) -> None:
        handler = self._handlers.get(cmd.word)
        if handler is None:
            self._r4(cmd, t, 20)  # grbl: unsupported command
            return
        handler(cmd, t)

    def _start_move_4x(self, cmd: _Command, t: float) -> None:
        """A queued 4.x move: parse against the current target, check (mc_line), move."""
        if cmd.target is None:
            status = self._moves_4x[cmd.word](cmd, t)
            if status is not None:
                self._queue.popleft()
                self._t_free = t
                self._r4(cmd, t, {"ok": 0, "silent": None}.get(status, status))
                return
        # mc_line: the three steppers' bits (not the wrist's), then the joint limits.
        if (self._bits & 0x07) != 0x07:
            status = 27
        elif not is_reachable(*cmd.target):
            status = 22
        elif not cmd.speed:
            status = 0  # mc_line with no feed rate: "ok" without moving
        else:
            status = None
        if status is not None:
            self._queue.popleft()
            self._t_free = t
            self._r4(cmd, t, status)
            return
        self._freeze_hand(t)
        start = self._actual(t)
        duration = math.dist(start, cmd.target) / cmd.speed * self.motion_scale
        self._last_target = cmd.target
        self._motion = _Motion(cmd, start, cmd.target, t, t + duration)
        if duration <= 0:
            self._finish_motion()

    def _speed_4x(self, f: float, linear: bool) -> float | None:
        # 4.x: F taken as mm/s, linear moves capped at 100, others at 200 (docs/uarm-protocol.md).
        return min(f, 100.0 if linear else 200.0) if f and f > 0 else None

    def _grbl_words(self, args: str) -> dict[str, float] | int | None:
        """grbl's word parser for G0/G1: letter, number, ... -> words, or a status: None for
        the silent ones (a missing letter or number, a negative F), 20 for an unsupported or
        repeated word."""
        words: dict[str, float] = {}
        pos = 0
        while pos < len(args):
            letter = args[pos]
            if not "A" <= letter <= "Z":
                return None
            m = _GRBL_FLOAT.match(args, pos + 1)
            if not m:
                return None
            if letter not in "XYZFN" or letter in words:
                return 20
            words[letter] = float(m.group(0))
            pos = m.end()
        if words.get("F", 0.0) < 0:
            return None
        return words

    def _g0_g1(self, cmd: _Command, t: float):
        words = self._grbl_words(cmd.args)
        if not isinstance(words, dict):
            return words if words is not None else "silent"
        if "F" in words:
            self._speed_set = words["F"]
        if cmd.word == "G1" and not self._speed_set:
            return "silent"  # G1 without a feed rate: STATUS_GCODE_UNDEFINED_FEED_RATE, reported with nothing
        base = self._last_target
        cmd.target = (words.get("X", base[0]), words.get("Y", base[1]), words.get("Z", base[2]))
        cmd.speed = self._speed_4x(self._speed_set or 0.0, cmd.word == "G1")
        return None

    def _fixed_move(self, spec: str, cmd: _Command, to_target, linear: bool):
        """A 4.x move with a fixed pattern (every field, in order, or E21)."""
        pattern = _pattern(spec)
        fields = scan4(pattern, cmd.args)
        if len(fields) < len(pattern):
            return 21
        values = []
        for (_, kind), text in zip(pattern, fields):
            v = int(text) if kind == "d" else grbl_read_float(text)
            if v is None:
                return "ok"  # `return false` from an enum function is UARM_CMD_OK: "ok", no move
            values.append(v)
        target = to_target(*values)
        if target is None:
            return 21
        if target == "ok":
            return "ok"
        cmd.target = target
        cmd.speed = self._speed_4x(values[-1], linear)
        return None

    # -- the 3Plus jogs: to the edge of the reach along an axis (G2207), a joint to its limit
    # (G2208), every joint back inside its limits (G2209). Approximation: the firmware computes
    # the edges from its joint limits with 1-2 degree margins; here the edge is found on the
    # same reach rule as every other move, 1 mm inside.
    def _jog(self, cmd, t, to_target):
        fields = scan4(_pattern("N d F f"), cmd.args)
        if len(fields) < 2:
            return 21
        speed = grbl_read_float(fields[1])
        if speed is None:
            return "ok"
        direction = int(fields[0]) + (3 if speed < 0 else 0)
        if not 0 <= direction <= 5:
            return 21
        target = to_target(direction, self._actual(t))
        cmd.target = target if target is not None else (-1.0, 0.0, 0.0)  # the firmware's "to report error"
        cmd.speed = self._speed_4x(abs(speed), False)
        return None

    @staticmethod
    def _axis_edge(direction, start):
        axis, sign = direction % 3, (1.0 if direction < 3 else -1.0)

        def at(d):
            p = list(start)
            p[axis] += sign * d
            return tuple(p)
        if not is_reachable(*start) or not is_reachable(*at(0.7)):
            return None  # no room to move: E22
        lo, hi = 0.7, 400.0
        for _ in range(40):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if is_reachable(*at(mid)) else (lo, mid)
        return at(lo - 1.0) if lo - 1.0 >= 0.7 else None

    @staticmethod
    def _joint_limit(direction, start):
        angles = joint_angles(*start)
        if angles is None:
            return None
        b, lo, up, _ = angles
        if direction in (0, 3):
            goal = BASE_LIMIT_DEG - 0.5 if direction == 0 else -BASE_LIMIT_DEG + 0.5
            b, moved = goal, abs(goal - b)
        elif direction in (1, 4):  # lower arm: until the angle between the arms is at its min / max
            between = BETWEEN_ARMS_LIMITS_DEG[0] if direction == 1 else BETWEEN_ARMS_LIMITS_DEG[1]
            goal = min(max(180.0 - between - up, LOWER_ARM_LIMITS_DEG[0] + 1), LOWER_ARM_LIMITS_DEG[1] - 1)
            lo, moved = goal, abs(goal - lo)
        else:  # upper arm, likewise
            between = BETWEEN_ARMS_LIMITS_DEG[0] if direction == 2 else BETWEEN_ARMS_LIMITS_DEG[1]
            goal = min(max(180.0 - between - lo, UPPER_ARM_LIMITS_DEG[0] + 1), UPPER_ARM_LIMITS_DEG[1] - 1)
            up, moved = goal, abs(goal - up)
        if moved < 0.7:
            return None  # already at the limit: E22
        return tool_position(b, lo, up)

    def _g2209(self, cmd, t):
        fields = scan4(_pattern("F f"), cmd.args)
        if not fields:
            return 21
        speed = grbl_read_float(fields[0])
        if speed is None:
            return "ok"
        angles = joint_angles(*self._actual(t))
        b, lo, up = angles[:3] if angles else (0.0, 45.0, 30.0)
        b = min(max(b, -BASE_LIMIT_DEG + 2), BASE_LIMIT_DEG - 2)
        lo = min(max(lo, LOWER_ARM_LIMITS_DEG[0] + 2), LOWER_ARM_LIMITS_DEG[1] - 2)
        up = min(max(up, UPPER_ARM_LIMITS_DEG[0] + 2), UPPER_ARM_LIMITS_DEG[1] - 2)
        cmd.target, cmd.speed = tool_position(b, lo, up), self._speed_4x(abs(speed), False)
        return None

    def _polar_target(self, s: float, r: float, h: float) -> tuple[float, float, float]:
        a = math.radians(r - 90.0)
        return (s * math.cos(a), s * math.sin(a), h)

    def _target_angles(self) -> tuple[float, float, float]:
        angles = joint_angles(*self._last_target)
        return angles[:3] if angles else (0.0, 90.0, 0.0)

    def _g2202_target(self, n, v, f):
        if n == 3:
            self._wrist = v
            return "ok"
        if n not in (0, 1, 2):
            return None
        b, lo, up = self._target_angles()
        if n == 0:
            b = v - 90.0
        elif n == 1:
            lo = v
        else:
            up = v
        return tool_position(b, lo, up)

    def _table_4x(self) -> dict:
        """The 4.x command table: uarm_protocol.c's G/M/P/S switches (docs/uarm-protocol.md)."""
        self._moves_4x = {
            "G0": self._g0_g1, "G1": self._g0_g1,
            "G2201": lambda c, t: self._fixed_move(
                "S f R f H f F f", c, lambda s, r, h, f: self._polar_target(s, r, h), True),
            "G2202": lambda c, t: self._fixed_move("N d V f F f", c, self._g2202_target, False),
            "G2204": lambda c, t: self._fixed_move(
                "X f Y f Z f F f", c, lambda x, y, z, f: tuple(
                    p + d for p, d in zip(self._last_target, (x, y, z))), True),
            "G2205": lambda c, t: self._fixed_move("S f R f H f F f", c, self._polar_offset, True),
            "G2206": lambda c, t: self._fixed_move(
                "B f L f R f F f", c, lambda b, lo, up, f: tool_position(b - 90.0, lo, up), False),
            "G2207": lambda c, t: self._jog(c, t, self._axis_edge),
            "G2208": lambda c, t: self._jog(c, t, self._joint_limit),
            "G2209": self._g2209,
        }
        h = {}  # the moves above are started by _start_move_4x from the queue
        h.update({
            "G2004": self._g2004_4x,
            "M17": self._m17, "M18": self._m2019, "M2019": self._m2019,
            "M204": self._m204_4x, "M2120": self._m2120, "M2121": self._m2121,
            "M2122": self._flag_4x("M2122"), "M2123": self._flag_4x("M2123"), "M2124": self._flag_4x("M2124"),
            "M2201": self._m2201, "M2202": self._m2202, "M2203": self._m2203,
            "M2205": self._m2205_4x, "M2210": self._m2210,
            "M2211": self._m2211, "M2212": self._m2212, "M2213": self._ok_only, "M2215": self._ok_only,
            "M2220": self._m2220, "M2221": self._m2221, "M2222": self._m2222,
            "M2231": self._effector_4x("pump", "012"), "M2232": self._effector_4x("gripper", "01"),
            "M2233": self._effector_4x("laser", "01"), "M2234": self._ok_only,
            "M2240": self._m2240, "M2241": self._m2241,
            "M2400": self._m2400, "M2401": self._ok_only, "M2410": self._m2410,
            "M2411": self._offset_4x("S", "front"), "M2412": self._offset_4x("V", "effect_angle"),
            "M2413": self._offset_4x("H", "height"), "M2500": self._ok_only,
            "P2200": self._p2200, "P2201": self._p_text(lambda: self.device_name),
            "P2202": self._p_text(lambda: self._profile.hardware),
            "P2203": self._p_text(lambda: self._profile.firmware),
            "P2204": self._p_text(lambda: self._profile.api), "P2205": self._p_text(lambda: "V" + self.uid),
            "P2206": self._p2206, "P2220": self._p2220, "P2221": self._p2221,
            "P2231": self._p_value(lambda: self._pump), "P2232": self._p_value(lambda: self._gripper),
            "P2233": self._p_value(lambda: 0), "P2234": self._p_value(lambda: 1),
            "P2235": self._p_value(lambda: self._laser), "P2236": self._p2236,
            "P2240": self._p2240, "P2241": self._p2241, "P2242": self._p2242, "P2243": self._p2242,
            "P2244": self._p_value(lambda: 0), "P2400": self._p_value(lambda: self._mode),
            "S1000": self._s1000, "S1100": self._s1100,
        })
        if self.version_tuple < (4, 5, 0):
            del h["S1100"]  # 4.5 added the planner clear
        return h

    def _polar_offset(self, s, r, h, f):
        x, y, z = self._last_target
        stretch = math.hypot(x, y) + s
        base = math.degrees(math.atan2(y, x)) + r
        return (stretch * math.cos(math.radians(base)), stretch * math.sin(math.radians(base)), z + h)

    # -- 4.x handlers (each answers its command)
    def _ok_only(self, cmd, t):
        self._r4(cmd, t) if self.firmware == 4 else self._r3_ok(cmd, t)

    def _char_arg(self, cmd, letter: str, allowed: str) -> int | None:
        """The 4.x check ``line[0] == letter && line[1] in allowed``: the digit, or None."""
        a = cmd.args
        return int(a[1]) if len(a) >= 2 and a[0] == letter and a[1] in allowed else None

    def _g2004_4x(self, cmd, t):
        fields = scan4(_pattern("P d"), cmd.args)
        if not fields:
            self._r4(cmd, t, 21)
            return
        self._r4(cmd, t)
        self._t_free = t + max(0, int(fields[0])) / 1000.0  # the next queued command waits

    def _m17(self, cmd, t):
        self._attach(set(_STEPPERS), t)
        self._bits = 0x0F
        self._servo_attached = True
        self._ok_only(cmd, t)

    def _m2019(self, cmd, t):
        self._enabled.clear()
        self._bits = 0x00
        self._servo_attached = False if self.firmware == 4 else self._servo_attached
        self._ok_only(cmd, t)

    def _attach(self, steppers: set[int], t: float) -> None:
        """Enable stepper drivers: a hand move stops where it is, and the firmware reads
        where the arm now is (4.x ``update_motor_position``; 3.x does not)."""
        self._freeze_hand(t)
        self._enabled |= steppers
        if self.firmware == 4:
            self._last_target = self._actual(t)

    def _m204_4x(self, cmd, t):
        fields = scan4(_pattern("A f"), cmd.args)
        v = grbl_read_float(fields[0]) if fields else None
        if v is None:
            self._r4(cmd, t, 21)
            return
        self._acceleration = v
        self._r4(cmd, t)

    def _m2120(self, cmd, t):
        if self.firmware == 4:
            m = re.match(r"V(\S+)", cmd.args)
            v = grbl_read_float(m.group(1)) if m else None
            if v is None:
                self._r4(cmd, t, 21)
                return
        else:
            if not self._seen(cmd, "V"):
                self._r3_ok(cmd, t)
                return
            v = marlin_float(self._after(cmd, "V"))
        self._report_interval = v if v > 0 else None
        self._next_report = t + v if v > 0 else math.inf
        self._ok_only(cmd, t)

    def _m2121(self, cmd, t):
        self._report_interval, self._next_report = None, math.inf
        self._ok_only(cmd, t)

    def _flag_4x(self, word):
        name = {"M2122": "stop_report", "M2123": "position_check", "M2124": "beep"}[word]

        def handler(cmd, t):
            v = self._char_arg(cmd, "V", "01")
            if v is None:
                self._r4(cmd, t, 21)
                return
            if name == "stop_report":
                self._report_stop = bool(v)
            else:
                self._flags[name] = bool(v)
            self._r4(cmd, t)
        return handler

    def _joint_arg(self, cmd) -> int | None:
        if self.firmware == 4:
            return self._char_arg(cmd, "N", "0123")
        return marlin_int(self._after(cmd, "N")) if self._seen(cmd, "N") else None

    def _m2201(self, cmd, t):
        n = self._joint_arg(cmd)
        if self.firmware == 4:
            if n is None:
                self._r4(cmd, t, 21)
                return
            if n < 3:
                self._attach(set(_STEPPERS), t)  # the firmware enables all three drivers for any of N0..N2
            else:
                self._servo_attached = True
            self._bits |= _BIT_OF_JOINT_4X[n]
            self._r4(cmd, t)
            return
        if n in _STEPPERS:
            self._attach({n}, t)
        elif n == 3:
            self._servo_attached = True
        self._r3_ok(cmd, t)

    def _m2202(self, cmd, t):
        n = self._joint_arg(cmd)
        if self.firmware == 4 and n is None:
            self._r4(cmd, t, 21)
            return
        if n in _STEPPERS:
            self._enabled.discard(n)
        elif n == 3:
            self._servo_attached = False
        if self.firmware == 4:
            self._bits &= ~_BIT_OF_JOINT_4X[n]
        self._ok_only(cmd, t)

    def _m2203(self, cmd, t):
        n = self._joint_arg(cmd)
        if self.firmware == 4:
            if n is None:
                self._r4(cmd, t, 21)
                return
            self._r4(cmd, t, 0, f" V{int(bool(self._bits & _BIT_READ_4X[n]))}")
            return
        attached = (n in self._enabled) if n in _STEPPERS else (self._servo_attached if n == 3 else False)
        self._r3(cmd, t, 0, f"V{int(attached)}")

    def _m2205_4x(self, cmd, t):
        fields = scan4([("VUB", "h")], cmd.args)
        if not fields:
            self._r4(cmd, t, 21)
            return
        self.uid = (fields[0] + self.uid)[:12] if len(fields[0]) < 12 else fields[0][:12]
        self._r4(cmd, t)

    def _m2210(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("F u T d"), cmd.args)
            f = grbl_read_float(fields[0]) if fields else None
            if len(fields) < 2 or f is None:
                self._r4(cmd, t, 21)
                return
            self.beeps.append((f, float(int(fields[1]))))
            self._r4(cmd, t)
            return
        f = float(min(marlin_int(self._after(cmd, "F")), 5000)) if self._seen(cmd, "F") else 1000.0
        d = marlin_float(self._after(cmd, "T")) if self._seen(cmd, "T") else 260.0
        self.beeps.append((f, d))
        self._r3_ok(cmd, t)

    # -- EEPROM (M2211 read, M2212 write): little-endian bytes, as the AVR stores them
    def _eeprom_of(self, device: int) -> bytearray:
        return self._eeprom.setdefault(device, bytearray(b"\xff" * _EEPROM_BYTES))

    def _eeprom_read(self, device, addr, kind):
        mem = self._eeprom_of(device)
        size = {1: 1, 2: 2, 4: 4}[kind]
        raw = bytes(mem[(addr + i) % _EEPROM_BYTES] for i in range(size))
        if kind == 1:
            return raw[0]
        if kind == 2:
            return struct.unpack("<h", raw)[0]
        return struct.unpack("<f", raw)[0]

    def _eeprom_write(self, device, addr, kind, value):
        mem = self._eeprom_of(device)
        if kind == 1:
            raw = bytes([int(value) & 0xFF])
        elif kind == 2:
            raw = struct.pack("<h", max(-32768, min(32767, int(value))))
        else:
            raw = struct.pack("<f", float(value))
        for i, b in enumerate(raw):
            mem[(addr + i) % _EEPROM_BYTES] = b

    def _m2211(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("N d A d T d"), cmd.args)
            if len(fields) < 3:
                self._r4(cmd, t, 21)
                return
            device, addr, kind = (int(v) for v in fields)
            if device != 1 or not 0 <= addr <= 65524 or kind not in (1, 2, 4):
                self._r4(cmd, t, 21)  # 4.x reads only device 1 (the SDK's N0 gets E21)
                return
            v = self._eeprom_read(device, addr, kind)
            if kind == 1:
                v = v - 256 if v > 127 else v  # printed through (char): signed
            text = self._num(v) if kind == 4 else str(int(v))
            self._r4(cmd, t, 0, f" V{text}")
            return
        if not all(self._seen(cmd, c) for c in "NAT"):
            self._r3(cmd, t, 21)
            return
        device = marlin_int(self._after(cmd, "N"))
        addr = marlin_int(self._after(cmd, "A")) & 0xFFFF
        kind = marlin_int(self._after(cmd, "T"))
        if kind not in (1, 2, 4):
            self._r3(cmd, t, 0, "")  # no case matches: "ok" and an empty buffer
            return
        v = self._eeprom_read(device, addr, kind)
        self._r3(cmd, t, 0, f"V{self._num(v) if kind == 4 else int(v)}")

    def _m2212(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("N d A d T d V u"), cmd.args)
            value = grbl_read_float(fields[3]) if len(fields) == 4 else None
            if len(fields) < 4 or value is None:
                self._r4(cmd, t, 21)  # includes negative values: the pattern has no sign
                return
            device, addr, kind = (int(v) for v in fields[:3])
            if device != 1 or not 0 <= addr <= 65524 or kind not in (1, 2, 4):
                self._r4(cmd, t, 21)
                return
            self._eeprom_write(device, addr, kind, value)
            self._r4(cmd, t)
            return
        if all(self._seen(cmd, c) for c in "NATV"):
            kind = marlin_int(self._after(cmd, "T"))
            if kind in (1, 2, 4):
                self._eeprom_write(marlin_int(self._after(cmd, "N")), marlin_int(self._after(cmd, "A")) & 0xFFFF,
                                   kind, marlin_float(self._after(cmd, "V")))
        self._r3_ok(cmd, t)

    def _angles_text(self, base_plus_90, lower, upper) -> str:
        return f"B{self._num(base_plus_90)} L{self._num(lower)} R{self._num(upper)}"

    def _three_floats4(self, cmd, t, letters: str) -> list | None:
        """A 4.x command's three float fields (``letters`` in order), or None after answering E21."""
        fields = scan4(_pattern(" ".join(f"{c} f" for c in letters)), cmd.args)
        values = [grbl_read_float(v) for v in fields]
        if len(fields) < 3 or None in values:
            self._r4(cmd, t, 21)
            return None
        return values

    def _m2220(self, cmd, t):
        if self.firmware == 4:
            values = self._three_floats4(cmd, t, "XYZ")
            if values is None:
                return
            angles = joint_angles(*values)
            b, lo, up = angles[:3] if angles else (math.degrees(math.atan2(values[1], values[0])), math.nan, math.nan)
            self._r4(cmd, t, 0, " " + self._angles_text(b + 90.0, lo, up))  # no legality check on 4.x
            return
        if not all(self._seen(cmd, c) for c in "XYZ"):
            self._r3(cmd, t, 21)
            return
        p = [marlin_float(self._after(cmd, c)) for c in "XYZ"]
        if not is_reachable(*p):
            self._r3(cmd, t, 22)
            return
        b, lo, up, _ = joint_angles(*p)
        self._r3(cmd, t, 0, self._angles_text(b + 90.0, lo, up))

    def _m2221(self, cmd, t):
        if self.firmware == 4:
            values = self._three_floats4(cmd, t, "BLR")
            if values is None:
                return
        else:
            if not all(self._seen(cmd, c) for c in "BLR"):
                self._r3(cmd, t, 21)
                return
            values = [marlin_float(self._after(cmd, c)) for c in "BLR"]
        x, y, z = tool_position(values[0] - 90.0, values[1], values[2])
        text = f"X{self._num(x)} Y{self._num(y)} Z{self._num(z)}"
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _m2222(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("X f Y f Z f P d"), cmd.args)
            values = [grbl_read_float(v) for v in fields[:3]]
            if len(fields) < 4 or None in values or int(fields[3]) not in (0, 1):
                self._r4(cmd, t, 21)
                return
            polar = int(fields[3]) == 1
        else:
            if not all(self._seen(cmd, c) for c in "XYZ"):
                self._r3(cmd, t, 21)
                return
            values = [marlin_float(self._after(cmd, c)) for c in "XYZ"]
            polar = self._seen(cmd, "S") and marlin_int(self._after(cmd, "S")) != 0
        p = self._polar_target(*values) if polar else tuple(values)
        text = f"V{int(is_reachable(*p))}"
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _effector_4x(self, name, allowed):
        def handler(cmd, t):
            v = self._char_arg(cmd, "V", allowed)
            if v is None:
                self._r4(cmd, t, 21)
                return
            setattr(self, "_" + name, 1 if v else 0)
            self._r4(cmd, t)
        return handler

    def _m2240(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("N d V d"), cmd.args)
            if len(fields) < 2 or not 0 <= int(fields[0]) <= 69 or int(fields[1]) not in (0, 1):
                self._r4(cmd, t, 21)
                return
            self._pins_out[int(fields[0])] = int(fields[1])
            self._r4(cmd, t)
            return
        if self._seen(cmd, "N") and self._seen(cmd, "V"):
            self._pins_out[marlin_int(self._after(cmd, "N")) & 0xFF] = int(marlin_int(self._after(cmd, "V")) != 0)
        self._r3_ok(cmd, t)

    def _m2241(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(_pattern("N d V d"), cmd.args)
            if len(fields) < 2 or not 0 <= int(fields[0]) <= 69 or int(fields[1]) not in (0, 1):
                self._r4(cmd, t, 21)
                return
            self._pins_mode[int(fields[0])] = "output" if int(fields[1]) else "input"
            self._r4(cmd, t)
            return
        if self._seen(cmd, "N") and self._seen(cmd, "V"):
            pin = marlin_int(self._after(cmd, "N")) & 0xFF
            self._pins_mode[pin] = "output" if marlin_int(self._after(cmd, "V")) else "input"
        self._r3_ok(cmd, t)

    def _m2400(self, cmd, t):
        if self.firmware == 4:
            # the firmware checks line[1] >= '0' && line[1] <= '11' (a two-character constant):
            # any digit passes, and only that one digit is read.
            a = cmd.args
            if not (len(a) >= 2 and a[0] == "S" and a[1].isdigit()):
                self._r4(cmd, t, 21)
                return
            mode = int(a[1])
            if mode <= 8:
                self._mode = mode
            self._r4(cmd, t)
            return
        if self._seen(cmd, "S"):
            self._mode = marlin_int(self._after(cmd, "S")) & 0xFF
            self._resync(t)
        self._r3_ok(cmd, t)

    def _m2410(self, cmd, t):
        if self.firmware == 4:
            self._offsets["height"] = self._actual(t)[2]
            self._r4(cmd, t)
            return
        self._offsets["height"] = marlin_float(self._after(cmd, "S")) if self._seen(cmd, "S") else self._actual(t)[2]
        self._resync(t)
        self._r3_ok(cmd, t)

    def _offset_4x(self, letter, name):
        def handler(cmd, t):
            fields = scan4([(letter, "f")], cmd.args)
            v = grbl_read_float(fields[0]) if fields else None
            if v is None:
                self._r4(cmd, t, 21)
                return
            self._offsets[name] = v
            self._r4(cmd, t)
        return handler

    # -- queries
    def _p_text(self, value):
        def handler(cmd, t):
            self._r4(cmd, t, 0, " " + value())
        return handler

    def _p_value(self, value):
        def handler(cmd, t):
            if self.firmware == 4:
                self._r4(cmd, t, 0, f" V{int(value())}")
            else:
                self._r3(cmd, t, 0, f"V{int(value())}")
        return handler

    def _measured_angles(self, t) -> tuple[float, float, float]:
        angles = joint_angles(*self._actual(t))
        return angles[:3] if angles else (0.0, 0.0, 0.0)

    def _p2200(self, cmd, t):
        b, lo, up = self._measured_angles(t)
        text = self._angles_text(90.0 + b, lo, up)
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _p2206(self, cmd, t):
        if self.firmware == 4:
            n = self._char_arg(cmd, "N", "0123")
            if n is None:
                self._r4(cmd, t, 21)
                return
        else:
            if not self._seen(cmd, "N"):
                self._r3(cmd, t, 21)
                return
            n = marlin_int(self._after(cmd, "N")) & 0xFF
            if n > 3:
                self._r3(cmd, t, 22)
                return
        b, lo, up = self._measured_angles(t)
        v = (90.0 + b, lo, up, self._wrist)[n]
        if self.firmware == 4:
            self._r4(cmd, t, 0, f" V{self._num(v)}")
        else:
            self._r3(cmd, t, 0, f"V{self._num(v)}\r\n")  # its buffer ends in "\r\n": a blank line follows

    def _p2220(self, cmd, t):
        # 4.x reads the encoders, even mid-move and while released; 3.x answers its
        # current_position: the last target, stale after a hand move (SDK #2).
        x, y, z = self._actual(t) if self.firmware == 4 else self._last_target
        text = f"X{self._num(x)} Y{self._num(y)} Z{self._num(z)}"
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _p2221(self, cmd, t):
        x, y, z = self._actual(t) if self.firmware == 4 else self._last_target
        text = (f"S{self._num(math.hypot(x, y))} R{self._num(90 + math.degrees(math.atan2(y, x)))} "
                f"H{self._num(z)}")
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _p2236(self, cmd, t):
        fields = scan4(_pattern("N d"), cmd.args)
        if not fields or int(fields[0]) not in (0, 1):
            self._r4(cmd, t, 21)
            return
        self._r4(cmd, t, 0, " V0")  # nobody presses the arm's buttons

    def _pin_read(self, pin: int) -> int:
        return self._pins_out.get(pin, 0) if self._pins_mode.get(pin) == "output" else 0

    @staticmethod
    def _analog(pin: int) -> int:
        return 700 if pin == 5 else 0  # A5 reads the power supply (> 100 when powered)

    def _p2240(self, cmd, t):
        self._read_pin(cmd, t, 69, self._pin_read)   # digital pins 0-69

    def _p2241(self, cmd, t):
        self._read_pin(cmd, t, 15, self._analog)     # analog pins 0-15

    def _read_pin(self, cmd, t, highest: int, read) -> None:
        """P2240/P2241: one pin's value; 4.x checks the pin's range, 3.x masks it to a byte as Marlin does."""
        if self.firmware == 4:
            fields = scan4(_pattern("N d"), cmd.args)
            if not fields or not 0 <= int(fields[0]) <= highest:
                self._r4(cmd, t, 21)
                return
            self._r4(cmd, t, 0, f" V{read(int(fields[0]))}")
            return
        if not self._seen(cmd, "N"):
            self._r3(cmd, t, 21)
            return
        self._r3(cmd, t, 0, f"V{read(marlin_int(self._after(cmd, 'N')) & 0xFF)}")

    def _p2242(self, cmd, t):
        """Raw 12-bit angle-sensor values (P2242 reference / P2243 register on 4.x)."""
        b, lo, up = self._measured_angles(t)
        adc = [int(round((a % 360.0) / 360.0 * 4096)) for a in (90.0 + b, lo, up)]
        text = f"B{adc[0]} L{adc[1]} R{adc[2]}"
        self._r4(cmd, t, 0, " " + text) if self.firmware == 4 else self._r3(cmd, t, 0, text)

    def _s1000(self, cmd, t):
        v = self._char_arg(cmd, "V", "01")
        if v is None:
            self._r4(cmd, t, 21)
            return
        self._cut_motion(t)
        if v:
            self._paused = False
            self._t_free = t
        else:
            self._paused = True  # the head of the queue keeps its target and restarts on resume
        self._r4(cmd, t)

    def _s1100(self, cmd, t):
        # S1100 (4.5+) clears the planner. UNCERTAIN: whether the cleared commands are ever
        # answered; here they are not.
        self._cut_motion(t)
        self._queue.clear()
        self._paused = False
        self._t_free = t
        self._last_target = self._pos
        self._r4(cmd, t)

    def _cut_motion(self, t):
        if self._motion:
            self._pos = self._motion.at(t)
            self._motion = None

    # ------------------------------------------------------------------ 3.x
    @staticmethod
    def _seen(cmd, letter: str) -> bool:
        return letter in cmd.args  # Marlin's code_seen: strchr on the arguments

    @staticmethod
    def _after(cmd, letter: str) -> str:
        return cmd.args[cmd.args.index(letter) + 1:]

    def _resync(self, t):
        """3.x ``update_current_pos``: current_position from the joint sensors."""
        self._freeze_hand(t)
        self._last_target = self._actual(t)

    def _table_3x(self) -> dict:
        """The 3.x command table: Marlin_main.cpp's uArm G/M/P cases (docs/uarm-protocol.md)."""
        return {
            "G0": self._move_3x, "G1": self._move_3x, "G2201": self._move_3x, "G2204": self._move_3x,
            "G2205": self._move_3x, "G2202": self._g2202_3x, "G2203": self._g2203_3x,
            "G4": self._dwell_3x, "G2004": self._dwell_3x,
            "G90": self._relative_3x(False), "G91": self._relative_3x(True),
            "M17": self._m17, "M18": self._m2019, "M84": self._m2019, "M2019": self._m2019,
            "M204": self._m204_3x, "M2000": self._m2000_3x, "M2120": self._m2120, "M2122": self._m2122_3x,
            "M2200": self._m2200_3x, "M2201": self._m2201, "M2202": self._m2202, "M2203": self._m2203,
            "M2210": self._m2210, "M2211": self._m2211, "M2212": self._m2212, "M2213": self._m2213_3x,
            "M2220": self._m2220, "M2221": self._m2221, "M2222": self._m2222,
            "M2231": self._effector_3x("pump"), "M2232": self._effector_3x("gripper"),
            "M2233": self._ok_only, "M2234": self._m2234_3x, "M2240": self._m2240, "M2241": self._m2241,
            "M2245": self._m2245_3x, "M2300": self._r3_ok, "M2301": self._r3_ok, "M2302": self._r3_ok,
            "M2303": self._r3_ok, "M2304": self._m2304_3x, "M2305": self._m2305_3x, "M2306": self._grove_port_3x,
            "M2307": self._grove_port_3x, "M2400": self._m2400, "M2401": self._m2401_3x,
            "M2410": self._m2410, "M2411": self._m2411_3x, "M2500": self._m2500_3x,
            "P2200": self._p2200, "P2201": self._p3_text(lambda: "V" + self.device_name),
            "P2202": self._p3_text(lambda: self._profile.hardware),
            "P2203": self._p3_text(lambda: self._profile.firmware),
            "P2204": self._p3_text(lambda: self._profile.firmware), "P2205": self._p3_text(lambda: "V" + self.uid),
            "P2206": self._p2206, "P2220": self._p2220, "P2221": self._p2221,
            "P2231": self._p_value(lambda: self._pump), "P2232": self._p_value(lambda: self._gripper),
            "P2233": self._p_value(lambda: 0), "P2234": self._p_value(lambda: 1),
            "P2240": self._p2240, "P2241": self._p2241, "P2242": self._p2242,
            "P2245": self._p3_text(lambda: ""), "P2400": self._p_value(lambda: self._mode),
        }

    def _p3_text(self, value):
        def handler(cmd, t):
            self._r3(cmd, t, 0, value())
        return handler

    def _relative_3x(self, relative: bool):
        def handler(cmd, t):
            self._relative = relative
            self._r3_ok(cmd, t)
        return handler

    def _dwell_3x(self, cmd, t):
        self._r3_ok(cmd, t)  # Marlin's G4 waits for the planner, then dwells; hosts see "ok"

    def _m204_3x(self, cmd, t):
        for letter in "SPTR":
            if self._seen(cmd, letter):
                self._acceleration = marlin_float(self._after(cmd, letter))
        self._r3_ok(cmd, t)

    def _m2000_3x(self, cmd, t):
        # clear_command_queue + quickstop_stepper: the 3.x stop
        self._cut_motion(t)
        self._queue.clear()
        for waiter in self._sync_waiters:
            self._r3_ok(waiter, t)
        self._sync_waiters.clear()
        self._resync(t)
        self._r3_ok(cmd, t)

    def _m2122_3x(self, cmd, t):
        if self._seen(cmd, "V"):
            self._report_stop = marlin_int(self._after(cmd, "V")) != 0
        self._r3_ok(cmd, t)

    def _m2200_3x(self, cmd, t):
        moving = self._motion is not None or bool(self._queue)
        self._r3(cmd, t, 0, f"V{int(moving)}")

    def _m2213_3x(self, cmd, t):
        if self._seen(cmd, "V"):
            self._flags["keys"] = marlin_int(self._after(cmd, "V")) != 0
        self._r3_ok(cmd, t)

    def _effector_3x(self, name):
        def handler(cmd, t):
            if self._seen(cmd, "V"):
                setattr(self, "_" + name, 1 if marlin_int(self._after(cmd, "V")) & 0xFF else 0)
            self._r3_ok(cmd, t)
        return handler

    def _m2234_3x(self, cmd, t):
        if self._seen(cmd, "V"):
            self._flags["bluetooth"] = marlin_int(self._after(cmd, "V")) != 0
        self._r3_ok(cmd, t)

    def _m2245_3x(self, cmd, t):
        if not self._seen(cmd, "V"):
            self._r3(cmd, t, 25, "Format Error!")
            return
        self.bt_name = self._after(cmd, "V").strip()[:11]
        self._r3(cmd, t, 0, "")

    # -- Grove modules (3.x, uArmGrove2.cpp): ports 0..13, 22 module types, each allowed on
    # some ports (PortMask). Nothing is plugged into the simulated arm: a module on the I2C
    # port (the sensors and displays that answer on the bus) fails its init; UNCERTAIN: that
    # the digital and analog ones initialise without a module, as here.
    _GROVE_PORTS = 14
    _GROVE_MASKS = (0, 0x38, 0x38, 6, 0x338, 6, 6, 6, 6, 1, 1, 1, 0x310, 0x310, 0x338, 1, 0x338, 1, 0x338,
                    0x338, 6, 1)

    def _grove_arg(self, cmd, letters: str):
        """The 3.x Grove commands' arguments, or None (answered) when one is missing."""
        if not all(self._seen(cmd, c) for c in letters):
            self._r3(cmd, t=cmd.arrival, result=25, buf=f"format: {cmd.word} " + " ".join(f"{c}n" for c in letters)
                     + "\r\n")
            return None
        return [marlin_int(self._after(cmd, c)) & 0xFF for c in letters]

    def _m2304_3x(self, cmd, t):
        args = self._grove_arg(cmd, "P")
        if args is not None:
            self._grove.pop(args[0], None)
            self._r3(cmd, t, 0, "")

    def _m2305_3x(self, cmd, t):
        args = self._grove_arg(cmd, "PN")
        if args is None:
            return
        port, kind = args
        if port > self._GROVE_PORTS - 1:
            self._r3(cmd, t, 25, f"port num should less than {self._GROVE_PORTS}\r\n")
        elif kind > len(self._GROVE_MASKS) - 1:
            self._r3(cmd, t, 25, f"module num should less than {len(self._GROVE_MASKS)}\r\n")
        elif not self._GROVE_MASKS[kind] & (1 << port):
            valid = "".join(f"{i} " for i in range(self._GROVE_PORTS) if self._GROVE_MASKS[kind] & (1 << i))
            self._r3(cmd, t, 25, f"For module {kind}, valid port(s) is(are): {valid}\r\n")
        elif kind == 0:
            self._r3(cmd, t, 25, "Memory allocation failed\r\n")
        elif self._GROVE_MASKS[kind] == 1:
            self._r3(cmd, t, 25, "init failed\r\n")  # nothing answers on the I2C bus
        else:
            self._grove[port] = kind
            self._r3(cmd, t, 0, "")

    def _grove_port_3x(self, cmd, t):
        args = self._grove_arg(cmd, "PV" if cmd.word == "M2306" else "P")
        if args is None:
            return
        port = args[0]
        if port > self._GROVE_PORTS - 1:
            self._r3(cmd, t, 25, f"port num should less than {self._GROVE_PORTS}\r\n")
        elif port not in self._grove:
            self._r3(cmd, t, 25, f"port {port} not initialized\r\n")
        else:
            self._r3(cmd, t, 0, "")  # reports (@11) need a module that reads something: none here

    def _m2401_3x(self, cmd, t):
        # calibration needs an unlock code (V) or B; the code is not published: V fails.
        if self._seen(cmd, "B"):
            self._resync(t)
            self._r3(cmd, t, 0, "")
        else:
            self._r3(cmd, t, 25, "")

    def _m2411_3x(self, cmd, t):
        if self._seen(cmd, "S"):
            self._offsets["front"] = marlin_float(self._after(cmd, "S"))
            self._resync(t)
        self._r3_ok(cmd, t)

    def _m2500_3x(self, cmd, t):
        self._r3_ok(cmd, t)
        self._serial_moved = True  # commands now go to Serial2: this port hears nothing more

    def _g2203_3x(self, cmd, t):
        # stepper.synchronize(): the reply comes when the planned motion has ended. It is
        # not a stop (M2000 is).
        if self._motion is None and not self._queue:
            self._r3_ok(cmd, t)
        else:
            self._sync_waiters.append(cmd)

    def _g2202_3x(self, cmd, t):
        if self._seen(cmd, "N"):
            n = marlin_int(self._after(cmd, "N")) & 0xFF
            if n < 3 and self._seen(cmd, "V"):
                b, lo, up = self._believed_angles()
                v = marlin_float(self._after(cmd, "V"))
                if n == 0:
                    b = v - 90.0
                elif n == 1:
                    lo = v
                else:
                    up = v
                self._speed_3x(cmd)
                self._queue_move_3x(cmd, tool_position(b, lo, up), t)  # no legality check on 3.x
            elif n == 3 and self._seen(cmd, "V"):
                self._wrist = marlin_float(self._after(cmd, "V"))
        self._r3_ok(cmd, t)

    def _believed_angles(self):
        angles = joint_angles(*self._last_target)
        return angles[:3] if angles else (0.0, 90.0, 0.0)

    def _speed_3x(self, cmd) -> None:
        if self._seen(cmd, "F"):
            f = marlin_float(self._after(cmd, "F"))
            if f > 0:
                self._speed_set = f

    def _move_3x(self, cmd, t):
        """G0/G1/G2201/G2204/G2205 on 3.x: reachable -> queued and ``ok `` at once;
        unreachable -> ``ok E22 unreachable`` and a blank line (Marlin prints the reply
        buffer, which ends in ``\\r\\n``, with println)."""
        w = cmd.word
        base = self._last_target
        relative = self._relative or w in ("G2204", "G2205")
        if w in ("G2201", "G2205"):
            s0 = math.hypot(base[0], base[1])
            r0 = 90.0 + math.degrees(math.atan2(base[1], base[0]))
            cur = (s0, r0, base[2])
            polar = [marlin_float(self._after(cmd, c)) + (cur[i] if relative else 0) if self._seen(cmd, c)
                     else cur[i] for i, c in enumerate("SRH")]
            target = self._polar_target(*polar)
        else:
            target = tuple(marlin_float(self._after(cmd, c)) + (base[i] if relative else 0) if self._seen(cmd, c)
                           else base[i] for i, c in enumerate("XYZ"))
        if not is_reachable(*target):
            self._r3(cmd, t, 0, "E22 unreachable\r\n")
            return
        self._speed_3x(cmd)
        self._queue_move_3x(cmd, target, t)
        self._r3(cmd, t, 0, "")

    def _queue_move_3x(self, cmd, target, t) -> None:
        """Plan a 3.x move. The planner moves the joints from the angles it believes
        (current_position) to the target's: after a hand move the arm lands off by the
        hand's displacement until ``update_current_pos`` (M2400, M2000, ...) has run."""
        believed = joint_angles(*self._last_target)
        if self._motion is None and not self._queue:
            actual = joint_angles(*self._actual(t))
            self._joint_offset = ([a - b for a, b in zip(actual[:3], believed[:3])]
                                  if actual and believed else [0.0, 0.0, 0.0])
        self._last_target = target
        speed = self._speed_set / 60.0 if self._speed_set else None  # F in mm/min per the 3.x guide
        if speed is None:
            return
        self._enabled |= set(_STEPPERS)  # Marlin's planner enables the steppers it moves
        self._freeze_hand(t)
        land, goal = target, joint_angles(*target)
        if goal and any(abs(o) > 1e-9 for o in self._joint_offset):
            land = tool_position(*(g + o for g, o in zip(goal[:3], self._joint_offset)))
        cmd.target, cmd.speed = land, speed
        self._queue.append(cmd)
        self._advance(t)

    def _execute_queued_3x(self, cmd, t):
        """Start the 3.x move at the head of the planner (its reply was sent when queued)."""
        start = self._pos
        self._motion = _Motion(cmd, start, cmd.target, t,
                               t + math.dist(start, cmd.target) / cmd.speed * self.motion_scale)
        if self._motion.t1 <= t:
            self._finish_motion()
