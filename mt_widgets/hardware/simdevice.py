"""A simulated uArm Swift Pro: the device model, pure Python, no serial port.

It behaves as ``docs/uarm-protocol.md`` ("What the simulated device does") describes, for the
firmware 4.x profile (default) and the 3.x profile. Time is passed in explicitly (``now``,
seconds on any monotonic clock), so the model is deterministic; the pyserial adapter
(:mod:`mt_widgets.hardware.urlhandler.protocol_uarmsim`) and the pseudo-terminal test server
drive it with ``time.monotonic``.

Host side: :meth:`SimulatedSwiftPro.write` takes bytes from the host,
:meth:`SimulatedSwiftPro.read_available` gives the bytes due by ``now``, and
:meth:`SimulatedSwiftPro.next_due` says when something will next happen.

Approximations, on purpose: moves are straight lines at constant speed (4.x G0 is
joint-space on the real arm); reachability follows the 4.x rule for the suction mode in
every mode and in both profiles (see :func:`is_reachable`).
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

from .protocol import is_fixed_decimal

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

#: 4.x queues this many G/M commands; the next one gets a bare ``E23``.
QUEUE_SIZE = 20

_REALTIME = frozenset(b"?!~@\x18")


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


def is_reachable(x: float, y: float, z: float) -> bool:
    """Whether the simulated arm can put its tool at (x, y, z) mm (4.x rule, mode 0)."""
    if not all(math.isfinite(v) for v in (x, y, z)):
        return False
    angles = joint_angles(x, y, z)
    if angles is None:
        return False
    base, lower, upper, between = angles
    return (abs(base) <= BASE_LIMIT_DEG
            and LOWER_ARM_LIMITS_DEG[0] <= lower <= LOWER_ARM_LIMITS_DEG[1]
            and UPPER_ARM_LIMITS_DEG[0] <= upper <= UPPER_ARM_LIMITS_DEG[1]
            and BETWEEN_ARMS_LIMITS_DEG[0] <= between <= BETWEEN_ARMS_LIMITS_DEG[1])


@dataclass
class _Command:
    number: int | None
    word: str
    params: dict[str, float]
    text: str
    arrival: float
    target: tuple[float, float, float] | None = None
    speed: float | None = None
    reply_sent: bool = False
    lose_reply: bool = False


@dataclass
class _Motion:
    command: _Command
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


_PROFILES = {
    4: _Profile("V4.10.0", "V3.3.1", "V4.0.1", b"\n"),
    3: _Profile("V3.2.0", "V3.3.1", "V3.2.0", b"\r\n"),
}

# Parameters each command takes; the 4.x parser wants all of them, in order, for the
# fixed-pattern commands (docs/uarm-protocol.md "Framing").
_FIXED_4X = {"G2201": "SRHF", "G2204": "XYZF", "G2205": "SRHF", "M2222": "XYZP", "M2210": "FT"}
_ALLOWED = {
    "G0": "XYZF", "G1": "XYZF", "G2201": "SRHF", "G2204": "XYZF", "G2205": "SRHF",
    "M17": "", "M2019": "", "M2201": "N", "M2202": "N", "M2203": "N", "M2222": "XYZPS",
    "M2210": "FT", "M2120": "V", "M2121": "", "M2122": "V", "M2400": "S", "M2231": "V",
    "M2232": "V", "P2200": "", "P2201": "", "P2202": "", "P2203": "", "P2204": "", "P2205": "",
    "P2220": "", "P2221": "", "P2233": "", "P2234": "", "P2400": "", "S1000": "V", "S1100": "",
}
_MOVES = {"G0", "G1", "G2201", "G2204", "G2205"}
_ONLY_3X = {"M2200": "", "G2203": ""}
_ONLY_4X = {"S1000", "S1100"}


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
            self._motion: _Motion | None = None
            self._t_free = now
            self._paused = False
            self._pos = tuple(float(v) for v in self.start)
            self._last_target = self._pos
            self._speed_set: float | None = None
            self._attached = {0, 1, 2, 3}
            self._mode = 0
            self._report_interval: float | None = None
            self._next_report = math.inf
            self._report_stop = False
            self._next_chatter = math.inf  # set when the banner is out

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

    def moving_at(self, t: float) -> bool:
        """Whether the tool is moving at ``t`` (for tests that wait for a move to be under way)."""
        with self.lock:
            self._advance(t)
            return self._motion is not None and self._motion.t0 <= t < self._motion.t1

    def position_at(self, t: float) -> tuple[float, float, float]:
        """Where the tool is at ``t`` (encoder truth, whatever the profile reports)."""
        with self.lock:
            self._advance(t)
            return self._motion.at(t) if self._motion else self._pos

    # ------------------------------------------------------------------ internals
    def _emit(self, line: str, t: float, *, reply: bool = False) -> None:
        data = line.encode("ascii") + self._profile.newline
        due = t + self.latency
        if self.baud:
            due = max(due, self._wire_free) + 10.0 * len(data) / self.baud
            self._wire_free = due
        self._seq += 1
        heapq.heappush(self._out, (due, self._seq, data))
        if self.firmware == 3 and reply and self._seq % 3 == 0:
            # 3.x sometimes adds a blank line (docs/uarm-protocol.md "Link").
            self._seq += 1
            heapq.heappush(self._out, (due, self._seq, b"\r\n"))

    def _reply(self, cmd: _Command, text: str, t: float) -> None:
        if cmd.reply_sent:
            return
        cmd.reply_sent = True
        if cmd.lose_reply:
            return
        prefix = "" if cmd.number is None else f"${cmd.number} "
        self._emit(prefix + text, t, reply=True)

    def _error(self, cmd: _Command, code: int, t: float) -> None:
        if code == 22 and self.firmware == 3:
            self._reply(cmd, "ok E22 unreachable", t)  # 3.x form: "ok" and an E token
        else:
            self._reply(cmd, f"E{code}", t)

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
                x, y, z = self._motion.at(t) if self._motion else self._pos
                self._emit(f"@3 X{x:.4f} Y{y:.4f} Z{z:.4f} R90.0000", t)
                self._next_report = t + self._report_interval
            elif t == self._next_chatter:
                self._chat(t)
                self._next_chatter = t + self.chatter
            else:
                self._execute(self._queue[0], t)

    def _banner(self, t: float) -> None:
        if self.chatter:
            self._next_chatter = t + self.chatter
        if self.firmware == 4:
            for line in (f"device name : {self.device_name}", f"soft ver : {self._profile.firmware}",
                         f"hard ver : {self._profile.hardware}", f"api ver : {self._profile.api}", "@1"):
                self._emit(line, t)
        else:
            for line in ("start", f"echo: {self.device_name} {self._profile.firmware}", ""):
                self._emit(line, t)

    def _chat(self, t: float) -> None:
        x, y, z = self._motion.at(t) if self._motion else self._pos
        line = self._rng.choice([f"@3 X{x:.4f} Y{y:.4f} Z{z:.4f} R90.0000", "@5 V1",
                                 f"@6 N0 V{self._rng.randint(0, 1)}", "@9 V0"])
        self._emit(line, t)

    def _finish_motion(self) -> None:
        m = self._motion
        self._motion = None
        self._pos = m.target
        self._t_free = m.t1
        if self._queue and self._queue[0] is m.command:
            self._queue.popleft()
        self._reply(m.command, "ok", m.t1)
        if self._report_stop:
            self._emit("@9 V0", m.t1)

    def _line(self, raw: str, now: float) -> None:
        self.received_lines.append(raw)
        if self._disconnect_after is not None:
            self._disconnect_after -= 1
            if self._disconnect_after <= 0:
                self._disconnect_after = None
                self.disconnected = True
                return
        if self.firmware == 4:
            # 4.x drops white space, upper-cases, keeps 80 characters (docs/uarm-protocol.md "Link").
            text = re.sub(r"\s", "", raw).upper()[:80]
        else:
            text = raw.strip()
        if not text:
            return
        number = None
        m = re.match(r"#(\d+)\s*", text)
        if m:
            number, text = int(m.group(1)), text[m.end():]
        m = re.match(r"([GMPS]\d+)", text)
        word = m.group(1) if m else text.split()[0] if text.split() else text
        cmd = _Command(number, word, {}, text, now)
        self._lines_since_boot += 1
        if self._drop_line == self._lines_since_boot:
            cmd.lose_reply = True
        elif self._drop_replies > 0:
            self._drop_replies -= 1
            cmd.lose_reply = True
        known = (word in _ALLOWED and not (self.firmware == 3 and word in _ONLY_4X)
                 and not (word == "S1100" and self.version_tuple < (4, 5, 0))) or (
            self.firmware == 3 and word in _ONLY_3X)
        if not m or not known:
            if self.firmware == 4:
                self._reply(cmd, "E20", now)
            else:
                self._emit(f'echo:Unknown command: "{raw.strip()}"', now)
            return
        rest = text[m.end():]
        tokens = re.findall(r"[A-Z][^A-Z\s]*", rest) if self.firmware == 4 else rest.split()
        allowed = _ALLOWED.get(word, _ONLY_3X.get(word, ""))
        letters = "".join(tok[0] for tok in tokens)
        for tok in tokens:
            if tok[0] not in allowed or not is_fixed_decimal(tok[1:]) or tok[0] in cmd.params:
                self._error(cmd, 21, now)
                return
            cmd.params[tok[0]] = float(tok[1:])
        fixed = _FIXED_4X.get(word)
        if fixed and (letters != fixed if self.firmware == 4 else not set(fixed[:-1]) <= set(letters)):
            self._error(cmd, 21, now)
            return
        if word in ("M2201", "M2202", "M2203") and "N" not in cmd.params:
            self._error(cmd, 21, now)
            return
        if word[0] in "PS" or word == "M2200" or word == "G2203":
            self._immediate(cmd, now)
        elif self.firmware == 4:
            if len(self._queue) >= QUEUE_SIZE:
                self._emit("E23 buffer full", now)  # bare: no number (docs/uarm-protocol.md)
                return
            self._queue.append(cmd)
            self._advance(now)
        elif word in _MOVES:
            self._queue_move_3x(cmd, now)
        else:
            self._execute(cmd, now)

    def _current(self, t: float) -> tuple[float, float, float]:
        return self._motion.at(t) if self._motion else self._pos

    def _immediate(self, cmd: _Command, t: float) -> None:
        w = cmd.word
        if w == "P2220":
            # 4.x reads the encoders, even mid-move; 3.x answers its last target (SDK #2).
            x, y, z = self._current(t) if self.firmware == 4 else self._last_target
            self._reply(cmd, f"ok X{x:.4f} Y{y:.4f} Z{z:.4f}", t)
        elif w == "P2221":
            x, y, z = self._current(t) if self.firmware == 4 else self._last_target
            self._reply(cmd, f"ok S{math.hypot(x, y):.4f} R{90 + math.degrees(math.atan2(y, x)):.4f} H{z:.4f}", t)
        elif w == "P2200":
            angles = joint_angles(*self._current(t))
            b, lo, up = angles[:3] if angles else (0.0, 0.0, 0.0)
            self._reply(cmd, f"ok B{90 + b:.4f} L{lo:.4f} R{up:.4f}", t)
        elif w == "P2201":
            self._reply(cmd, "ok " + ("V" if self.firmware == 3 else "") + self.device_name, t)
        elif w == "P2202":
            self._reply(cmd, f"ok {self._profile.hardware}", t)
        elif w == "P2203":
            self._reply(cmd, f"ok {self._profile.firmware}", t)
        elif w == "P2204":
            self._reply(cmd, f"ok {self._profile.api}", t)
        elif w == "P2205":
            self._reply(cmd, "ok 5357494654505230", t)
        elif w == "P2234":
            self._reply(cmd, "ok V1", t)
        elif w == "P2233":
            self._reply(cmd, "ok V0", t)
        elif w == "P2400":
            self._reply(cmd, f"ok V{self._mode}", t)
        elif w == "M2200":
            moving = self._motion is not None or bool(self._queue)
            self._reply(cmd, f"ok V{int(moving)}", t)
        elif w in ("S1000", "S1100", "G2203"):
            if self._motion:
                self._pos = self._motion.at(t)
                self._motion = None
            if w == "S1000" and cmd.params.get("V", 0) != 0:
                self._paused = False
                self._t_free = t
            elif w == "S1000":
                # the head of the queue keeps its target and restarts from here on resume
                self._paused = True
            else:
                # S1100 (4.5+) / G2203 (3.x) clear the planner. UNCERTAIN: whether the
                # cleared commands are ever answered; here they are not.
                self._queue.clear()
                self._paused = False
                self._t_free = t
                self._last_target = self._pos
            self._reply(cmd, "ok", t)

    def _move_target(self, cmd: _Command, base: tuple[float, float, float]):
        p = cmd.params
        if cmd.word in ("G0", "G1"):
            return (p.get("X", base[0]), p.get("Y", base[1]), p.get("Z", base[2]))
        if cmd.word == "G2204":
            return (base[0] + p.get("X", 0.0), base[1] + p.get("Y", 0.0), base[2] + p.get("Z", 0.0))
        s0 = math.hypot(base[0], base[1])
        r0 = 90.0 + math.degrees(math.atan2(base[1], base[0]))
        if cmd.word == "G2201":
            s, r, h = p["S"], p["R"], p["H"]
        else:
            s, r, h = s0 + p["S"], r0 + p["R"], base[2] + p["H"]
        a = math.radians(r - 90.0)
        return (s * math.cos(a), s * math.sin(a), h)

    def _speed(self, cmd: _Command) -> float | None:
        if "F" in cmd.params:
            self._speed_set = cmd.params["F"]
        f = self._speed_set
        if not f or f <= 0:
            return None
        if self.firmware == 3:
            return f / 60.0  # mm/min per the 3.x guide
        # 4.x: F taken as mm/s, linear moves capped at 100, others at 200 (docs/uarm-protocol.md).
        return min(f, 100.0 if cmd.word in ("G1", "G2204") else 200.0)

    def _queue_move_3x(self, cmd: _Command, t: float) -> None:
        target = self._move_target(cmd, self._last_target)
        if not is_reachable(*target):
            self._error(cmd, 22, t)
            return
        speed = self._speed(cmd)
        self._last_target = target
        cmd.target, cmd.speed = target, speed
        # 3.x answers when the move is queued; hosts poll M2200 for its end.
        self._reply(cmd, "ok", t)
        if speed is not None and len(self._attached) == 4:
            self._queue.append(cmd)
            self._advance(t)

    def _execute(self, cmd: _Command, t: float) -> None:
        """Run the command at the head of the queue (4.x), or an M command now (3.x)."""
        w, p = cmd.word, cmd.params
        in_queue = bool(self._queue) and self._queue[0] is cmd
        if w in _MOVES:
            if self.firmware == 3:  # a queued 3.x move: its reply is already sent
                self._motion = _Motion(cmd, self._pos, cmd.target, t,
                                       t + math.dist(self._pos, cmd.target) / cmd.speed * self.motion_scale)
                if self._motion.t1 <= t:
                    self._finish_motion()
                return
            if cmd.target is None:
                cmd.target = self._move_target(cmd, self._pos)
                cmd.speed = self._speed(cmd)
            if len(self._attached) < 4:
                self._queue.popleft()
                self._t_free = t
                self._error(cmd, 27, t)
                return
            if not is_reachable(*cmd.target):
                self._queue.popleft()
                self._t_free = t
                self._error(cmd, 22, t)
                return
            if cmd.speed is None:  # 4.x with no F yet: "ok" without moving
                self._queue.popleft()
                self._t_free = t
                self._reply(cmd, "ok", t)
                return
            duration = math.dist(self._pos, cmd.target) / cmd.speed * self.motion_scale
            self._last_target = cmd.target
            self._motion = _Motion(cmd, self._pos, cmd.target, t, t + duration)
            if duration <= 0:
                self._finish_motion()
            return
        if in_queue:
            self._queue.popleft()
            self._t_free = t
        if w == "M17":
            self._attached = {0, 1, 2, 3}
        elif w == "M2019":
            self._attached = set()
        elif w in ("M2201", "M2202", "M2203"):
            n = int(p["N"])
            if n not in (0, 1, 2, 3):
                self._error(cmd, 21, t)
                return
            if w == "M2201":
                self._attached.add(n)
            elif w == "M2202":
                self._attached.discard(n)
            else:
                self._reply(cmd, f"ok V{int(n in self._attached)}", t)
                return
        elif w == "M2222":
            ok = is_reachable(p["X"], p["Y"], p["Z"])
            self._reply(cmd, f"ok V{int(ok)}", t)
            return
        elif w == "M2210":
            self.beeps.append((p.get("F", 1000.0), p.get("T", 200.0)))
        elif w == "M2120":
            v = p.get("V", 0.0)
            self._report_interval = v if v > 0 else None
            self._next_report = t + v if v > 0 else math.inf
        elif w == "M2121":
            self._report_interval, self._next_report = None, math.inf
        elif w == "M2122":
            self._report_stop = p.get("V", 0.0) != 0
        elif w == "M2400":
            self._mode = int(p.get("S", 0))
        self._reply(cmd, "ok", t)
