"""The uArm Swift Pro connector over pyserial.

Facts about the arm come from ``/work/shared/UARM_PROTOCOL.md`` (collected from the
official firmware and SDK sources; cited below as "the doc"). Design in short:

* one reader thread splits the incoming bytes into lines; ``$n ...`` replies are matched
  to the numbered request ``#n ...`` that waits for them, everything else (``@1``, ``@3``,
  ``@5``, ``@6``, ``@9``, ``echo:`` lines, a bare ``E23``, banners) goes to the event queue
  and the event callbacks;
* numbers run 1..9999 and wrap, at most 2 requests in flight (as the official SDK); a
  request that times out has its number retired, so a late reply is dropped and never
  taken for the answer to a later request (resynchronisation);
* every wait has a timeout; a port that fails or closes wakes every waiter with
  :class:`SwiftProDisconnected`;
* a move is checked against the :class:`SafetyEnvelope` (target, step, path, speed), then
  the arm is asked (M2222) whether it can reach the target, and only then sent. There is
  no public method that sends raw G-code;
* an arm outside the envelope (as after power-up) is never moved by :meth:`SwiftPro.move_to`,
  which refuses: an experimenter brings it in with :meth:`SwiftPro.home`, which lifts it into
  the height band, moves it out of the hole round the base along its own yaw, then follows a
  polar path, at ``entry_speed_mm_s``, every leg checked (never further out than it was, at
  most ``max_step_mm``, reachable by M2222). Participant-facing code only calls ``home`` once
  at connection, from the experimenter's app;
* :meth:`SwiftPro.stop` always wins: it bypasses the 2-request in-flight limit, makes every
  move that began before it refuse to be sent (the stop generation, see
  :attr:`SwiftPro.stop_generation` and ``move_to(..., unless_stopped_since=...)``), and cuts
  the current one. On firmware 4.0-4.4, which has no planner clear, it pauses the arm
  (``S1000 V0``) and :meth:`SwiftPro.resume` must be called before anything moves again; see
  there for what happens to the move the pause cut short.
"""

from __future__ import annotations

import logging
import math
import numbers
import random
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import serial
from serial.serialutil import SerialException, SerialTimeoutException

from . import protocol
from .envelope import TEACHING_HEIGHT_MM, SafetyEnvelope, is_real
from .errors import (
    SwiftProCommandError,
    SwiftProDisconnected,
    SwiftProError,
    SwiftProNotFound,
    SwiftProPortBusy,
    SwiftProStopped,
    SwiftProTimeout,
    UnsafeMoveError,
    error_for_code,
)
from .protocol import Event, Reply

log = logging.getLogger(__name__)

#: USB id of the Arduino Mega 2560 inside the Swift and the Swift Pro (the doc, "Link").
USB_VID, USB_PID = 0x2341, 0x0042
#: URL of the simulated arm used when asked to fall back on it.
SIMULATOR_URL = "uarm-sim://?firmware=4"

_BUSY_HINTS = ("multiple access", "exclusively lock", "resource temporarily unavailable", "busy")


@dataclass
class _Pending:
    number: int
    command: str
    done: threading.Event
    reply: Reply | None = None
    error: BaseException | None = None
    released: bool = False
    #: False for stop commands, which bypass the in-flight limit (Stop must never wait for a slot).
    holds_slot: bool = True


def _port_error(port: str, exc: BaseException, doing: str) -> SwiftProDisconnected:
    text = str(exc)
    if any(h in text.lower() for h in _BUSY_HINTS):
        return SwiftProPortBusy(
            f"port {port!r} seems held by another program while {doing} ({text}); close other "
            "programs using the arm (uArm-Python-SDK issue #11)")
    return SwiftProDisconnected(f"port {port!r} failed while {doing}: {text}")


class SwiftPro:
    """A uArm Swift Pro on a serial port (or the simulated one).

    Args:
        port: a device path (``/dev/ttyACM0``, ``COM3``), a pyserial URL
            (``uarm-sim://?firmware=4``), or None / ``"auto"`` to find the arm by its USB id
            (2341:0042) and its P2201 answer.
        envelope: the safety envelope; the conservative default if None.
        teaching_height_mm: the height of moves that give no ``z``.
        default_speed_mm_s: the speed of moves that give no ``speed``.
        timeout: seconds to wait for a reply (moves get this plus their expected duration).
        ready_timeout: seconds to wait for the arm to boot after the port opens.
        max_in_flight: requests sent but not yet answered; 2 as in the official SDK (more than
            20 only to provoke the firmware's E23 in tests).
        simulate_if_absent: with ``port=None``/``"auto"``, use the simulated arm when no
            Swift Pro is plugged in instead of raising :class:`SwiftProNotFound`.

    Example:
        >>> with SwiftPro("uarm-sim://?boot=0.01") as arm:   # doctest: +SKIP
        ...     arm.move_to(200, 50)
        ...     arm.position()
    """

    def __init__(self, port: str | None = None, *, envelope: SafetyEnvelope | None = None,
                 teaching_height_mm: float = TEACHING_HEIGHT_MM, default_speed_mm_s: float = 50.0,
                 timeout: float = 2.0, ready_timeout: float = 5.0, max_in_flight: int = 2,
                 simulate_if_absent: bool = False):
        if port is not None and not isinstance(port, str):
            raise ValueError(f"port must be a device path, a pyserial URL, 'auto' or None, got {port!r}")
        for name, value in (("timeout", timeout), ("ready_timeout", ready_timeout)):
            if not (is_real(value) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive, finite number of seconds, got {value!r}")
        if not (isinstance(max_in_flight, numbers.Integral) and not isinstance(max_in_flight, bool)
                and 1 <= max_in_flight <= 32):
            raise ValueError(f"max_in_flight must be an integer in 1..32, got {max_in_flight!r}")
        if not is_real(teaching_height_mm):
            raise ValueError(f"teaching_height_mm must be a real number of mm in the envelope's height band, "
                             f"got {teaching_height_mm!r}")
        self.port = port
        self.envelope = envelope if envelope is not None else SafetyEnvelope()
        if not isinstance(self.envelope, SafetyEnvelope):
            raise ValueError(f"envelope must be a SafetyEnvelope, got {type(envelope).__name__}")
        self.envelope.check_point(self.envelope.min_radius_mm + 1e-6, 0.0, teaching_height_mm)
        self.teaching_height_mm = float(teaching_height_mm)
        self.default_speed_mm_s = self.envelope.check_speed(default_speed_mm_s)
        self.timeout = float(timeout)
        self.ready_timeout = float(ready_timeout)
        self.max_in_flight = int(max_in_flight)
        self.simulate_if_absent = simulate_if_absent

        self.firmware_version: tuple[int, int, int] | None = None
        self.device_name: str | None = None
        self.port_used: str | None = None
        self._ser = None
        self._reader: threading.Thread | None = None
        self._lock = threading.Lock()
        self._write_lock = threading.Lock()
        self._move_lock = threading.Lock()
        # Every stop() starts a new generation; a move is sent only if no stop came since its
        # move_to() began. Checked and sent under _stop_lock, so a stop either finds the move
        # already on the wire (and cuts it) or the move finds the stop (and is never sent).
        self._stop_lock = threading.Lock()
        self._stop_generation = 0
        self._slots = threading.Semaphore(max_in_flight)
        self._pending: dict[int, _Pending] = {}
        self._order: deque[int] = deque()
        self._retired: dict[int, float] = {}
        self._next_number = 1
        self._dead: SwiftProDisconnected | None = None
        self._closing = False
        self._ready = threading.Event()
        self._events: deque[Event] = deque(maxlen=1000)
        self._events_cond = threading.Condition()
        self._callbacks: list[Callable[[Event], None]] = []
        self._last_target: tuple[float, float, float] | None = None
        self._current_move: _Pending | None = None
        self._current_target: tuple[float, float, float, float] | None = None  # x, y, z mm and speed mm/s
        self._stopped = False
        # Firmware 4.0-4.4: stop() paused the arm (S1000 V0); nothing may be queued until
        # resume(), and the target of the move the pause cut short (x, y, z, speed) or None.
        self._paused = False
        self._paused_target: tuple[float, float, float, float] | None = None

    # ================================================================== life cycle
    def __enter__(self) -> SwiftPro:
        self.connect()
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    @property
    def connected(self) -> bool:
        """True between a successful :meth:`connect` and :meth:`close` or a link failure."""
        return self._ser is not None and self._dead is None

    @property
    def stop_generation(self) -> int:
        """How many times :meth:`stop` was called. Read it when a job starts and pass it to
        every ``move_to(..., unless_stopped_since=generation)`` of the job: a stop at any
        time since then makes those moves refuse to be sent."""
        return self._stop_generation

    @property
    def paused(self) -> bool:
        """True after :meth:`stop` on firmware 4.0-4.4 until :meth:`resume`: nothing moves."""
        return self._paused

    @property
    def firmware_major(self) -> int | None:
        """3 or 4 once connected (the two generations differ, see the doc)."""
        return self.firmware_version[0] if self.firmware_version else None

    @staticmethod
    def find_ports() -> list[str]:
        """Serial ports with the Swift Pro's USB id (2341:0042), not yet probed."""
        from serial.tools import list_ports

        return [p.device for p in list_ports.comports() if p.vid == USB_VID and p.pid == USB_PID]

    def connect(self) -> None:
        """Open the port, wait until the arm is ready, detect its firmware (P2203), check it
        is a Swift Pro (P2201) and read its position.

        Raises:
            SwiftProNotFound: auto-detection found no Swift Pro.
            SwiftProPortBusy: another program holds the port.
            SwiftProTimeout: the arm did not get ready within ``ready_timeout``.
            SwiftProError: the device is not a Swift Pro, or answered nonsense.
        """
        if self.connected:
            return
        if self.port in (None, "auto"):
            candidates = self.find_ports()
            reasons = []
            for candidate in candidates:
                try:
                    self._connect_to(candidate)
                    return
                except SwiftProError as exc:
                    reasons.append(f"{candidate}: {exc}")
            if self.simulate_if_absent:
                log.info("no Swift Pro found (%s); using the simulated arm", reasons or "no USB candidates")
                self._connect_to(SIMULATOR_URL)
                return
            raise SwiftProNotFound(
                "no Swift Pro found: looked for serial ports with USB VID:PID 2341:0042 answering "
                f"P2201 with 'SwiftPro'; candidates: {reasons or 'none'}")
        self._connect_to(self.port)

    def _connect_to(self, port: str) -> None:
        if self._ser is not None:
            # After a link failure the old port is still open and its reader may still run:
            # close both, or the file descriptor leaks and an exclusive reopen finds the port busy.
            self.close()
        self._reset_state()
        try:
            ser = serial.serial_for_url(port, baudrate=115200, timeout=0.05, write_timeout=self.timeout,
                                        exclusive=True)
        except SerialException as exc:
            err = _port_error(port, exc, "opening")
            if isinstance(err, SwiftProPortBusy):
                raise err from exc
            raise SwiftProError(f"could not open port {port!r}: {exc}") from exc
        except ValueError as exc:
            raise SwiftProError(f"port must be a device path or a known pyserial URL, got {port!r}: {exc}") from exc
        self._ser = ser
        self.port_used = port
        try:
            # Output left over from an earlier run must not be read as ours (SDK issue #25).
            ser.reset_input_buffer()
        except (SerialException, OSError) as exc:
            self._close_port()
            raise _port_error(port, exc, "opening") from exc
        self._reader = threading.Thread(target=self._read_loop, name=f"SwiftPro reader {port}", daemon=True)
        self._reader.start()
        try:
            self._wait_ready()
            version_reply = self._request("P2203")
            version = protocol.parse_version(version_reply.payload)
            if version is None:
                raise SwiftProError(f"P2203 must answer a firmware version like V4.10.0, got {version_reply.line!r}")
            name_reply = self._request("P2201")
            # 3.x answers "VSwiftPro", 4.x "SwiftPro" (the doc, "Commands").
            name = name_reply.payload.strip()
            name = name[1:] if name.startswith("VSwift") else name
            if name != "SwiftPro":
                raise SwiftProError(f"P2201 must name a SwiftPro, got {name!r}: this connector drives the Swift Pro only")
            self.firmware_version, self.device_name = version, name
            self._last_target = self.position()
        except BaseException:
            self.close()
            raise

    def _reset_state(self) -> None:
        self._closing = False
        self._dead = None
        self._ready.clear()
        self._pending.clear()
        self._order.clear()
        self._retired.clear()
        self._slots = threading.Semaphore(self.max_in_flight)
        # Start numbering at random so that replies replayed from an earlier session (SDK
        # issue #25) are unlikely to match a request of this one.
        self._next_number = random.randint(1, protocol.MAX_REQUEST_NUMBER)
        self._last_target = None
        self.firmware_version = None
        self._current_move = None
        # Opening the port resets the board (the doc: probably, through DTR), which ends a pause.
        self._paused = False
        self._paused_target = None

    def _wait_ready(self) -> None:
        """4.x says ``@1`` when booted; 3.x does not (the doc, "Link"), so also poll P2234."""
        deadline = time.monotonic() + self.ready_timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise SwiftProTimeout(
                    f"the arm on {self.port_used!r} was not ready within ready_timeout = {self.ready_timeout} s "
                    "(no @1 and no answer to P2234): is it powered? (SDK issue #25)")
            if self._ready.wait(min(0.1, remaining)):
                return
            try:
                self._request("P2234", timeout=min(0.25, max(0.01, deadline - time.monotonic())))
                return
            except SwiftProTimeout:
                continue

    def close(self) -> None:
        """Stop the reader thread and close the port; pending requests fail with
        :class:`SwiftProDisconnected`. Safe to call twice."""
        if self._ser is None:
            return
        self._closing = True
        try:
            self._ser.cancel_read()
        except (AttributeError, SerialException, OSError) as exc:
            log.debug("cancel_read failed on close: %s", exc)
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(timeout=2.0)
        self._close_port()
        self._fail_all(SwiftProDisconnected(f"connection to {self.port_used!r} was closed"), keep_dead=False)

    def _close_port(self) -> None:
        ser, self._ser = self._ser, None
        if ser is not None:
            try:
                ser.close()
            except (SerialException, OSError) as exc:
                log.debug("closing the port failed: %s", exc)

    # ================================================================== reader side
    def _read_loop(self) -> None:
        ser = self._ser
        buf = b""
        while not self._closing:
            try:
                data = ser.read(max(1, ser.in_waiting))
            except (SerialException, OSError, TypeError, AttributeError) as exc:
                # TypeError/AttributeError: pyserial's posix port after close() from another thread.
                if not self._closing:
                    self._fail_all(_port_error(self.port_used, exc, "reading"))
                return
            if not data:
                continue
            buf += data
            *lines, buf = buf.split(b"\n")
            for raw in lines:
                self._handle_line(raw.decode("ascii", "replace").strip())

    def _handle_line(self, line: str) -> None:
        item = protocol.classify_line(line)
        if item is None:
            return
        if isinstance(item, Reply):
            with self._lock:
                pending = self._pending.pop(item.number, None)
                if pending is None:
                    late = self._retired.pop(item.number, None) is not None
                else:
                    self._order.remove(item.number)
            if pending is None:
                log.info("%s reply %r: no request waits for it; dropped", "late" if late else "stray", line)
                return
            pending.reply = item
            self._release(pending)
            pending.done.set()
            return
        if item.kind == "@1":
            self._ready.set()
        if item.kind == "error" and item.error_code == 23:
            # A bare "E23 buffer full" answers the newest command (the 21st in the queue, doc "Errors").
            with self._lock:
                number = self._order.pop() if self._order else None
                pending = self._pending.pop(number, None) if number is not None else None
            if pending is not None:
                pending.error = error_for_code(23, command=pending.command, line=line)
                self._release(pending)
                pending.done.set()
        with self._events_cond:
            self._events.append(item)
            self._events_cond.notify_all()
        for callback in list(self._callbacks):
            try:
                callback(item)
            except Exception:  # a user's callback must not kill the reader thread
                log.exception("event callback %r failed on %r", callback, line)

    def _release(self, pending: _Pending) -> None:
        with self._lock:
            if pending.released:
                return
            pending.released = True
        if pending.holds_slot:
            self._slots.release()

    def _fail_all(self, error: SwiftProDisconnected, keep_dead: bool = True) -> None:
        with self._lock:
            if keep_dead and self._dead is None:
                self._dead = error
            pendings = list(self._pending.values())
            self._pending.clear()
            self._order.clear()
        for pending in pendings:
            pending.error = error
            self._release(pending)
            pending.done.set()
        with self._events_cond:
            self._events_cond.notify_all()

    # ================================================================== requests
    def _submit(self, command: str, *params: tuple[str, float], move_generation: int | None = None,
                is_stop: bool = False, while_paused: bool = False) -> _Pending:
        """Send a numbered request; returns its pending record. Private: no raw G-code
        reaches a participant-facing UI.

        With ``move_generation`` the request is a move: it is sent only if no :meth:`stop`
        came since that generation, and it becomes the current move that a stop cuts.
        ``is_stop`` requests bypass the in-flight limit. While the arm is paused (4.0-4.4)
        G and M commands would queue behind the cut move and never be answered: they are
        refused unless ``while_paused`` (resume's own barrier).
        """
        self._check_alive()
        if self._paused and not while_paused and command[:1] in ("G", "M"):
            raise SwiftProStopped(f"{command!r} was not sent: the arm is paused by stop(); call resume() first")
        if not is_stop and not self._slots.acquire(timeout=self.timeout):
            raise SwiftProTimeout(
                f"{self.max_in_flight} requests still unanswered after {self.timeout} s; {command!r} not sent")
        pending = None
        try:
            self._check_alive()
            with self._stop_lock:
                if move_generation is not None and move_generation != self._stop_generation:
                    raise SwiftProStopped(f"{command!r} was not sent: stop() came before it")
                with self._lock:
                    number = self._allocate_number()
                    pending = _Pending(number, command, threading.Event(), holds_slot=not is_stop)
                    self._pending[number] = pending
                    self._order.append(number)
                if move_generation is not None:
                    self._current_move = pending
                self._send(protocol.build_request(number, command, *params))
        except BaseException:
            if pending is None:
                if not is_stop:
                    self._slots.release()
            else:
                with self._lock:
                    if self._pending.pop(pending.number, None) is not None:
                        self._order.remove(pending.number)
                self._release(pending)
            raise
        return pending

    def _allocate_number(self) -> int:
        now = time.monotonic()
        # Retired numbers older than a minute will not be answered any more.
        for n in [n for n, t in self._retired.items() if now - t > 60.0]:
            del self._retired[n]
        for _ in range(protocol.MAX_REQUEST_NUMBER):
            n = self._next_number
            self._next_number = n % protocol.MAX_REQUEST_NUMBER + 1
            if n not in self._pending and n not in self._retired:
                return n
        raise SwiftProError("all request numbers 1..9999 are in use or retired")

    def _send(self, line: str) -> None:
        data = (protocol.check_line(line) + "\n").encode("ascii")
        ser = self._ser
        if ser is None:
            raise SwiftProDisconnected("not connected: call connect() first")
        try:
            with self._write_lock:
                ser.write(data)
        except SerialTimeoutException as exc:
            raise SwiftProTimeout(f"writing {line!r} to {self.port_used!r} timed out after {self.timeout} s") from exc
        except (SerialException, OSError) as exc:
            err = _port_error(self.port_used, exc, f"writing {line!r}")
            self._fail_all(err)
            raise err from exc

    def _check_alive(self) -> None:
        if self._dead is not None:
            raise self._dead
        if self._ser is None:
            raise SwiftProDisconnected("not connected: call connect() first")

    def _wait(self, pending: _Pending, timeout: float) -> Reply:
        if not pending.done.wait(timeout):
            with self._lock:
                still = self._pending.pop(pending.number, None) is not None
                if still:
                    self._order.remove(pending.number)
                    self._retired[pending.number] = time.monotonic()
            if still:
                self._release(pending)
                echo = self._recent_unknown_echo()
                hint = f"; the arm said {echo!r} (3.x answers unknown commands this way)" if echo else ""
                raise SwiftProTimeout(
                    f"no reply to {pending.command!r} (#{pending.number}) within {timeout:.3f} s{hint}; "
                    "its number is retired, a late reply will be ignored")
        if pending.error is not None:
            raise pending.error
        reply = pending.reply
        if reply.error_code is not None:
            raise error_for_code(reply.error_code, command=pending.command, line=reply.line)
        if not reply.ok:
            raise SwiftProCommandError(f"command {pending.command!r} got an unexpected reply {reply.line!r}",
                                       command=pending.command, line=reply.line)
        return reply

    def _recent_unknown_echo(self) -> str | None:
        with self._events_cond:
            for event in reversed(self._events):
                if event.kind == "echo" and "unknown command" in event.line.lower():
                    return event.line
        return None

    def _request(self, command: str, *params: tuple[str, float], timeout: float | None = None,
                 is_stop: bool = False) -> Reply:
        return self._wait(self._submit(command, *params, is_stop=is_stop), self.timeout if timeout is None else timeout)

    # ================================================================== events
    def on_event(self, callback: Callable[[Event], None]) -> None:
        """Call ``callback(event)`` from the reader thread for every unsolicited line."""
        self._callbacks.append(callback)

    def next_event(self, kind: str | None = None, timeout: float | None = None) -> Event:
        """Take the oldest queued event (of ``kind``, e.g. ``"@3"``, if given).

        Args:
            kind: ``"@1"``, ``"@3"``, ..., ``"echo"``, ``"error"``, ``"info"``, or None for any.
            timeout: seconds to wait; ``self.timeout`` if None.

        Raises:
            SwiftProTimeout: nothing came in time.
        """
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        with self._events_cond:
            while True:
                for event in self._events:
                    if kind is None or event.kind == kind:
                        self._events.remove(event)
                        return event
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise SwiftProTimeout(f"no {kind or 'event'} within {timeout} s")
                self._events_cond.wait(remaining)

    def drain_events(self) -> list[Event]:
        """All queued events, oldest first; the queue is left empty."""
        with self._events_cond:
            events = list(self._events)
            self._events.clear()
        return events

    # ================================================================== arm commands
    def position(self) -> tuple[float, float, float]:
        """Where the tool is, (x, y, z) in mm (P2220).

        On 4.x this reads the encoders, even mid-move; on 3.x it is the last target, stale
        while the motors are detached (SDK issue #2).
        """
        reply = self._request("P2220")
        values = protocol.parse_values(reply.payload)
        if not {"X", "Y", "Z"} <= values.keys():
            raise SwiftProError(f"P2220 must answer X.. Y.. Z.., got {reply.line!r}")
        return values["X"], values["Y"], values["Z"]

    def is_reachable(self, x: float, y: float, z: float) -> bool:
        """Ask the arm whether it can reach (x, y, z) mm (M2222 ... P0 -> V1/V0). Nothing moves."""
        reply = self._request("M2222", ("X", x), ("Y", y), ("Z", z), ("P", 0))
        values = protocol.parse_values(reply.payload)
        if "V" not in values:
            raise SwiftProError(f"M2222 must answer V0 or V1, got {reply.line!r}")
        return values["V"] == 1

    def move_to(self, x: float, y: float, z: float | None = None, speed: float | None = None, *,
                unless_stopped_since: int | None = None) -> None:
        """Move the tool in a straight line to (x, y, z) mm and wait until it is there.

        Checks, in order, before anything is sent: the target is inside the envelope; the
        arm is inside it too (an arm outside, as after power-up, is refused: an experimenter
        brings it in with :meth:`home`); the speed is allowed; the straight path from the
        last known position stays inside and is at most ``max_step_mm`` long; the arm itself
        says the target is reachable (M2222).

        Args:
            x: forward, mm.
            y: left, mm.
            z: up, mm; the teaching height if None.
            speed: mm/s; ``default_speed_mm_s`` if None.
            unless_stopped_since: a :attr:`stop_generation` read earlier (when a job began);
                if :meth:`stop` was called since, the move is refused. None: since this call.

        Raises:
            UnsafeMoveError: a check failed; nothing was sent.
            SwiftProUnreachable, SwiftProMotorsDetached, ...: the arm refused the move.
            SwiftProStopped: :meth:`stop` cut the move short, came since
                ``unless_stopped_since``, or paused the arm (4.0-4.4) and :meth:`resume` was
                not called since.
            SwiftProTimeout, SwiftProDisconnected: the link failed.
        """
        generation = self._generation_since(unless_stopped_since)
        z = self.teaching_height_mm if z is None else z
        speed = self.default_speed_mm_s if speed is None else speed
        # Round to the 4 decimals that go on the wire before checking, so that what is
        # checked is exactly what is sent.
        target = self.envelope.check_point(*(round(v, 4) for v in self.envelope.check_point(x, y, z)))
        self._move(target, speed, generation, homing=False)

    def home(self, x: float = 200.0, y: float = 0.0, z: float | None = None, *, speed: float | None = None,
             max_segment_mm: float = 40.0, unless_stopped_since: int | None = None
             ) -> list[tuple[float, float, float]]:
        """Experimenter-level: bring the arm into the envelope (after power-up, or after it was
        moved by hand) and to (x, y, z) mm, the only way into the envelope.

        The path is :meth:`SafetyEnvelope.entry_path`: straight up into the height band if
        below it, out of (or into) the radius band along the arm's own yaw, down into the
        band if above it, then a polar path to the target; legs at most ``max_segment_mm``,
        all at ``speed`` (at most ``entry_speed_mm_s``). Each leg is checked before it is
        sent: while the arm is outside, it may not take it further out in any respect
        (:meth:`SafetyEnvelope.check_entering_segment`); once inside, the usual checks of
        :meth:`move_to`; and the arm is asked (M2222). From inside, ``home`` is a slow
        :meth:`move_to` along a polar path.

        Args:
            x, y: the target, mm, inside the envelope (default: 200 mm straight ahead).
            z: its height, mm; the teaching height if None.
            speed: mm/s; ``entry_speed_mm_s`` if None.
            max_segment_mm: longest leg, mm.
            unless_stopped_since: as for :meth:`move_to`.

        Returns:
            The points the arm was sent to, in order, mm.

        Raises:
            As :meth:`move_to`; a failed leg leaves the arm where that leg began (or cut short).
        """
        generation = self._generation_since(unless_stopped_since)
        z = self.teaching_height_mm if z is None else z
        target = self.envelope.check_point(*(round(v, 4) for v in self.envelope.check_point(x, y, z)))
        speed = self.envelope.check_speed(self.envelope.entry_speed_mm_s if speed is None else speed, entering=True)
        self._check_alive()
        with self._move_lock:
            self._last_target = None  # read where the arm really is, not where it was sent
            start = self.position()
            legs = [tuple(round(v, 4) for v in leg) for leg in self.envelope.entry_path(start, target, max_segment_mm)]
        for leg in legs:
            self._move(leg, speed, generation, homing=True)
        return legs

    def _generation_since(self, unless_stopped_since: int | None) -> int:
        if unless_stopped_since is None:
            return self._stop_generation
        if not (isinstance(unless_stopped_since, numbers.Integral) and not isinstance(unless_stopped_since, bool)
                and 0 <= unless_stopped_since <= self._stop_generation):
            raise ValueError(f"unless_stopped_since must be a stop_generation read earlier, an integer in "
                             f"0..{self._stop_generation}, got {unless_stopped_since!r}")
        if unless_stopped_since != self._stop_generation:
            raise SwiftProStopped(f"not moving: stop() was called since generation {unless_stopped_since}")
        return int(unless_stopped_since)

    def _move(self, target: tuple[float, float, float], speed: float, generation: int, *, homing: bool) -> None:
        """Check the move from where the arm is to ``target`` and send it (``home`` legs may
        start and end outside the envelope; see :meth:`home`)."""
        self._check_alive()
        with self._move_lock:
            if self._paused:
                raise SwiftProStopped("the arm is paused by stop(); call resume() first")
            start = self._last_target if self._last_target is not None else self.position()
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
            if not self.is_reachable(*target):
                raise UnsafeMoveError(
                    f"the arm says (x, y, z) = {target} mm is unreachable (M2222 answered V0)",
                    coordinate="target", value=math.hypot(target[0], target[1]), limit=None)
            if self.firmware_major == 3:
                # 3.x: F in mm/min (the 3.x guide); G0 is its documented move.
                word, feed = "G0", speed * 60.0
            else:
                # 4.x: G1 is the linear move; F is sent as mm/s. UNCERTAIN (the doc): if the
                # firmware read it as mm/min the arm would move slower, never faster.
                word, feed = "G1", speed
            duration = math.dist(start, target) / speed
            self._stopped = False
            self._last_target = None  # unknown until the move is confirmed
            self._current_target = (*target, speed)
            pending = self._submit(word, ("X", target[0]), ("Y", target[1]), ("Z", target[2]), ("F", feed),
                                   move_generation=generation)
            try:
                self._wait(pending, self.timeout + 1.5 * duration)
                if self.firmware_major == 3:
                    self._wait_motion_end_3x(deadline=time.monotonic() + self.timeout + 1.5 * duration)
            finally:
                self._current_move = None
            if self._stopped:
                raise SwiftProStopped(f"move to {target} mm was stopped")
            self._last_target = target

    def _wait_motion_end_3x(self, deadline: float) -> None:
        # 3.x answers "ok" when the move is queued; poll M2200 for its end (the doc, "Commands").
        while True:
            values = protocol.parse_values(self._request("M2200").payload)
            if values.get("V") == 0 or self._stopped:
                return
            if time.monotonic() > deadline:
                raise SwiftProTimeout("the 3.x arm still reports moving (M2200 V1) after the expected duration")
            time.sleep(0.01)

    def stop(self) -> None:
        """Stop moving now; a move waiting in :meth:`move_to` raises :class:`SwiftProStopped`,
        and every move begun before this call (``unless_stopped_since``) refuses to be sent.

        The stop command never waits for a request slot. 4.5+ sends ``S1100`` (clears the
        planner); 4.0-4.4 ``S1000 V0`` (pause: nothing more moves until :meth:`resume`);
        3.x ``G2203``. UNCERTAIN (the doc): whether the firmware ever answers the cut move,
        so its number is retired here.
        """
        version = self.firmware_version or (4, 0, 0)
        if version[0] == 3:
            command = ("G2203",)
        elif version >= (4, 5, 0):
            command = ("S1100",)
        else:
            command = ("S1000", ("V", 0))
        with self._stop_lock:
            self._stop_generation += 1
            self._stopped = True
            move = self._current_move
            if command[0] == "S1000":
                # Paused from now on, even if the reply is lost: refusing moves is the safe side.
                if move is not None and self._current_target is not None:
                    self._paused_target = self._current_target
                self._paused = True
        try:
            self._request(*command, is_stop=True)
        finally:
            if move is not None:
                with self._lock:
                    if self._pending.pop(move.number, None) is not None:
                        self._order.remove(move.number)
                        self._retired[move.number] = time.monotonic()
                        move.error = SwiftProStopped(f"{move.command!r} was stopped")
                self._release(move)
                move.done.set()
            self._last_target = None

    def resume(self) -> None:
        """Let the arm move again after :meth:`stop` paused it (firmware 4.0-4.4); nothing to do
        on other firmware (their stop clears the planner) or when not paused.

        4.0-4.4 has no planner clear (``S1100`` is 4.5+), so the move the pause cut short is
        still at the head of the firmware's queue and goes on with ``S1000 V1``. Rather than
        let it run after (or between) new moves, resume sends ``S1000 V1``, then waits for
        that old move to end: a harmless M2222 question queued behind it is answered only
        when the queue is empty (4.x answers G/M commands when idle). Then it re-reads the
        position, from which the next move is checked. The old move was checked against
        the envelope when it was sent, so finishing it stays inside. A :meth:`stop` while
        waiting pauses the arm again and makes resume raise :class:`SwiftProStopped`.

        Raises:
            SwiftProStopped: a stop came while resuming (the arm is paused again).
            SwiftProTimeout, SwiftProDisconnected: the link failed (the arm stays marked paused).
        """
        self._check_alive()
        with self._move_lock:
            if not self._paused:
                return
            generation = self._stop_generation
            target = self._paused_target
            # Sent like a move, only if no stop came since resume began (checked atomically with
            # sending): a stop either finds it on the wire, and its S1000 V0 follows, or wins.
            pending = self._submit("S1000", ("V", 1), move_generation=generation)
            try:
                self._wait(pending, self.timeout)
            finally:
                self._current_move = None
            here = self.position()
            wait_s = self.timeout
            if target is not None:
                wait_s += 1.5 * math.dist(here, target[:3]) / target[3]
            barrier = here if target is None else target[:3]
            pending = self._submit("M2222", ("X", barrier[0]), ("Y", barrier[1]), ("Z", barrier[2]), ("P", 0),
                                   move_generation=generation, while_paused=True)
            try:
                self._wait(pending, wait_s)
            finally:
                self._current_move = None
            with self._stop_lock:
                if self._stop_generation != generation:
                    raise SwiftProStopped("resume was cut short by stop(): the arm is paused again")
                self._paused = False
                self._paused_target = None
            self._last_target = self.position()

    def beep(self, frequency_hz: float = 1000.0, duration_ms: float = 200.0) -> None:
        """Sound the buzzer (M2210 F T; both fields on 4.x).

        Args:
            frequency_hz: pitch, 50..10000 Hz.
            duration_ms: length, 1..5000 ms.
        """
        if not (is_real(frequency_hz) and 50 <= frequency_hz <= 10000):
            raise ValueError(f"frequency_hz must be in 50..10000 Hz, got {frequency_hz!r}")
        if not (is_real(duration_ms) and 1 <= duration_ms <= 5000):
            raise ValueError(f"duration_ms must be in 1..5000 ms, got {duration_ms!r}")
        self._request("M2210", ("F", frequency_hz), ("T", duration_ms), timeout=self.timeout + duration_ms / 1000)

    def attach(self) -> None:
        """Power all motors (M17)."""
        self._request("M17")
        self._last_target = None

    def detach(self) -> None:
        """Release all motors (M2019): the arm can be moved by hand (and may sag)."""
        self._request("M2019")
        self._last_target = None

    def set_position_reports(self, interval_s: float | None) -> None:
        """Ask for ``@3`` position events every ``interval_s`` seconds (M2120); None or 0 stops them."""
        if interval_s is None or (is_real(interval_s) and interval_s == 0):
            self._request("M2120", ("V", 0))
            return
        if not (is_real(interval_s) and 0.01 <= interval_s <= 60):
            raise ValueError(f"interval_s must be None, 0 or in 0.01..60 s, got {interval_s!r}")
        self._request("M2120", ("V", interval_s))
