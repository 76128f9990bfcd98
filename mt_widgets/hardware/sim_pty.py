"""A simulated device on a real serial device: a pseudo-terminal served by a thread (POSIX).

The simulated arms (the uArm's ``SimulatedSwiftPro``, the SO-101's ``SimulatedBus``) each take bytes
written at a time, answer with bytes due at a later time (their firmware's or their servos' timing)
and can be unplugged. ``SimulatedPort(device).path`` is a device path (``/dev/pts/N``) that a connector,
a vendor's SDK or another program opens as it opens ``/dev/ttyACM0``: the whole serial stack is real.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from typing import Protocol


class SimulatedSerialDevice(Protocol):
    """What a simulated device gives the port: its bytes in, its bytes out when due, its cable."""

    disconnected: bool

    def write(self, data: bytes, now: float) -> None: ...

    def read_available(self, now: float) -> bytes: ...

    def next_due(self, now: float) -> float | None: ...


class SimulatedPort:
    """Serve ``device`` on the master side of a new pseudo-terminal until :meth:`close`.

    Args:
        device: the simulated device.
        poll: the longest wait (s) between looks at the device when nothing is due.
        name: the serving thread's name.

    Attributes:
        path: the slave side's device path, to open as a serial port.
    """

    def __init__(self, device: SimulatedSerialDevice, poll: float = 0.01, name: str = "simulated-port"):
        self.device = device
        self.poll = poll
        self.master, self.slave = os.openpty()
        tty.setraw(self.master)
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, name=name, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            now = time.monotonic()
            due = self.device.next_due(now)
            wait = self.poll if due is None else min(self.poll, max(0.0, due - now))
            try:
                readable, _, _ = select.select([self.master], [], [], wait)
                if readable:
                    self.device.write(os.read(self.master, 4096), time.monotonic())
                if self.device.disconnected:
                    self.hang_up()
                    return
                out = self.device.read_available(time.monotonic())
                if out:
                    os.write(self.master, out)
            except OSError:
                return

    def hang_up(self) -> None:
        """Close both ends, as pulling the cable does."""
        self._stop.set()
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass
        self.master = self.slave = -1

    def close(self) -> None:
        """Stop serving and close the pseudo-terminal."""
        self._stop.set()
        self.thread.join(timeout=1.0)
        if self.master != -1:
            self.hang_up()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()
