"""The commands both firmwares of the simulated uArm Swift Pro know, each answered in its dialect.

The steppers (M17, M2019, M2201..M2203), reports (M2120, M2121), the buzzer (M2210), the
coordinate conversions (M2220..M2222), pins (M2240, M2241, P2240, P2241), modes and offsets
(M2400, M2410) and the position and angle queries (P2200, P2206, P2220, P2221, P2242): one
handler a command, which reads its arguments and answers as 4.x (grbl patterns, ``$n ok V1``)
or as 3.x (Marlin letters, ``$n ok V1`` with 3.x's faults) does. A mixin of
:class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`.
"""

from __future__ import annotations

import math
import re

from .sim_grammar import grbl_read_float, marlin_after, marlin_float, marlin_int, marlin_seen, scan4, scan_pattern
from .sim_kinematics import STEPPERS, is_reachable, joint_angles, tool_position

#: 4.x bits of ``motor_state_bits`` set/cleared by M2201/M2202 N0..N3 (base, lower, upper, wrist)...
BIT_OF_JOINT_4X = {0: 0x04, 1: 0x01, 2: 0x02, 3: 0x08}
#: ...and the bit M2203 N0..N3 reads: the firmware's M2203 N0 reads the bit M2201 N1 sets.
BIT_READ_4X = {0: 0x01, 1: 0x02, 2: 0x04, 3: 0x08}


class SharedCommands:
    """The handlers of the commands in both command tables."""

    def _polar_target(self, s: float, r: float, h: float) -> tuple[float, float, float]:
        a = math.radians(r - 90.0)
        return (s * math.cos(a), s * math.sin(a), h)

    def _ok_only(self, cmd, t):
        self._r4(cmd, t) if self.firmware == 4 else self._r3_ok(cmd, t)

    def _m17(self, cmd, t):
        self._attach(set(STEPPERS), t)
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
                self._attach(set(STEPPERS), t)  # the firmware enables all three drivers for any of N0..N2
            else:
                self._servo_attached = True
            self._bits |= BIT_OF_JOINT_4X[n]
            self._r4(cmd, t)
            return
        if n in STEPPERS:
            self._attach({n}, t)
        elif n == 3:
            self._servo_attached = True
        self._r3_ok(cmd, t)

    def _m2202(self, cmd, t):
        n = self._joint_arg(cmd)
        if self.firmware == 4 and n is None:
            self._r4(cmd, t, 21)
            return
        if n in STEPPERS:
            self._enabled.discard(n)
        elif n == 3:
            self._servo_attached = False
        if self.firmware == 4:
            self._bits &= ~BIT_OF_JOINT_4X[n]
        self._ok_only(cmd, t)

    def _m2203(self, cmd, t):
        n = self._joint_arg(cmd)
        if self.firmware == 4:
            if n is None:
                self._r4(cmd, t, 21)
                return
            self._r4(cmd, t, 0, f" V{int(bool(self._bits & BIT_READ_4X[n]))}")
            return
        attached = (n in self._enabled) if n in STEPPERS else (self._servo_attached if n == 3 else False)
        self._r3(cmd, t, 0, f"V{int(attached)}")

    def _m2210(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(scan_pattern("F u T d"), cmd.args)
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

    def _angles_text(self, base_plus_90, lower, upper) -> str:
        return f"B{self._num(base_plus_90)} L{self._num(lower)} R{self._num(upper)}"

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
            fields = scan4(scan_pattern("X f Y f Z f P d"), cmd.args)
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

    def _m2240(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(scan_pattern("N d V d"), cmd.args)
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
            fields = scan4(scan_pattern("N d V d"), cmd.args)
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
            fields = scan4(scan_pattern("N d"), cmd.args)
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

    # -- Marlin's arguments (3.x)
    @staticmethod
    def _seen(cmd, letter: str) -> bool:
        return marlin_seen(cmd.args, letter)

    @staticmethod
    def _after(cmd, letter: str) -> str:
        return marlin_after(cmd.args, letter)
