"""The simulated SO-101 for the tests: a LeRobot-style calibration, the arm's chain from its URDF."""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from functools import cache
from importlib.metadata import distribution
from pathlib import Path

from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.hardware.feetech import SO101_IDS, SimulatedBus
from mt_widgets.robot_models.urdf import read_serial_chain

URDF = "robots/so_arm_description/urdf/so101.urdf"

#: A calibration as lerobot-calibrate writes it (the numbers of a real arm's order of magnitude).
CALIBRATION = {
    "shoulder_pan": {"id": 1, "drive_mode": 0, "homing_offset": -1470, "range_min": 760, "range_max": 3330},
    "shoulder_lift": {"id": 2, "drive_mode": 0, "homing_offset": 120, "range_min": 900, "range_max": 3200},
    "elbow_flex": {"id": 3, "drive_mode": 0, "homing_offset": 300, "range_min": 950, "range_max": 3150},
    "wrist_flex": {"id": 4, "drive_mode": 0, "homing_offset": -50, "range_min": 950, "range_max": 3150},
    "wrist_roll": {"id": 5, "drive_mode": 0, "homing_offset": 1000, "range_min": 0, "range_max": 4095},
    "gripper": {"id": 6, "drive_mode": 0, "homing_offset": 700, "range_min": 2000, "range_max": 3400},
}


def urdf_path() -> Path:
    return Path(str(distribution("example-robot-data").locate_file(f"cmeel.prefix/share/example-robot-data/{URDF}")))


@cache
def so101_chain() -> SerialChain:
    """The five arm joints to the gripper frame; the gripper's jaw (a branch) left out."""
    root = ElementTree.fromstring(urdf_path().read_text())
    for joint in root.findall("joint"):
        if joint.get("name") == "gripper":
            root.remove(joint)
    for link in root.findall("link"):
        if link.get("name") == "moving_jaw_so101_v1_link":
            root.remove(link)
    chain = read_serial_chain(ElementTree.tostring(root, encoding="unicode"), "gripper_frame_link")
    return SerialChain(chain["joints"], chain["inertials"], chain["tip"])


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
