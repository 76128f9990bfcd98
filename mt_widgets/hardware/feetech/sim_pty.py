"""The simulated SO-101 on a real serial device (POSIX).

``SimulatedArmPort(SimulatedBus()).path`` is a device path (``/dev/pts/N``) that the
connector, the SDK's ``PortHandler`` or LeRobot open as they open ``/dev/ttyACM0``.
"""

from __future__ import annotations

from ..sim_pty import SimulatedPort
from .sim_bus import SimulatedBus


class SimulatedArmPort(SimulatedPort):
    """Serve the six simulated servos of ``bus`` on a new pseudo-terminal until :meth:`close`.

    Attributes:
        path: the slave side's device path, to open as a serial port.
        bus: the simulated servos (inject faults through it).
    """

    def __init__(self, bus: SimulatedBus):
        super().__init__(bus, poll=0.01, name="so101-sim")
        self.bus = bus
