"""How the arm may move: the safety envelope on every move, stop, pause/resume, home.

The policy between a caller's ``move_to`` and the wire:

* a move is checked against the :class:`SafetyEnvelope` (target, step, path, speed), then
  the arm is asked (M2222) whether it can reach the target, and only then sent. Nothing
  here sends raw G-code on a caller's behalf;
* an arm outside the envelope (as after power-up) is never moved by :meth:`MotionPolicy.move_to`,
  which refuses: an experimenter brings it in with :meth:`MotionPolicy.home`, which lifts it
  into the height band, moves it out of the hole round the base along its own yaw, then
  follows a polar path, at ``entry_speed_mm_s``, every leg checked (never further out than
  it was, at most ``max_step_mm``, reachable by M2222);
* :meth:`MotionPolicy.stop` always wins: it presses the :class:`StopSwitch` (so every move
  that began before it refuses to be sent), bypasses the in-flight limit, and cuts the
  current move. On firmware 4.0-4.4, which has no planner clear, the stop is a pause
  (``S1000 V0``) and :meth:`MotionPolicy.resume` must be called before anything moves again.
"""

from __future__ import annotations

import math
import numbers
import threading
import time
from typing import Protocol

from .dialects import Dialect
from .envelope import SafetyEnvelope
from .errors import SwiftProStopped, SwiftProTimeout, UnsafeMoveError
from .link import Pending, SerialLink
from .protocol import parse_values
from .stop import StopSwitch

Point = tuple[float, float, float]


class Arm(Protocol):
    """What the policy asks of the connector (:class:`mt_widgets.hardware.SwiftPro`)."""

    dialect: Dialect
    timeout: float

    def position(self) -> Point: ...

    def is_reachable(self, x: float, y: float, z: float) -> bool: ...


def _wire(point) -> Point:
    """Rounded to the 4 decimals that go on the wire, so what is checked is what is sent."""
    return tuple(round(float(v), 4) for v in point)


class MotionPolicy:
    """Moves, stops and resumes one arm within its safety envelope.

    Args:
        arm: the connector, asked for its position, reachability and firmware dialect.
        link: its serial link, on which moves are sent.
        switch: the stop switch shared with whoever else drives the arm (the bridge).
        envelope: the safety envelope.
    """

    def __init__(self, arm: Arm, link: SerialLink, switch: StopSwitch, envelope: SafetyEnvelope):
        self._arm, self._link, self._switch, self.envelope = arm, link, switch, envelope
        # One move (or home, or resume) at a time: each is checked from where the previous
        # one ended (``_last_target``), which a second move under way would falsify. Held for
        # a whole move; stop() never takes it.
        self._lock = threading.Lock()
        self._last_target: Point | None = None
        self._current_move: Pending | None = None
        self._current_target: tuple[float, float, float, float] | None = None  # x, y, z mm and speed mm/s
        self._stopped = False
        # Firmware 4.0-4.4: stop() paused the arm (S1000 V0); nothing may be queued until
        # resume(), and the target of the move the pause cut short (x, y, z, speed) or None.
        self._paused = False
        self._paused_target: tuple[float, float, float, float] | None = None

    # ------------------------------------------------------------------ state
    @property
    def paused(self) -> bool:
        return self._paused

    def forget_position(self) -> None:
        """The arm may have moved by other means: read its position before the next move."""
        self._last_target = None

    def connected_at(self, position: Point | None) -> None:
        """A new connection: the board was reset (the protocol notes: probably, through DTR),
        which ends a pause; ``position`` is where the arm is."""
        self._current_move = None
        self._paused = False
        self._paused_target = None
        self._last_target = position

    def refuse_while_paused(self, command: str) -> None:
        """While paused (4.0-4.4), G and M commands would queue behind the cut move and never
        be answered: refuse them at once."""
        if self._paused and command[:1] in ("G", "M"):
            raise SwiftProStopped(f"{command!r} was not sent: the arm is paused by stop(); call resume() first")

    def generation_since(self, unless_stopped_since: int | None) -> int:
        """The stop generation a move must see unchanged: the current one, or the one given
        (a job's), after checking no stop came since."""
        current = self._switch.generation
        if unless_stopped_since is None:
            return current
        if not (isinstance(unless_stopped_since, numbers.Integral) and not isinstance(unless_stopped_since, bool)
                and 0 <= unless_stopped_since <= current):
            raise ValueError(f"unless_stopped_since: expected a stop_generation read earlier, an integer in "
                             f"0..{current}, got {unless_stopped_since!r}")
        if unless_stopped_since != current:
            raise SwiftProStopped(f"not moving: stop() was called since generation {unless_stopped_since}")
        return int(unless_stopped_since)

    # ------------------------------------------------------------------ moves
    def move_to(self, target: Point, speed: float, generation: int) -> None:
        """Check and send one move to ``target`` (mm, inside the envelope); see ``SwiftPro.move_to``."""
        self._move(self._checked_target(target), speed, generation, homing=False)

    def _checked_target(self, target) -> Point:
        return self.envelope.check_point(*_wire(self.envelope.check_point(*target)))

    def home(self, target: Point, speed: float | None, max_segment_mm: float, generation: int) -> list[Point]:
        """Bring the arm into the envelope along :meth:`SafetyEnvelope.entry_path`; see ``SwiftPro.home``."""
        target = self._checked_target(target)
        speed = self.envelope.check_speed(self.envelope.entry_speed_mm_s if speed is None else speed, entering=True)
        self._link.check_alive()
        with self._lock:
            self._last_target = None  # read where the arm really is, not where it was sent
            start = self._arm.position()
            legs = [_wire(leg) for leg in self.envelope.entry_path(start, target, max_segment_mm)]
        for leg in legs:
            self._move(leg, speed, generation, homing=True)
        return legs

    def _move(self, target: Point, speed: float, generation: int, *, homing: bool) -> None:
        """Check the move from where the arm is to ``target`` and send it (``home`` legs may
        start and end outside the envelope)."""
        self._link.check_alive()
        with self._lock:
            if self._paused:
                raise SwiftProStopped("the arm is paused by stop(); call resume() first")
            start = self._last_target if self._last_target is not None else self._arm.position()
            try:
                self.envelope.check_point(*start)
                inside = True
            except UnsafeMoveError as outside:
                if not homing:
                    raise UnsafeMoveError(
                        f"the arm is at {tuple(round(v, 3) for v in start)} mm, outside the safety envelope "
                        f"({outside}); nothing was sent: an experimenter must bring it in with home() first",
                        coordinate=outside.coordinate, value=outside.value, limit=outside.limit) from outside
                inside = False
            speed = self.envelope.check_speed(speed, entering=homing)
            if inside:
                self.envelope.check_segment(start, target)
            else:
                self.envelope.check_entering_segment(start, target)
            if not self._arm.is_reachable(*target):
                raise UnsafeMoveError(
                    f"the arm says (x, y, z) = {target} mm is unreachable (M2222 answered V0)",
                    coordinate="target", value=math.hypot(target[0], target[1]), limit=None)
            dialect = self._arm.dialect
            duration = math.dist(start, target) / speed
            self._stopped = False
            self._last_target = None  # unknown until the move is confirmed
            self._current_target = (*target, speed)
            pending = self._send(dialect.move_word, ("X", target[0]), ("Y", target[1]), ("Z", target[2]),
                                 ("F", speed * dialect.feed_per_mm_s), generation=generation)
            wait_s = self._arm.timeout + 1.5 * duration
            try:
                self._link.wait(pending, wait_s)
                if dialect.ok_when_queued:
                    self._wait_motion_end(deadline=time.monotonic() + wait_s)
            finally:
                self._current_move = None
            if self._stopped:
                raise SwiftProStopped(f"move to {target} mm was stopped")
            self._last_target = target

    def _send(self, command: str, *params: tuple[str, float], generation: int, while_paused: bool = False
              ) -> Pending:
        """Send a request that a stop cuts: only if no stop came since ``generation``
        (checked and sent under the switch's lock), and it becomes the current move."""
        if not while_paused:
            self.refuse_while_paused(command)

        def on_sent(pending: Pending) -> None:
            self._current_move = pending

        return self._link.submit(command, *params, guard=self._switch.unless_pressed_since(generation, repr(command)),
                                 on_sent=on_sent)

    def _wait_motion_end(self, deadline: float) -> None:
        # 3.x answers "ok" when the move is queued; poll M2200 for its end.
        while True:
            values = parse_values(self._link.request("M2200").payload)
            if values.get("V") == 0 or self._stopped:
                return
            if time.monotonic() > deadline:
                raise SwiftProTimeout("the 3.x arm still reports moving (M2200 V1) after the expected duration")
            time.sleep(0.01)

    # ------------------------------------------------------------------ stop and resume
    def stop(self) -> None:
        """Press the switch, send the dialect's stop command (never waiting for a slot) and
        cut the current move; see ``SwiftPro.stop``."""
        dialect = self._arm.dialect

        def cut() -> Pending | None:
            self._stopped = True
            move = self._current_move
            if dialect.stop_pauses:
                # Paused from now on, even if the reply is lost: refusing moves is the safe side.
                if move is not None and self._current_target is not None:
                    self._paused_target = self._current_target
                self._paused = True
            return move

        move = self._switch.press(cut)
        try:
            self._link.request(*dialect.stop_command, bypass_limit=True)
        finally:
            if move is not None:
                # Whether the firmware ever answers the cut move is UNCERTAIN: retire its number.
                self._link.retire(move, SwiftProStopped(f"{move.command!r} was stopped"))
            self._last_target = None

    def resume(self) -> None:
        """Release the switch; on 4.0-4.4 first un-pause and wait for the cut move to end;
        see ``SwiftPro.resume``."""
        seen = self._switch.generation
        self._link.check_alive()
        with self._lock:
            dialect = self._arm.dialect
            if not self._paused:
                self._switch.release(seen)
                return
            target = self._paused_target
            # Sent like a move, only if no stop came since resume began: a stop either finds
            # it on the wire, and its S1000 V0 follows, or wins.
            pending = self._send(*dialect.resume_command, generation=seen)
            try:
                self._link.wait(pending, self._arm.timeout)
            finally:
                self._current_move = None
            here = self._arm.position()
            wait_s = self._arm.timeout
            if target is not None:
                wait_s += 1.5 * math.dist(here, target[:3]) / target[3]
            # 4.x answers G/M commands only when idle: a harmless M2222 question queued behind
            # the old move is answered when that move has ended.
            barrier = here if target is None else target[:3]
            pending = self._send("M2222", ("X", barrier[0]), ("Y", barrier[1]), ("Z", barrier[2]), ("P", 0),
                                 generation=seen, while_paused=True)
            try:
                self._link.wait(pending, wait_s)
            finally:
                self._current_move = None

            def unpause() -> None:
                self._paused = False
                self._paused_target = None

            self._switch.release(seen, while_locked=unpause)
            self._last_target = self._arm.position()
