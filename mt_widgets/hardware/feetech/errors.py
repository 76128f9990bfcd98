"""Errors of the SO-101 and its Feetech bus, each in words a student understands.

Every failure of the arm or of its link is an :class:`SO101Error`. The connector turns a bus
fault into one of these after it has stopped the arm (torque held where it is), and the
message says what happened and what to do, as the uArm's errors do
(``mt_widgets/hardware/errors.py``). A move refused before anything was sent is an
:class:`~mt_widgets.hardware.errors.UnsafeMoveError` (a ``ValueError``), shared with the uArm.
"""

from __future__ import annotations

from .packet import StatusError

#: What each status error bit means, for a person.
_MEANINGS = {
    StatusError.VOLTAGE: "its power supply is too low or too high (is the 12 V supply plugged in and on?)",
    StatusError.SENSOR: "its position sensor failed",
    StatusError.OVERHEAT: "it is too hot (let the arm rest a few minutes)",
    StatusError.OVERCURRENT: "it drew too much current",
    StatusError.OVERLOAD: "it was blocked or carried too much and let go (free the joint, then turn the torque "
                          "on again with torque(True))",
}


def describe(error: int) -> str:
    """The status error byte in words, e.g. ``"it is too hot (...)"``."""
    parts = [text for bit, text in _MEANINGS.items() if error & bit]
    unknown = error & ~sum(_MEANINGS)
    if unknown:
        parts.append(f"it reported an unknown error (bits 0x{unknown:02X})")
    return "; ".join(parts) if parts else "no error"


class SO101Error(Exception):
    """Base class of every error of the SO-101 or of its bus."""


class BusDisconnected(SO101Error, ConnectionError):
    """The serial port closed, vanished or failed (the USB cable was pulled, or a wrong port)."""


class ServoNotAnswering(SO101Error, TimeoutError):
    """A servo did not answer in time.

    Attributes:
        servo_id: the silent servo's id.
    """

    def __init__(self, message: str, *, servo_id: int):
        super().__init__(message)
        self.servo_id = servo_id


class CorruptReply(SO101Error):
    """An answer arrived damaged (its checksum did not match): noise on the bus or a loose wire.

    Attributes:
        servo_id: the servo whose answer was damaged.
    """

    def __init__(self, message: str, *, servo_id: int):
        super().__init__(message)
        self.servo_id = servo_id


class ServoFault(SO101Error):
    """A servo answered with error bits set (see :class:`~.packet.StatusError`).

    Attributes:
        servo_id: the servo's id.
        error: its error byte.
    """

    def __init__(self, message: str, *, servo_id: int, error: int):
        super().__init__(message)
        self.servo_id = servo_id
        self.error = error


class WrongServo(SO101Error):
    """A servo on the bus is missing or is not an STS3215 (another model number)."""


class CalibrationError(SO101Error, ValueError):
    """A calibration file is missing, malformed, or belongs to another arm."""
