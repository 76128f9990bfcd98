"""The simulated SO-101 for the tests: a LeRobot-style calibration, the arm's chain from its URDF."""

from __future__ import annotations

from importlib.metadata import distribution
from pathlib import Path

from mt_widgets.arms import so101_chain as shipped_so101_chain
from mt_widgets.hardware.feetech import SimulatedBus
from mt_widgets.hardware.feetech.sim_bus import SIMULATED_CALIBRATION
from mt_widgets.hardware.feetech.sim_bus import calibrated_bus as package_calibrated_bus

#: A calibration as lerobot-calibrate writes it (the simulated arm's own).
CALIBRATION = SIMULATED_CALIBRATION


#: example-robot-data's own SO-101 URDF: the reference pinocchio reads (the package ships a copy without meshes).
URDF = "robots/so_arm_description/urdf/so101.urdf"


def urdf_path() -> Path:
    return Path(str(distribution("example-robot-data").locate_file(f"cmeel.prefix/share/example-robot-data/{URDF}")))


def so101_chain():
    """The five arm joints to the gripper frame, from the URDF the package ships."""
    return shipped_so101_chain()


def calibrated_bus(speed_scale: float = 50.0, calibration=None) -> SimulatedBus:
    """Six servos with ``calibration`` in their EEPROM (as LeRobot leaves them), each at the
    middle of its range; moves 50 times faster than the real servos by default."""
    return package_calibrated_bus(speed_scale, calibration)
