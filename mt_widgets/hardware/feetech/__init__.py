"""The SO-101 arm on its Feetech bus: protocol, client, connector, safety envelope, simulated arm.

Layers, bottom up: :mod:`.packet` (framing, checksum, instructions, status error bits),
:mod:`.control_table` (the STS3215's registers), :mod:`.bus` (the host's client over pyserial),
:mod:`.arm` (joint names and ids), :mod:`.calibration` (LeRobot's file, steps <-> radians),
:mod:`.kinematics` (the one adapter to a kinematic model), :mod:`.envelope` and
:mod:`.connector` (:class:`SO101`). Beside them the simulated arm: :mod:`.sim_servo` (one
STS3215), :mod:`.sim_bus` (six on a 1 Mbit/s bus, with faults) and :mod:`.sim_pty` (served on
a pseudo-terminal).
"""

from .arm import ARM_JOINTS, GRIPPER, SO101_IDS
from .bus import FeetechBus
from .calibration import JointCalibration, read_calibration, write_calibration
from .connector import SO101, SO101Stopped
from .envelope import SO101Envelope
from .errors import (
    BusDisconnected,
    CalibrationError,
    CorruptReply,
    ServoFault,
    ServoNotAnswering,
    SO101Error,
    WrongServo,
)
from .kinematics import ArmKinematics
from .packet import Instruction, StatusError
from .sim_bus import SimulatedBus
from .sim_servo import SimulatedServo

__all__ = [
    "ARM_JOINTS", "ArmKinematics", "BusDisconnected", "CalibrationError", "CorruptReply", "FeetechBus", "GRIPPER",
    "Instruction", "JointCalibration", "SO101", "SO101Envelope", "SO101Error", "SO101Stopped", "SO101_IDS",
    "ServoFault", "ServoNotAnswering", "SimulatedBus", "SimulatedServo", "StatusError", "WrongServo",
    "read_calibration", "write_calibration",
]
