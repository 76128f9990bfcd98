"""The simulated uArm Swift Pro's 3.x command set (Marlin-based firmware).

How 3.x reads a line (Marlin's ``#n``, ``N`` line numbers and ``*`` checksums), its command
table (Marlin_main.cpp's uArm G/M/P cases, docs/uarm-protocol.md "The command table"), its
moves (answered when planned, run from the planner from the angles it believes), the Grove
modules, and the commands only 3.x has. The commands both firmwares know are in
sim_commands.py. A mixin of :class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`.
"""

from __future__ import annotations

import math
import re

from .sim_firmware import Motion
from .sim_grammar import marlin_float, marlin_int
from .sim_kinematics import STEPPERS, is_reachable, joint_angles, tool_position


class Commands3x:
    """The 3.x firmware's line reader, moves, Grove modules and own commands."""

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
        self._enabled |= set(STEPPERS)  # Marlin's planner enables the steppers it moves
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
        self._motion = Motion(cmd, start, cmd.target, t,
                               t + math.dist(start, cmd.target) / cmd.speed * self.motion_scale)
        if self._motion.t1 <= t:
            self._finish_motion()
