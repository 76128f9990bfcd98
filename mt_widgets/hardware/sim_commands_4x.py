"""The simulated uArm Swift Pro's 4.x command set (grbl-based firmware).

How 4.x reads a line (white space dropped, upper case, 80 characters, ``#n`` numbers), its
queue of G/M commands, its moves (G0/G1 and the fixed-pattern G22xx moves, checked as
``mc_line`` does), and the commands only 4.x has; the command table is uarm_protocol.c's
G/M/P/S switches (docs/uarm-protocol.md "The command table"). The commands both firmwares
know are in sim_commands.py. A mixin of :class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`.
"""

from __future__ import annotations

import math
import re

from .sim_firmware import Command, Motion
from .sim_grammar import grbl_read_float, grbl_words, scan4, scan_pattern
from .sim_kinematics import (
    BASE_LIMIT_DEG,
    LOWER_ARM_LIMITS_DEG,
    UPPER_ARM_LIMITS_DEG,
    axis_edge,
    is_reachable,
    joint_angles,
    joint_limit,
    tool_position,
)

#: 4.x queues this many G/M commands; the next one gets a bare ``E23 buffer full``.
QUEUE_SIZE = 20


class Commands4x:
    """The 4.x firmware's line reader, queue execution, moves and own commands."""

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

    def _execute_queued_4x(self, cmd: Command, t: float) -> None:
        """The 4.x command at the head of the queue: a move starts, any other G/M command runs."""
        if cmd.word in self._moves_4x:
            self._start_move_4x(cmd, t)
            return
        self._queue.popleft()
        self._t_free = t
        self._dispatch_4x(cmd, t)

    def _dispatch_4x(self, cmd: Command, t: float) -> None:
        handler = self._handlers.get(cmd.word)
        if handler is None:
            self._r4(cmd, t, 20)  # grbl: unsupported command
            return
        handler(cmd, t)

    def _start_move_4x(self, cmd: Command, t: float) -> None:
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
        self._motion = Motion(cmd, start, cmd.target, t, t + duration)
        if duration <= 0:
            self._finish_motion()

    def _speed_4x(self, f: float, linear: bool) -> float | None:
        # 4.x: F taken as mm/s, linear moves capped at 100, others at 200 (docs/uarm-protocol.md).
        return min(f, 100.0 if linear else 200.0) if f and f > 0 else None

    def _g0_g1(self, cmd: Command, t: float):
        words = grbl_words(cmd.args)
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

    def _fixed_move(self, spec: str, cmd: Command, to_target, linear: bool):
        """A 4.x move with a fixed pattern (every field, in order, or E21)."""
        pattern = scan_pattern(spec)
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
        fields = scan4(scan_pattern("N d F f"), cmd.args)
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

    def _g2209(self, cmd, t):
        fields = scan4(scan_pattern("F f"), cmd.args)
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
            "G2207": lambda c, t: self._jog(c, t, axis_edge),
            "G2208": lambda c, t: self._jog(c, t, joint_limit),
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

    def _char_arg(self, cmd, letter: str, allowed: str) -> int | None:
        """The 4.x check ``line[0] == letter && line[1] in allowed``: the digit, or None."""
        a = cmd.args
        return int(a[1]) if len(a) >= 2 and a[0] == letter and a[1] in allowed else None

    def _g2004_4x(self, cmd, t):
        fields = scan4(scan_pattern("P d"), cmd.args)
        if not fields:
            self._r4(cmd, t, 21)
            return
        self._r4(cmd, t)
        self._t_free = t + max(0, int(fields[0])) / 1000.0  # the next queued command waits

    def _m204_4x(self, cmd, t):
        fields = scan4(scan_pattern("A f"), cmd.args)
        v = grbl_read_float(fields[0]) if fields else None
        if v is None:
            self._r4(cmd, t, 21)
            return
        self._acceleration = v
        self._r4(cmd, t)

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

    def _m2205_4x(self, cmd, t):
        fields = scan4([("VUB", "h")], cmd.args)
        if not fields:
            self._r4(cmd, t, 21)
            return
        self.uid = (fields[0] + self.uid)[:12] if len(fields[0]) < 12 else fields[0][:12]
        self._r4(cmd, t)

    def _three_floats4(self, cmd, t, letters: str) -> list | None:
        """A 4.x command's three float fields (``letters`` in order), or None after answering E21."""
        fields = scan4(scan_pattern(" ".join(f"{c} f" for c in letters)), cmd.args)
        values = [grbl_read_float(v) for v in fields]
        if len(fields) < 3 or None in values:
            self._r4(cmd, t, 21)
            return None
        return values

    def _effector_4x(self, name, allowed):
        def handler(cmd, t):
            v = self._char_arg(cmd, "V", allowed)
            if v is None:
                self._r4(cmd, t, 21)
                return
            setattr(self, "_" + name, 1 if v else 0)
            self._r4(cmd, t)
        return handler

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

    def _p2236(self, cmd, t):
        fields = scan4(scan_pattern("N d"), cmd.args)
        if not fields or int(fields[0]) not in (0, 1):
            self._r4(cmd, t, 21)
            return
        self._r4(cmd, t, 0, " V0")  # nobody presses the arm's buttons

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
