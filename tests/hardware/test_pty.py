"""The connector on a real OS serial device: a pseudo-terminal with the simulated arm on the
master side, served by a thread."""

from __future__ import annotations

import sys
import time

import pytest

from mt_widgets.hardware import SwiftPro, SwiftProDisconnected
from mt_widgets.hardware.simdevice import SimulatedSwiftPro

from .helpers import PtyArm

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


@pytest.fixture(params=[4, 3], ids=["fw4", "fw3"])
def pty_arm(request):
    server = PtyArm(SimulatedSwiftPro(firmware=request.param, boot_delay=0.01, motion_scale=0.01))
    yield server
    server.close()


def test_connect_move_and_read_back_over_a_pseudo_terminal(pty_arm):
    with SwiftPro(pty_arm.path, timeout=1.0) as arm:
        assert arm.firmware_major == pty_arm.device.firmware
        arm.move_to(240.0, -40.0)
        assert arm.position() == pytest.approx((240.0, -40.0, 80.0))
        arm.beep(880, 50)
    assert pty_arm.device.beeps == [(880.0, 50.0)]
    # Every line went through the tty unchanged: numbered, newline-terminated, no \r added.
    assert all(line.startswith("#") for line in pty_arm.device.received_lines)


def test_unplugging_mid_command_raises_disconnected_without_hanging(pty_arm):
    arm = SwiftPro(pty_arm.path, timeout=2.0)
    arm.connect()
    pty_arm.device.disconnect_on_command()
    start = time.monotonic()
    with pytest.raises(SwiftProDisconnected):
        arm.position()
    assert time.monotonic() - start < 1.0
    arm.close()
    assert not arm.connected
