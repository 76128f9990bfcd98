"""The uArm Swift Pro: a connector over pyserial, its safety envelope, a simulated arm, the bridge.

Layers, bottom up: :mod:`.protocol` (the text of the lines), :mod:`.link` (the serial link),
:mod:`.dialects` (firmware generations), :mod:`.stop` and :mod:`.motion` (the one stop
mechanism; the motion and safety policy, with :mod:`.envelope`), :mod:`.connector`
(:class:`SwiftPro`), :mod:`.bridge` (the teaching plant on the arm, no Jupyter). Beside them,
:mod:`.simdevice` (:class:`SimulatedSwiftPro`, made of the ``sim_*`` modules: kinematics,
number grammars, the firmware loop, the shared, 4.x and 3.x command sets, the EEPROM).
The SO-101 on its Feetech bus is the subpackage :mod:`.feetech`.

Importing this package registers the pyserial URL handler ``uarm-sim://`` (also spelled
``uarmsim://``), so ``SwiftPro("uarm-sim://?firmware=4&latency=0.003")`` talks to the
simulated arm exactly as ``SwiftPro("/dev/ttyACM0")`` talks to a real one.
"""

import sys

import serial

from .bridge import ExecutionReport, UArmBridge, connect_arm
from .connector import SwiftPro
from .envelope import TEACHING_HEIGHT_MM, TEACHING_MAX_YAW_DEG, TEACHING_RADIUS_MM, SafetyEnvelope
from .errors import (
    ERROR_CLASSES,
    SwiftProBufferFull,
    SwiftProCommandError,
    SwiftProDisconnected,
    SwiftProEncoderError,
    SwiftProError,
    SwiftProMotorsDetached,
    SwiftProNotFound,
    SwiftProOperationFailed,
    SwiftProParameterError,
    SwiftProPortBusy,
    SwiftProPowerError,
    SwiftProStopped,
    SwiftProTimeout,
    SwiftProUnknownCommand,
    SwiftProUnreachable,
    UnsafeMoveError,
)
from .feetech import SO101, SO101Envelope, SO101Error, SO101Stopped
from .protocol import Event
from .sim_kinematics import is_reachable
from .simdevice import SimulatedSwiftPro
from .stop import StopSwitch
from .urlhandler import protocol_uarmsim

_HANDLERS = __name__ + ".urlhandler"
if _HANDLERS not in serial.protocol_handler_packages:
    serial.protocol_handler_packages.append(_HANDLERS)
# pyserial imports "<package>.protocol_<scheme>"; "uarm-sim" has a hyphen, which no module
# file name can hold, so the module is also filed under that name.
sys.modules.setdefault(_HANDLERS + ".protocol_uarm-sim", protocol_uarmsim)

__all__ = [
    "ERROR_CLASSES", "Event", "ExecutionReport", "SafetyEnvelope", "SimulatedSwiftPro", "StopSwitch", "SwiftPro",
    "SO101", "SO101Envelope", "SO101Error", "SO101Stopped",
    "SwiftProBufferFull", "SwiftProCommandError", "SwiftProDisconnected", "SwiftProEncoderError", "SwiftProError",
    "SwiftProMotorsDetached", "SwiftProNotFound", "SwiftProOperationFailed", "SwiftProParameterError",
    "SwiftProPortBusy", "SwiftProPowerError", "SwiftProStopped", "SwiftProTimeout", "SwiftProUnknownCommand",
    "SwiftProUnreachable", "TEACHING_HEIGHT_MM", "TEACHING_MAX_YAW_DEG", "TEACHING_RADIUS_MM",
    "UArmBridge", "UnsafeMoveError", "connect_arm", "is_reachable",
]
