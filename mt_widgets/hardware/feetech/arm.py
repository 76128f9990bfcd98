"""The SO-101's servos: joint names and bus ids, as LeRobot's ``so101_follower`` numbers them."""

from __future__ import annotations

#: Joint name -> servo id (LeRobot's SO-101: five arm joints, then the gripper).
SO101_IDS = {"shoulder_pan": 1, "shoulder_lift": 2, "elbow_flex": 3, "wrist_flex": 4, "wrist_roll": 5, "gripper": 6}
#: The five joints of the arm, base to wrist (the URDF's revolute chain to the gripper frame).
ARM_JOINTS = tuple(name for name in SO101_IDS if name != "gripper")
GRIPPER = "gripper"
