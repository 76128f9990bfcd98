"""pyserial URL handler ``uarm-sim://`` (also ``uarmsim://``): a simulated Swift Pro.

Importing :mod:`mt_widgets.hardware` registers it, after which::

    serial.serial_for_url("uarm-sim://?firmware=4&latency=0.003")

opens a port with the simulated arm (:class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`)
on the other side. pyserial imports ``<package>.protocol_<scheme>`` for a URL's scheme; a
hyphen cannot be in a file's module name, so this module is ``protocol_uarmsim`` and
:mod:`mt_widgets.hardware` also files it in ``sys.modules`` under ``protocol_uarm-sim``.

URL options (all optional):
    firmware: 3 or 4 (default 4).
    version: the firmware version P2203 reports, e.g. ``4.2`` (default 4.10.0 / 3.2.0); before
        4.5 stop is a pause (``S1000 V0``) and ``S1100`` does not exist.
    boot: seconds from opening to the banner (default 0.3; tests use 0.01).
    latency: seconds added to each line the arm sends (default 0).
    motion_scale: factor on move durations (default 1).
    chatter: seconds between random unsolicited ``@3/@5/@6/@9`` lines (default none).
    baud: simulate the wire time of each sent line at this rate (default none).
    device: what P2201 answers (default ``SwiftPro``; ``Swift`` for the non-Pro arm).
    start: ``x,y,z`` tool position in mm at power-on (default ``200,0,100``).
    seed: seed of the random chatter (default 0).
    drop: lose the reply to the n-th command line (fault).
    close_after: the port closes when the n-th command line arrives (fault).
    busy: 1 makes reads fail as a port held by another program does (fault).
    name: share one arm between ports opened with the same name; an exclusive open of a
        name already open fails, a non-exclusive one becomes a second reader (fault).
"""

from __future__ import annotations

import threading
import time
import urllib.parse

from serial.serialutil import PortNotOpenError, SerialBase, SerialException

from ..simdevice import SimulatedSwiftPro

_SHARED: dict[str, tuple[SimulatedSwiftPro, set]] = {}
_SHARED_LOCK = threading.Lock()
_BUSY_MESSAGE = ("device reports readiness to read but returned no data "
                 "(device disconnected or multiple access on port?)")


def device_from_url(url: str) -> tuple[SimulatedSwiftPro, dict[str, str]]:
    """Build the simulated arm a ``uarm-sim://`` URL describes.

    Args:
        url: e.g. ``"uarm-sim://?firmware=3&boot=0.01"``.

    Returns:
        The (not yet powered) device and the URL's options.

    Raises:
        SerialException: for an unknown scheme or option, or a value of the wrong form.
    """
    parts = urllib.parse.urlsplit(url)
    if parts.scheme.lower() not in ("uarm-sim", "uarmsim"):
        raise SerialException(f"expected a URL starting with uarm-sim://, got {url!r}")
    options = {k: v[-1] for k, v in urllib.parse.parse_qs(parts.query, keep_blank_values=True).items()}
    known = {"firmware", "version", "boot", "latency", "motion_scale", "chatter", "baud", "device", "start", "seed",
             "drop", "close_after", "busy", "name"}
    unknown = sorted(set(options) - known)
    if unknown:
        raise SerialException(f"uarm-sim:// options: expected names among {sorted(known)}, got {unknown}")
    try:
        kwargs = {
            "firmware": int(options.get("firmware", 4)),
            "version": options.get("version") or None,
            "boot_delay": float(options.get("boot", 0.3)),
            "latency": float(options.get("latency", 0.0)),
            "motion_scale": float(options.get("motion_scale", 1.0)),
            "chatter": float(options["chatter"]) if options.get("chatter") else None,
            "baud": float(options["baud"]) if options.get("baud") else None,
            "device_name": options.get("device", "SwiftPro"),
            "seed": int(options.get("seed", 0)),
        }
        if "start" in options:
            start = tuple(float(v) for v in options["start"].split(","))
            if len(start) != 3:
                raise ValueError(f"start: expected x,y,z in mm, got {options['start']!r}")
            kwargs["start"] = start
        device = SimulatedSwiftPro(**kwargs)
        if "drop" in options:
            device.drop_reply_to_line(int(options["drop"]))
        if "close_after" in options:
            device.disconnect_on_command(int(options["close_after"]))
    except ValueError as exc:
        raise SerialException(f"bad uarm-sim:// URL {url!r}: {exc}") from exc
    return device, options


class Serial(SerialBase):
    """A pyserial port whose other end is a :class:`SimulatedSwiftPro`.

    The device is available as ``port.device`` for tests (fault injection, the lines it
    received).
    """

    def __init__(self, *args, **kwargs):
        self.device: SimulatedSwiftPro | None = None
        self._cond = threading.Condition()
        self._rx = bytearray()
        self._cancel = False
        self._busy = False
        self._name: str | None = None
        super().__init__(*args, **kwargs)

    # ---------------------------------------------------------------- open / close
    def open(self):
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        device, options = device_from_url(self._port)
        self._busy = options.get("busy", "0") not in ("", "0")
        name = options.get("name")
        now = time.monotonic()
        if name:
            with _SHARED_LOCK:
                if name in _SHARED and _SHARED[name][1]:
                    if self._exclusive:
                        raise SerialException(
                            f"Could not exclusively lock port {self._port}: already open (uarm-sim name {name!r})")
                    device = _SHARED[name][0]  # a second reader on the same arm
                else:
                    _SHARED[name] = (device, set())
                    device.power_on(now)
                _SHARED[name][1].add(id(self))
            self._name = name
        else:
            device.power_on(now)
        self.device = device
        self._rx.clear()
        self._cancel = False
        self.is_open = True

    def close(self):
        if self.is_open:
            self.is_open = False
            if self._name:
                with _SHARED_LOCK:
                    _SHARED.get(self._name, (None, set()))[1].discard(id(self))
            with self._cond:
                self._cond.notify_all()
        super().close()

    def _reconfigure_port(self, *args, **kwargs):
        """Line settings mean nothing to the simulated arm."""

    def _update_dtr_state(self):
        """DTR is not simulated (opening the port is the reset)."""

    def _update_rts_state(self):
        """RTS is not simulated."""

    def _update_break_state(self):
        """Break is not simulated."""

    # ---------------------------------------------------------------- data
    def _check(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()
        if self.device.disconnected:
            raise SerialException(f"read failed: the simulated arm on {self._port} closed the port")
        if self._busy:
            raise SerialException(_BUSY_MESSAGE)

    def _pull(self, now: float) -> None:
        self._rx += self.device.read_available(now)

    @property
    def in_waiting(self) -> int:
        self._check()
        with self._cond:
            self._pull(time.monotonic())
            return len(self._rx)

    def read(self, size: int = 1) -> bytes:
        """Read up to ``size`` bytes, waiting at most ``timeout`` seconds (None: forever)."""
        self._check()
        deadline = None if self._timeout is None else time.monotonic() + self._timeout
        with self._cond:
            while True:
                self._check()
                now = time.monotonic()
                self._pull(now)
                if len(self._rx) >= size or self._cancel or (deadline is not None and now >= deadline):
                    break
                due = self.device.next_due(now)
                waits = [t - now for t in (due, deadline) if t is not None]
                self._cond.wait(max(0.0, min(waits)) if waits else None)
            self._cancel = False
            data = bytes(self._rx[:size])
            del self._rx[:size]
            return data

    def write(self, data) -> int:
        self._check()
        data = bytes(data)
        with self._cond:
            self.device.write(data, time.monotonic())
            self._cond.notify_all()
        return len(data)

    def cancel_read(self):
        with self._cond:
            self._cancel = True
            self._cond.notify_all()

    def reset_input_buffer(self):
        self._check()
        with self._cond:
            self._pull(time.monotonic())
            self._rx.clear()

    def reset_output_buffer(self):
        """Nothing is buffered on the way out: writes reach the arm at once."""
        self._check()

    @property
    def out_waiting(self) -> int:
        return 0

    @property
    def cts(self):
        return True

    @property
    def dsr(self):
        return True

    @property
    def ri(self):
        return False

    @property
    def cd(self):
        return True


def serial_class_for_url(url: str):
    """pyserial hook: the class for a ``uarm-sim://`` URL."""
    return url, Serial
