"""The simulated SO-101 for the tests: a LeRobot-style calibration, the arm's chain from its URDF."""

from __future__ import annotations

from importlib.metadata import distribution
from pathlib import Path

from mt_widgets.arms import so101_chain as shipped_so101_chain
from mt_widgets.hardware.feetech import SO101_IDS, SimulatedBus

#: A calibration as lerobot-calibrate writes it (the numbers of a real arm's order of magnitude).
CALIBRATION = {
    "shoulder_pan": {"id": 1, "drive_mode": 0, "homing_offset": -1470, "range_min": 760, "range_max": 3330},
    "shoulder_lift": {"id": 2, "drive_mode": 0, "homing_offset": 120, "range_min": 900, "range_max": 3200},
    "elbow_flex": {"id": 3, "drive_mode": 0, "homing_offset": 300, "range_min": 950, "range_max": 3150},
    "wrist_flex": {"id": 4, "drive_mode": 0, "homing_offset": -50, "range_min": 950, "range_max": 3150},
    "wrist_roll": {"id": 5, "drive_mode": 0, "homing_offset": 1000, "range_min": 0, "range_max": 4095},
    "gripper": {"id": 6, "drive_mode": 0, "homing_offset": 700, "range_min": 2000, "range_max": 3400},
}


#: example-robot-data's own SO-101 URDF: the reference pinocchio reads (the package ships a copy without meshes).
URDF = "robots/so_arm_description/urdf/so101.urdf"


def urdf_path() -> Path:
    return Path(str(distribution("example-robot-data").locate_file(f"cmeel.prefix/share/example-robot-data/{URDF}")))


def so101_chain():
    """The five arm joints to the gripper frame, from the URDF the package ships."""
    return shipped_so101_chain()


def calibrated_bus(speed_scale: float = 50.0, calibration=None) -> SimulatedBus:
    """Six servos with ``calibration`` in their EEPROM (as LeRobot leaves them), each at the
    middle of its range."""
    calibration = CALIBRATION if calibration is None else calibration
    bus = SimulatedBus(speed_scale=speed_scale)
    for joint, servo_id in SO101_IDS.items():
        servo = bus.servos[servo_id]
        c = calibration[joint]
        servo.flash("homing_offset", c["homing_offset"])
        servo.flash("min_position_limit", c["range_min"])
        servo.flash("max_position_limit", c["range_max"])
        servo.position = (c["range_min"] + c["range_max"]) / 2 + c["homing_offset"]
        servo.power_on(0.0)
    return bus
