"""The serial link to a uArm Swift Pro: framing, request numbering, lost requests, events.

Knows the wire (``docs/uarm-protocol.md``, "Link", "Framing", "Errors and events"), not
the firmware generations nor what a move is:

* one reader thread splits the incoming bytes into lines; ``$n ...`` replies are matched
  to the numbered request ``#n ...`` that waits for them, everything else (``@1``, ``@3``,
  ``@5``, ``@6``, ``@9``, ``echo:`` lines, a bare ``E23``, banners) goes to the event queue
  and the event callbacks;
* numbers run 1..9999 and wrap, starting at random, at most ``max_in_flight`` requests in
  flight (2, as the official SDK); a request that times out has its number retired, so a
  late reply is dropped and never taken for the answer to a later request;
* every wait has a timeout; a port that fails or closes wakes every waiter with
  :class:`SwiftProDisconnected`.
"""

from __future__ import annotations

import logging
import random
import threading
import time
from collections import deque
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass

import serial
from serial.serialutil import SerialException, SerialTimeoutException

from . import protocol
from .errors import (
    SwiftProCommandError,
    SwiftProDisconnected,
    SwiftProError,
    SwiftProPortBusy,
    SwiftProTimeout,
    error_for_code,
)
from .protocol import Event, Reply

log = logging.getLogger(__name__)

_BUSY_HINTS = ("multiple access", "exclusively lock", "resource temporarily unavailable", "busy")
#: Seconds after which a retired number may be used again: a reply that late will not come.
RETIRE_S = 60.0


@dataclass
class Pending:
    """A request sent and not yet answered."""

    number: int
    command: str
    done: threading.Event
    reply: Reply | None = None
    error: BaseException | None = None
    released: bool = False
    #: False for requests that bypass the in-flight limit (a stop must never wait for a slot).
    holds_slot: bool = True


def port_error(port: str | None, exc: BaseException, doing: str) -> SwiftProDisconnected:
    """The error for a failed port: :class:`SwiftProPortBusy` if another program holds it."""
    text = str(exc)
    if any(h in text.lower() for h in _BUSY_HINTS):
        return SwiftProPortBusy(
            f"port {port!r} seems held by another program while {doing} ({text}); close other "
            "programs using the arm (uArm-Python-SDK issue #11)")
    return SwiftProDisconnected(f"port {port!r} failed while {doing}: {text}")


class SerialLink:
    """Numbered requests and unsolicited events over one serial port.

    Args:
        timeout: seconds a request waits for a free slot, and the default wait for a reply.
        max_in_flight: requests sent but not yet answered.
    """

    def __init__(self, timeout: float, max_in_flight: int):
        self.timeout = timeout
        self.max_in_flight = max_in_flight
        self.port: str | None = None
        self.serial = None
        self.reader: threading.Thread | None = None
        # One lock for the link's state (pending requests, their order, retired numbers, the
        # next number, the event queue) and for writing to the port: registering a request
        # and writing its line happen together, so the order of ``_order`` is the order on
        # the wire (a bare E23 answers the newest line sent). Held only for bookkeeping and
        # one short write, never while waiting for the arm.
        self._lock = threading.Lock()
        self._events_cond = threading.Condition(self._lock)
        self._slots = threading.Semaphore(max_in_flight)
        self._pending: dict[int, Pending] = {}
        self._order: deque[int] = deque()
        self._retired: dict[int, float] = {}
        self._next_number = 1
        self._dead: SwiftProDisconnected | None = None
        self._closing = False
        self.ready = threading.Event()
        self._events: deque[Event] = deque(maxlen=1000)
        self._callbacks: list[Callable[[Event], None]] = []

    # ------------------------------------------------------------------ life cycle
    @property
    def connected(self) -> bool:
        return self.serial is not None and self._dead is None

    def open(self, port: str) -> None:
        """Open ``port`` (a device path or pyserial URL) exclusively and start the reader.

        Raises:
            SwiftProPortBusy: another program holds the port.
            SwiftProError: the port could not be opened.
        """
        if self.serial is not None:
            # After a link failure the old port is still open and its reader may still run:
            # close both, or the file descriptor leaks and an exclusive reopen finds the port busy.
            self.close()
        self._closing = False
        self._dead = None
        self.ready.clear()
        with self._lock:
            self._pending.clear()
            self._order.clear()
            self._retired.clear()
            # Start numbering at random so that replies replayed from an earlier session (SDK
            # issue #25) are unlikely to match a request of this one.
            self._next_number = random.randint(1, protocol.MAX_REQUEST_NUMBER)
        self._slots = threading.Semaphore(self.max_in_flight)
        try:
            ser = serial.serial_for_url(port, baudrate=115200, timeout=0.05, write_timeout=self.timeout,
                                        exclusive=True)
        except SerialException as exc:
            err = port_error(port, exc, "opening")
            if isinstance(err, SwiftProPortBusy):
                raise err from exc
            raise SwiftProError(f"could not open port {port!r}: {exc}") from exc
        except ValueError as exc:
            raise SwiftProError(f"port: expected a device path or a known pyserial URL, got {port!r}: {exc}") from exc
        self.serial, self.port = ser, port
        try:
            # Output left over from an earlier run must not be read as ours (SDK issue #25).
            ser.reset_input_buffer()
        except (SerialException, OSError) as exc:
            self._close_port()
            raise port_error(port, exc, "opening") from exc
        self.reader = threading.Thread(target=self._read_loop, name=f"SwiftPro reader {port}", daemon=True)
        self.reader.start()

    def close(self) -> None:
        """Stop the reader and close the port; pending requests fail with
        :class:`SwiftProDisconnected`. Safe to call twice."""
        if self.serial is None:
            return
        self._closing = True
        try:
            self.serial.cancel_read()
        except (AttributeError, SerialException, OSError) as exc:
            log.debug("cancel_read failed on close: %s", exc)
        if self.reader is not None and self.reader is not threading.current_thread():
            self.reader.join(timeout=2.0)
        self._close_port()
        self._fail_all(SwiftProDisconnected(f"connection to {self.port!r} was closed"), keep_dead=False)

    def _close_port(self) -> None:
        ser, self.serial = self.serial, None
        if ser is not None:
            try:
                ser.close()
            except (SerialException, OSError) as exc:
                log.debug("closing the port failed: %s", exc)

    def check_alive(self) -> None:
        """Raise the link's failure, or :class:`SwiftProDisconnected` if never connected."""
        if self._dead is not None:
            raise self._dead
        if self.serial is None:
            raise SwiftProDisconnected("not connected: call connect() first")

    # ------------------------------------------------------------------ reader side
    def _read_loop(self) -> None:
        ser = self.serial
        buf = b""
        while not self._closing:
            try:
                data = ser.read(max(1, ser.in_waiting))
            except (SerialException, OSError, TypeError, AttributeError) as exc:
                # TypeError/AttributeError: pyserial's posix port after close() from another thread.
                if not self._closing:
                    self._fail_all(port_error(self.port, exc, "reading"))
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
            self._finish(pending)
            return
        if item.kind == "@1":
            self.ready.set()
        if item.kind == "error" and item.error_code == 23:
            # A bare "E23 buffer full" answers the newest command (the 21st in the queue).
            with self._lock:
                number = self._order.pop() if self._order else None
                pending = self._pending.pop(number, None) if number is not None else None
            if pending is not None:
                pending.error = error_for_code(23, command=pending.command, line=line)
                self._finish(pending)
        with self._events_cond:
            self._events.append(item)
            self._events_cond.notify_all()
        for callback in list(self._callbacks):
            try:
                callback(item)
            except Exception:  # a user's callback must not kill the reader thread
                log.exception("event callback %r failed on %r", callback, line)

    def _finish(self, pending: Pending) -> None:
        """Give back its slot (once) and wake its waiter."""
        with self._lock:
            release, pending.released = pending.holds_slot and not pending.released, True
        if release:
            self._slots.release()
        pending.done.set()

    def _fail_all(self, error: SwiftProDisconnected, keep_dead: bool = True) -> None:
        with self._lock:
            if keep_dead and self._dead is None:
                self._dead = error
            pendings = list(self._pending.values())
            self._pending.clear()
            self._order.clear()
            self._events_cond.notify_all()
        for pending in pendings:
            pending.error = error
            self._finish(pending)

    # ------------------------------------------------------------------ requests
    def submit(self, command: str, *params: tuple[str, float], bypass_limit: bool = False,
               guard: AbstractContextManager | None = None,
               on_sent: Callable[[Pending], None] | None = None) -> Pending:
        """Send a numbered request; returns its :class:`Pending` record (see :meth:`wait`).

        Args:
            command, params: as :func:`mt_widgets.hardware.protocol.build_request`.
            bypass_limit: send without taking an in-flight slot (a stop must never wait).
            guard: entered after the slot is taken and held while the line is sent; it may
                raise to keep the line from being sent (the stop switch does).
            on_sent: called with the record inside ``guard`` once the line is on the wire.
        """
        self.check_alive()
        if not bypass_limit and not self._slots.acquire(timeout=self.timeout):
            raise SwiftProTimeout(
                f"{self.max_in_flight} requests still unanswered after {self.timeout} s; {command!r} not sent")
        pending = None
        try:
            with guard if guard is not None else nullcontext():
                self.check_alive()
                with self._lock:
                    number = self._allocate_number()
                    line = protocol.build_request(number, command, *params)
                    pending = Pending(number, command, threading.Event(), holds_slot=not bypass_limit)
                    self._pending[number] = pending
                    self._order.append(number)
                    failure = self._write(line)
                if failure is not None:
                    self._fail_all(failure)
                    raise failure
                if on_sent is not None:
                    on_sent(pending)
        except BaseException:
            if pending is None:
                if not bypass_limit:
                    self._slots.release()
            else:
                self.retire(pending, None, remember=False)
            raise
        return pending

    def _allocate_number(self) -> int:
        now = time.monotonic()
        for n in [n for n, t in self._retired.items() if now - t > RETIRE_S]:
            del self._retired[n]
        for _ in range(protocol.MAX_REQUEST_NUMBER):
            n = self._next_number
            self._next_number = n % protocol.MAX_REQUEST_NUMBER + 1
            if n not in self._pending and n not in self._retired:
                return n
        raise SwiftProError("all request numbers 1..9999 are in use or retired")

    def _write(self, line: str) -> SwiftProDisconnected | None:
        """Write one line (under the lock); a timeout raises, a failed port is returned, to be
        failed once the lock is free."""
        data = (protocol.check_line(line) + "\n").encode("ascii")
        try:
            self.serial.write(data)
        except SerialTimeoutException as exc:
            raise SwiftProTimeout(f"writing {line!r} to {self.port!r} timed out after {self.timeout} s") from exc
        except (SerialException, OSError) as exc:
            err = port_error(self.port, exc, f"writing {line!r}")
            err.__cause__ = exc
            return err
        return None

    def retire(self, pending: Pending, error: BaseException | None, *, remember: bool = True) -> bool:
        """Stop waiting for ``pending``: its waiter gets ``error``, a late reply is dropped.

        Returns:
            True if it was still waiting (no reply had come).
        """
        with self._lock:
            still = self._pending.pop(pending.number, None) is not None
            if still:
                self._order.remove(pending.number)
                if remember:
                    self._retired[pending.number] = time.monotonic()
                if error is not None:
                    pending.error = error
        self._finish(pending)
        return still

    def wait(self, pending: Pending, timeout: float) -> Reply:
        """Wait for the reply to ``pending``.

        Raises:
            SwiftProTimeout: none came within ``timeout`` s (the number is retired).
            SwiftProCommandError: the arm answered with an error code (its own subclass).
            SwiftProDisconnected: the link failed meanwhile.
        """
        if not pending.done.wait(timeout):
            if self.retire(pending, None):
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

    def request(self, command: str, *params: tuple[str, float], timeout: float | None = None,
                bypass_limit: bool = False) -> Reply:
        """:meth:`submit` then :meth:`wait` (``timeout`` defaults to the link's)."""
        pending = self.submit(command, *params, bypass_limit=bypass_limit)
        return self.wait(pending, self.timeout if timeout is None else timeout)

    def _recent_unknown_echo(self) -> str | None:
        with self._lock:
            for event in reversed(self._events):
                if event.kind == "echo" and "unknown command" in event.line.lower():
                    return event.line
        return None

    # ------------------------------------------------------------------ events
    def on_event(self, callback: Callable[[Event], None]) -> None:
        self._callbacks.append(callback)

    def next_event(self, kind: str | None, timeout: float) -> Event:
        deadline = time.monotonic() + timeout
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
        with self._lock:
            events = list(self._events)
            self._events.clear()
        return events
