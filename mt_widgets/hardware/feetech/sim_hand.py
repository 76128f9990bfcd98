"""A person's hand on the simulated SO-101 (or on a simulated leader arm).

A hand grips the gripper and moves it: the joints turn as the arm's geometry lets them. Here the
hand is given a point for the gripper frame (m, base frame); the joint angles that put the tool
there, nearest the present ones, come from the arm's kinematics, and each servo's shaft is turned
to them (``SimulatedBus.hand_move``), as a hand turns a servo whose torque is off. A servo holding
with its torque on does not give way, and then neither does the arm.
"""

from __future__ import annotations

import time

import numpy as np

from .arm import ARM_JOINTS, SO101_IDS
from .calibration import JointCalibration, calibration_from_dict
from .kinematics import ArmKinematics
from .sim_bus import SimulatedBus


class SimulatedHand:
    """Move the simulated arm's tool by hand.

    Args:
        bus: the simulated servos the hand grips.
        calibration: the arm's calibration ({joint: JointCalibration} or LeRobot's mapping).
        kinematics: the arm's ``ArmKinematics``.
    """

    #: The table top's height (m, base frame): a hand cannot push the gripper through it.
    table_height = 0.0

    def __init__(self, bus: SimulatedBus, calibration, kinematics: ArmKinematics):
        if not isinstance(bus, SimulatedBus):
            raise TypeError(f"bus: expected a SimulatedBus, got {type(bus).__name__}")
        if not isinstance(kinematics, ArmKinematics):
            raise TypeError(f"kinematics: expected an ArmKinematics, got {type(kinematics).__name__}")
        if not all(isinstance(c, JointCalibration) for c in dict(calibration).values()):
            calibration = calibration_from_dict(dict(calibration))
        self.bus, self.calibration, self.kinematics = bus, dict(calibration), kinematics

    def joints(self, now: float | None = None) -> np.ndarray:
        """(5,) rad, the arm joints where the shafts are now."""
        present = self.bus.present_positions(time.monotonic() if now is None else now)
        return np.array([self.calibration[j].to_radians(present[SO101_IDS[j]]) for j in ARM_JOINTS])

    def tool_point(self, now: float | None = None) -> np.ndarray:
        """(3,) m, where the gripper frame is now."""
        return self.kinematics.tool_point(self.joints(now))

    @property
    def limp(self) -> bool:
        """Whether every arm joint gives way to a hand (torque off, or dropped by an overload)."""
        return all(not s.torque or s.overloaded for i, s in self.bus.servos.items() if i != SO101_IDS["gripper"])

    def move_joints(self, q, now: float | None = None) -> bool:
        """Turn the arm joints to ``q`` (5,) rad; False (nothing moves) if a servo holds."""
        q = np.asarray(q, dtype=float)
        if q.shape != (len(ARM_JOINTS),) or not np.all(np.isfinite(q)):
            raise ValueError(f"q: expected {len(ARM_JOINTS)} finite joint angles (rad), got {q!r}")
        if not self.limp:
            return False
        steps = {SO101_IDS[j]: self.calibration[j].to_steps(float(v)) for j, v in zip(ARM_JOINTS, q)}
        return self.bus.hand_move(steps, time.monotonic() if now is None else now)

    def move_tool_to(self, point, now: float | None = None) -> bool:
        """Bring the tool to ``point`` (3,) m (a point under the table top: onto it); False if the arm
        holds or cannot reach it."""
        point = np.asarray(point, dtype=float)
        if point.shape != (3,) or not np.all(np.isfinite(point)):
            raise ValueError(f"point: expected (x, y, z) in m, got {point!r}")
        point = np.array([point[0], point[1], max(point[2], self.table_height)])  # not through the table
        q = self.kinematics.solve(point, self.joints(now))
        return q is not None and self.move_joints(q, now)

    def move_tool_by(self, displacement, now: float | None = None) -> bool:
        """Move the tool by ``displacement`` (3,) m from where it is."""
        return self.move_tool_to(self.tool_point(now) + np.asarray(displacement, dtype=float), now)


__all__ = ["SimulatedHand"]
