"""The simulated uArm Swift Pro's firmware loop: when things happen, how bytes leave.

The arm's clock runs only when the host calls in with ``now``: :meth:`FirmwareLoop._advance`
runs, in time order, everything due by then (the banner after boot, the end of a move, the
next queued command, position reports, chatter). Replies are framed here in each firmware's
format (``_r4`` for 4.x; ``_r3`` and ``_r3_ok`` for 3.x) and held until they are due; a line
from the host goes to its dialect's reader (``_line_4x`` in sim_commands_4x.py, ``_line_3x``
in sim_commands_3x.py). :class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro` composes
this loop with the command sets and owns the state it runs on.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass


@dataclass
class Command:
    """A command line the firmware took: its ``#n`` number, word (``G0``, ``M2201``...),
    arguments, arrival time and, for a move, the target and speed it was given."""

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
class Motion:
    """A straight move of the tool at constant speed from ``t0`` to ``t1`` (``command`` None:
    a person's hand)."""

    command: Command | None
    start: tuple[float, float, float]
    target: tuple[float, float, float]
    t0: float
    t1: float

    def at(self, t: float) -> tuple[float, float, float]:
        if t >= self.t1 or self.t1 <= self.t0:
            return self.target
        s = max(0.0, (t - self.t0) / (self.t1 - self.t0))
        return tuple(p + s * (q - p) for p, q in zip(self.start, self.target))


class FirmwareLoop:
    """The firmware's clock, output and input dispatch: a mixin of
    :class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`, on the state its ``power_on`` sets."""

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

    def _claim(self, cmd: Command) -> bool:
        """Mark a command answered; False if it was already, or its reply is to be lost."""
        if cmd.reply_sent:
            return False
        cmd.reply_sent = True
        return not cmd.lose_reply

    def _r4(self, cmd: Command, t: float, result: int | None = 0, tail: str = "") -> None:
        """A 4.x reply: ``$n ok V1`` / ``$n E21``; result None is a status grbl reports
        with nothing (``$n`` alone)."""
        if not self._claim(cmd):
            return
        head = "" if cmd.number is None else f"${cmd.number}"
        word = "" if result is None else ("ok" if result == 0 else f"E{result}")
        text = " ".join(p for p in (head, word) if p)
        self._emit(text + tail, t)

    def _r3_ok(self, cmd: Command, t: float) -> None:
        """3.x ``ok_to_send``: ``$n ok``."""
        if self._claim(cmd):
            self._emit(("" if cmd.number is None else f"${cmd.number} ") + "ok", t)

    def _r3(self, cmd: Command, t: float, result: int = 0, buf: str = "") -> None:
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

    def _new_command(self, number, word, args, text, now) -> Command:
        cmd = Command(number, word, args, text, now)
        self._lines_since_boot += 1
        if self._drop_line == self._lines_since_boot:
            cmd.lose_reply = True
        elif self._drop_replies > 0:
            self._drop_replies -= 1
            cmd.lose_reply = True
        return cmd

    # ------------------------------------------------------------------ the queue
    def _execute_queued(self, cmd: Command, t: float) -> None:
        """Run the command at the head of the queue: a 4.x G/M command, or a 3.x move."""
        if self.firmware == 3:
            self._execute_queued_3x(cmd, t)
        else:
            self._execute_queued_4x(cmd, t)

    def _cut_motion(self, t):
        if self._motion:
            self._pos = self._motion.at(t)
            self._motion = None
