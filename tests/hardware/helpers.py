"""Helpers for the hardware tests: simulated-arm URLs and a pseudo-terminal server."""

from __future__ import annotations

import threading
import time

# Importing the package (for SwiftPro) also registers the uarm-sim:// URL handler.
from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.sim_pty import SimulatedPort
from mt_widgets.hardware.simdevice import SimulatedSwiftPro

#: Fast defaults: a 10 ms boot, moves 100x faster than real.
FAST = {"boot": "0.01", "motion_scale": "0.01"}


def sim_url(**options) -> str:
    """A uarm-sim:// URL with fast defaults, overridden by ``options``."""
    merged = {**FAST, **{k: str(v) for k, v in options.items()}}
    return "uarm-sim://?" + "&".join(f"{k}={v}" for k, v in merged.items())


def device_of(arm: SwiftPro) -> SimulatedSwiftPro:
    """The simulated arm behind a connected SwiftPro on a uarm-sim:// port."""
    return arm._link.serial.device


def sent_lines(arm: SwiftPro) -> list[str]:
    return list(device_of(arm).received_lines)


def wait_until(condition, timeout: float = 10.0, what: str = "the condition") -> None:
    """Poll ``condition()`` until true; fail after ``timeout`` s (a guard against hangs only)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} did not happen within {timeout} s")
        time.sleep(0.002)


class InThread:
    """``call(*args)`` run in a thread of its own; ``raised()`` joins it and returns what it raised.

    ``pytest.raises`` inside a thread cannot fail a test (a DID NOT RAISE there is only a thread's
    warning), so the test asserts on ``raised()`` in its own thread instead.
    """

    def __init__(self, call, *args):
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, args=(call, args), daemon=True)
        self._thread.start()

    def _run(self, call, args) -> None:
        try:
            call(*args)
        except BaseException as error:   # handed to the test's thread
            self._error = error

    def raised(self, timeout: float = 10.0) -> BaseException | None:
        """What the call raised (None when it returned); fails when it is still running after ``timeout``."""
        self._thread.join(timeout)
        if self._thread.is_alive():
            raise AssertionError(f"the call in a thread did not end within {timeout} s")
        return self._error


def arm_is_moving(arm: SwiftPro) -> bool:
    """Whether the simulated arm behind ``arm`` has a move under way now."""
    return device_of(arm).moving_at(time.monotonic())


class PtyArm(SimulatedPort):
    """A simulated uArm, powered on, served on the master side of a pseudo-terminal by a thread.

    Args:
        device: the simulated arm.

    Attributes:
        path: the slave device path, to be opened as a serial port.
    """

    def __init__(self, device: SimulatedSwiftPro):
        device.power_on(time.monotonic())
        super().__init__(device, poll=0.02, name="uarm-sim")
