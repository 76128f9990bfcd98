"""Errors raised by the uArm Swift Pro connector.

Every failure of the arm or of the link is a :class:`SwiftProError`; each firmware error
code E20..E27 (``docs/uarm-protocol.md``, "Errors and events") has its own subclass so that
callers can catch, say, an unreachable target without parsing messages. A move refused by
the software safety envelope is an :class:`UnsafeMoveError`, a ``ValueError``: nothing was
sent, the arguments were wrong.
"""

from __future__ import annotations


class SwiftProError(Exception):
    """Base class of every error of the arm or of its serial link."""


class SwiftProCommandError(SwiftProError):
    """The firmware answered a command with an error code.

    Attributes:
        code: the firmware error number (20..27), or None if unknown.
        command: the command line that was sent (without its ``#n`` number), if known.
        line: the raw line received from the arm.
    """

    code: int | None = None
    meaning = "error"

    def __init__(self, message: str, *, command: str | None = None, line: str | None = None):
        super().__init__(message)
        self.command = command
        self.line = line


class SwiftProUnknownCommand(SwiftProCommandError):
    """E20: the firmware does not know the command."""

    code = 20
    meaning = "no such command"


class SwiftProParameterError(SwiftProCommandError):
    """E21: a parameter is missing or malformed (e.g. ``1e-05`` instead of ``0.00001``)."""

    code = 21
    meaning = "parameter error"


class SwiftProUnreachable(SwiftProCommandError):
    """E22: the target is out of the arm's range.

    Firmware 4.x answers ``$n E22``, firmware 3.x ``$n ok E22 unreachable``.
    """

    code = 22
    meaning = "out of range (unreachable)"


class SwiftProBufferFull(SwiftProCommandError):
    """E23: the firmware's command queue (20 G/M commands on 4.x) is full."""

    code = 23
    meaning = "command buffer full"


class SwiftProPowerError(SwiftProCommandError):
    """E24: the arm's power supply is not connected."""

    code = 24
    meaning = "power unconnected"


class SwiftProOperationFailed(SwiftProCommandError):
    """E25: the firmware reports an operation failure."""

    code = 25
    meaning = "operation failure"


class SwiftProEncoderError(SwiftProCommandError):
    """E26: the firmware could not talk to a joint encoder."""

    code = 26
    meaning = "encoder communication failed"


class SwiftProMotorsDetached(SwiftProCommandError):
    """E27: a move was asked while the motors are disabled (detached)."""

    code = 27
    meaning = "motor disabled"


#: Firmware error number -> exception class.
ERROR_CLASSES: dict[int, type[SwiftProCommandError]] = {
    cls.code: cls
    for cls in (
        SwiftProUnknownCommand,
        SwiftProParameterError,
        SwiftProUnreachable,
        SwiftProBufferFull,
        SwiftProPowerError,
        SwiftProOperationFailed,
        SwiftProEncoderError,
        SwiftProMotorsDetached,
    )
}


def error_for_code(code: int, *, command: str | None, line: str) -> SwiftProCommandError:
    """Build the typed exception for a firmware error code.

    Args:
        code: the number after ``E`` in the reply.
        command: the command that failed, for the message.
        line: the raw reply line.

    Returns:
        An instance of the matching :class:`SwiftProCommandError` subclass (the base
        class itself for a code outside E20..E27).
    """
    cls = ERROR_CLASSES.get(code, SwiftProCommandError)
    what = cls.meaning if code in ERROR_CLASSES else "unknown error code"
    subject = f"command {command!r}" if command else "the arm"
    err = cls(f"{subject} failed with E{code} ({what}); arm replied {line!r}", command=command, line=line)
    if cls is SwiftProCommandError:
        err.code = code
    return err


class SwiftProTimeout(SwiftProError, TimeoutError):
    """No answer came in time. The request's number is retired so that a late reply is
    never taken for the answer to a later request."""


class SwiftProDisconnected(SwiftProError, ConnectionError):
    """The serial port closed, vanished or failed while talking to the arm."""


class SwiftProPortBusy(SwiftProDisconnected):
    """Another program holds the port (uArm-Python-SDK issue #11: "device reports
    readiness to read but returned no data")."""


class SwiftProNotFound(SwiftProError):
    """Auto-detection found no Swift Pro on any USB serial port."""


class SwiftProStopped(SwiftProError):
    """A move was cut short by :meth:`SwiftPro.stop`."""


class UnsafeMoveError(ValueError):
    """A move was refused before anything was sent: it leaves the safety envelope, steps
    too far, goes too fast, or the arm itself says the target is unreachable.

    Attributes:
        coordinate: what was out of bounds (``"x"``, ``"radius"``, ``"speed"``, ...).
        value: the offending value.
        limit: the bound it broke.
    """

    def __init__(self, message: str, *, coordinate: str, value: float, limit: float | None):
        super().__init__(message)
        self.coordinate = coordinate
        self.value = value
        self.limit = limit
