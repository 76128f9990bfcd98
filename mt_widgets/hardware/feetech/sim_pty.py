"""The simulated SO-101 on a real serial device: a pseudo-terminal served by a thread (POSIX).

``SimulatedArmPort(SimulatedBus()).path`` is a device path (``/dev/pts/N``) that the
connector, the SDK's ``PortHandler`` or LeRobot open as they open ``/dev/ttyACM0``.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty

from .sim_bus import SimulatedBus


class SimulatedArmPort:
    """Serve ``bus`` on the master side of a new pseudo-terminal until :meth:`close`.

    Attributes:
        path: the slave side's device path, to open as a serial port.
    """

    def __init__(self, bus: SimulatedBus):
        self.bus = bus
        self.master, self.slave = os.openpty()
        tty.setraw(self.master)
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self._stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, name="so101-sim", daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            now = time.monotonic()
            due = self.bus.next_due(now)
            wait = 0.01 if due is None else min(0.01, max(0.0, due - now))
            try:
                readable, _, _ = select.select([self.master], [], [], wait)
                if readable:
                    self.bus.write(os.read(self.master, 4096), time.monotonic())
                if self.bus.disconnected:
                    self._hang_up()
                    return
                out = self.bus.read_available(time.monotonic())
                if out:
                    os.write(self.master, out)
            except OSError:
                return

    def _hang_up(self) -> None:
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
            self._hang_up()

    def __enter__(self) -> SimulatedArmPort:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
