"""The uArm Swift Pro connector: :class:`SwiftPro`, over pyserial.

Facts about the arm are in ``docs/uarm-protocol.md``. The connector is three layers, each
its own module, put together here:

* :mod:`~mt_widgets.hardware.link`: the serial link (framing, request numbering, retiring
  lost requests, events);
* :mod:`~mt_widgets.hardware.dialects`: what differs between firmware 3.x, 4.0-4.4 and 4.5+;
* :mod:`~mt_widgets.hardware.motion`: the motion and safety policy (the envelope on every
  move, stop, pause/resume, home), with the one stop mechanism,
  :class:`~mt_widgets.hardware.stop.StopSwitch`, which the bridge shares.

This module finds and connects to the arm, detects its firmware, and offers the commands.
There is no public method that sends raw G-code; participant-facing code only calls
:meth:`SwiftPro.home` once at connection, from the experimenter's app.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

from serial.tools import list_ports

from mt_widgets.core.validation import as_bool, as_count, as_positive, is_real

from . import protocol
from .dialects import Dialect, dialect_for
from .envelope import TEACHING_HEIGHT_MM, SafetyEnvelope
from .errors import SwiftProError, SwiftProNotFound, SwiftProTimeout
from .link import SerialLink
from .motion import MotionPolicy
from .protocol import Event, Reply
from .stop import StopSwitch

log = logging.getLogger(__name__)

#: USB id of the Arduino Mega 2560 inside the Swift and the Swift Pro.
USB_VID, USB_PID = 0x2341, 0x0042
#: The simulated arm used when no Swift Pro is plugged in: firmware 4.x, real-time moves.
SIMULATOR_URL = "uarm-sim://?firmware=4"


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
            raise ValueError(f"port: expected a device path, a pyserial URL, 'auto' or None, got {port!r}")
        self.timeout = as_positive("timeout", timeout)
        self.ready_timeout = as_positive("ready_timeout", ready_timeout)
        self.max_in_flight = as_count("max_in_flight", max_in_flight)
        if self.max_in_flight > 32:
            raise ValueError(f"max_in_flight: expected a whole number in 1..32, got {max_in_flight!r}")
        if not is_real(teaching_height_mm):
            raise ValueError(f"teaching_height_mm: expected a real number of mm in the envelope's height band, "
                             f"got {teaching_height_mm!r}")
        self.simulate_if_absent = as_bool("simulate_if_absent", simulate_if_absent)
        self.port = port
        self.envelope = envelope if envelope is not None else SafetyEnvelope()
        if not isinstance(self.envelope, SafetyEnvelope):
            raise ValueError(f"envelope: expected a SafetyEnvelope, got {type(envelope).__name__}")
        self.envelope.check_point(self.envelope.min_radius_mm + 1e-6, 0.0, teaching_height_mm)
        self.teaching_height_mm = float(teaching_height_mm)
        self.default_speed_mm_s = self.envelope.check_speed(default_speed_mm_s)

        self.firmware_version: tuple[int, int, int] | None = None
        self.device_name: str | None = None
        self._link = SerialLink(self.timeout, self.max_in_flight)
        self._stop_switch = StopSwitch()
        self._motion = MotionPolicy(self, self._link, self._stop_switch, self.envelope)

    # ================================================================== life cycle
    def __enter__(self) -> SwiftPro:
        self.connect()
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()

    @property
    def connected(self) -> bool:
        """True between a successful :meth:`connect` and :meth:`close` or a link failure."""
        return self._link.connected

    @property
    def port_used(self) -> str | None:
        """The port (device path or URL) of the current or last connection."""
        return self._link.port

    @property
    def stop_switch(self) -> StopSwitch:
        """The stop mechanism of this arm; the bridge shares it (see :mod:`mt_widgets.hardware.stop`)."""
        return self._stop_switch

    @property
    def stop_generation(self) -> int:
        """How many times :meth:`stop` was called. Read it when a job starts and pass it to
        every ``move_to(..., unless_stopped_since=generation)`` of the job: a stop at any
        time since then makes those moves refuse to be sent."""
        return self._stop_switch.generation

    @property
    def paused(self) -> bool:
        """True after :meth:`stop` on firmware 4.0-4.4 until :meth:`resume`: nothing moves."""
        return self._motion.paused

    @property
    def firmware_major(self) -> int | None:
        """3 or 4 once connected (the two generations differ, see ``docs/uarm-protocol.md``)."""
        return self.firmware_version[0] if self.firmware_version else None

    @property
    def dialect(self) -> Dialect:
        """The firmware's dialect (4.0-4.4 until the version is known)."""
        return dialect_for(self.firmware_version)

    @staticmethod
    def find_ports() -> list[str]:
        """Serial ports with the Swift Pro's USB id (2341:0042), not yet probed."""
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
        self.firmware_version = None
        self._motion.connected_at(None)
        self._link.open(port)
        try:
            self._wait_ready()
            version_reply = self._request("P2203")
            version = protocol.parse_version(version_reply.payload)
            if version is None:
                raise SwiftProError(f"P2203 must answer a firmware version like V4.10.0, got {version_reply.line!r}")
            # 3.x answers "VSwiftPro", 4.x "SwiftPro".
            name = dialect_for(version).device_name(self._request("P2201").payload)
            if name != "SwiftPro":
                raise SwiftProError(f"P2201 must name a SwiftPro, got {name!r}: this connector drives the Swift Pro "
                                    "only")
            self.firmware_version, self.device_name = version, name
            log.info("connected to a %s on %r, firmware %s (dialect %s)", name, port,
                     ".".join(map(str, version)), self.dialect.name)
            self._motion.connected_at(self.position())
        except BaseException:
            self.close()
            raise

    def _wait_ready(self) -> None:
        """4.x says ``@1`` when booted; 3.x does not, so also poll P2234."""
        deadline = time.monotonic() + self.ready_timeout
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise SwiftProTimeout(
                    f"the arm on {self.port_used!r} was not ready within ready_timeout = {self.ready_timeout} s "
                    "(no @1 and no answer to P2234): is it powered? (SDK issue #25)")
            if self._link.ready.wait(min(0.1, remaining)):
                return
            try:
                self._request("P2234", timeout=min(0.25, max(0.01, deadline - time.monotonic())))
                return
            except SwiftProTimeout:
                continue

    def close(self) -> None:
        """Stop the reader thread and close the port; pending requests fail with
        :class:`SwiftProDisconnected`. Safe to call twice."""
        self._link.close()

    def _request(self, command: str, *params: tuple[str, float], timeout: float | None = None) -> Reply:
        """Send one command and wait for its reply. Private: no raw G-code reaches a
        participant-facing UI. While paused (4.0-4.4), G and M commands are refused."""
        self._motion.refuse_while_paused(command)
        return self._link.request(command, *params, timeout=timeout)

    # ================================================================== events
    def on_event(self, callback: Callable[[Event], None]) -> None:
        """Call ``callback(event)`` from the reader thread for every unsolicited line."""
        self._link.on_event(callback)

    def next_event(self, kind: str | None = None, timeout: float | None = None) -> Event:
        """Take the oldest queued event (of ``kind``, e.g. ``"@3"``, if given).

        Args:
            kind: ``"@1"``, ``"@3"``, ..., ``"echo"``, ``"error"``, ``"info"``, or None for any.
            timeout: seconds to wait; ``self.timeout`` if None.

        Raises:
            SwiftProTimeout: nothing came in time.
        """
        return self._link.next_event(kind, self.timeout if timeout is None else timeout)

    def drain_events(self) -> list[Event]:
        """All queued events, oldest first; the queue is left empty."""
        return self._link.drain_events()

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
        generation = self._motion.generation_since(unless_stopped_since)
        z = self.teaching_height_mm if z is None else z
        speed = self.default_speed_mm_s if speed is None else speed
        self._motion.move_to((x, y, z), speed, generation)

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
        generation = self._motion.generation_since(unless_stopped_since)
        z = self.teaching_height_mm if z is None else z
        return self._motion.home((x, y, z), speed, max_segment_mm, generation)

    def stop(self) -> None:
        """Stop moving now; a move waiting in :meth:`move_to` raises :class:`SwiftProStopped`,
        and every move begun before this call (``unless_stopped_since``) refuses to be sent.

        The stop command never waits for a request slot. 4.5+ sends ``S1100`` (clears the
        planner); 4.0-4.4 ``S1000 V0`` (pause: nothing more moves until :meth:`resume`);
        3.x ``M2000`` (clears the command queue, quick-stops the steppers; ``G2203`` only waits
        for the end of motion). Whether the firmware ever answers the cut move is UNCERTAIN, so its
        number is retired here. The :attr:`stop_switch` stays held until :meth:`resume`.
        """
        self._motion.stop()

    def resume(self) -> None:
        """Release the :attr:`stop_switch`; on firmware 4.0-4.4 also let the arm move again
        after :meth:`stop` paused it (other firmware's stop clears the planner: no command).

        4.0-4.4 has no planner clear (``S1100`` is 4.5+), so the move the pause cut short is
        still at the head of the firmware's queue and goes on with ``S1000 V1``. Rather than
        let it run after (or between) new moves, resume sends ``S1000 V1``, then waits for
        that old move to end: a harmless M2222 question queued behind it is answered only
        when the queue is empty (4.x answers G/M commands when idle). Then it re-reads the
        position, from which the next move is checked. The old move was checked against
        the envelope when it was sent, so finishing it stays inside. A :meth:`stop` while
        resuming wins (the arm is paused again) and makes resume raise :class:`SwiftProStopped`.

        Raises:
            SwiftProStopped: a stop came while resuming (the switch stays held).
            SwiftProTimeout, SwiftProDisconnected: the link failed (the arm stays marked paused).
        """
        self._motion.resume()

    def beep(self, frequency_hz: float = 1000.0, duration_ms: float = 200.0) -> None:
        """Sound the buzzer (M2210 F T; both fields on 4.x).

        Args:
            frequency_hz: pitch, 50..10000 Hz.
            duration_ms: length, 1..5000 ms.
        """
        if not (is_real(frequency_hz) and 50 <= frequency_hz <= 10000):
            raise ValueError(f"frequency_hz: expected a number in 50..10000 Hz, got {frequency_hz!r}")
        if not (is_real(duration_ms) and 1 <= duration_ms <= 5000):
            raise ValueError(f"duration_ms: expected a number in 1..5000 ms, got {duration_ms!r}")
        self._request("M2210", ("F", frequency_hz), ("T", duration_ms), timeout=self.timeout + duration_ms / 1000)

    def attach(self) -> None:
        """Power all motors (M17) and make the firmware re-read where the arm is (the
        dialect's ``refresh_position``: after a move by hand, 3.x would otherwise plan from
        where it believes the arm still is)."""
        self._request("M17")
        refresh = self.dialect.refresh_position
        if refresh is not None:
            self._request(refresh[0], *refresh[1:])
        self._motion.forget_position()

    def detach(self) -> None:
        """Release all motors (M2019): the arm can be moved by hand (and may sag)."""
        self._request("M2019")
        self._motion.forget_position()

    def set_position_reports(self, interval_s: float | None) -> None:
        """Ask for ``@3`` position events every ``interval_s`` seconds (M2120); None or 0 stops them."""
        if interval_s is None or (is_real(interval_s) and interval_s == 0):
            self._request("M2120", ("V", 0))
            return
        if not (is_real(interval_s) and math.isfinite(interval_s) and 0.01 <= interval_s <= 60):
            raise ValueError(f"interval_s: expected None, 0 or a number in 0.01..60 s, got {interval_s!r}")
        self._request("M2120", ("V", interval_s))
