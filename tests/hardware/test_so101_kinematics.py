"""The SO-101 connector's one kinematic adapter against pinocchio on the whole URDF (the moving
jaw included), and the envelope's joint ranges, table and speed checks without a serial port."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio
import pytest

from mt_widgets.hardware.errors import UnsafeMoveError
from mt_widgets.hardware.feetech import ARM_JOINTS, ArmKinematics, SO101Envelope
from mt_widgets.hardware.feetech.calibration import calibration_from_dict

from .so101_support import CALIBRATION, so101_chain, urdf_path


@pytest.fixture(scope="module")
def reference():
    model = pinocchio.buildModelFromUrdf(str(urdf_path()))
    return model, model.createData(), model.getFrameId("gripper_frame_link")


def _pinocchio_q(model, q5):
    q = pinocchio.neutral(model)
    for name, value in zip(ARM_JOINTS, q5):
        q[model.joints[model.getJointId(name)].idx_q] = value
    return q


def test_the_tool_point_and_the_links_agree_with_pinocchio(reference):
    model, data, frame = reference
    kinematics = ArmKinematics(so101_chain())
    rng = np.random.default_rng(43)
    lower, upper = np.array(so101_chain().lower), np.array(so101_chain().upper)
    for q in rng.uniform(lower, upper, size=(20, 5)):
        pinocchio.framesForwardKinematics(model, data, _pinocchio_q(model, q))
        assert np.allclose(kinematics.tool_point(q), data.oMf[frame].translation, atol=1e-9)
        joints = [data.oMi[model.getJointId(name)].translation for name in ARM_JOINTS[1:]]
        assert np.allclose(kinematics.points(q)[:-1], joints, atol=1e-9)
    assert kinematics.limits["elbow_flex"] == pytest.approx((model.lowerPositionLimit[2], model.upperPositionLimit[2]))


def test_solve_reaches_a_reachable_point_within_the_limits_and_says_none_otherwise():
    kinematics = ArmKinematics(so101_chain())
    target_q = np.array([0.3, 0.4, -0.5, 0.6, 0.0])
    target = kinematics.tool_point(target_q)
    q = kinematics.solve(target, np.zeros(5))
    assert q is not None and np.linalg.norm(kinematics.tool_point(q) - target) < 1e-4
    assert np.all(q >= so101_chain().lower) and np.all(q <= so101_chain().upper)
    assert kinematics.solve([0.9, 0.0, 0.2], np.zeros(5)) is None


def test_a_chain_of_another_robot_is_refused():
    class Other:
        joint_names = ("a", "b")

    with pytest.raises(ValueError, match="chain: expected the SO-101's joints"):
        ArmKinematics(Other())


def test_the_envelope_intersects_the_calibration_and_the_urdf_and_checks_the_table():
    envelope = SO101Envelope(calibration_from_dict(CALIBRATION), ArmKinematics(so101_chain()))
    # shoulder_pan: calibrated +-1.97 rad, URDF +-1.92 rad: the URDF's is the tighter, less the margin.
    assert envelope.ranges["shoulder_pan"] == pytest.approx((-1.91986 + 0.05, 1.91986 - 0.05))
    # gripper: not in the chain, its calibrated range alone.
    c = calibration_from_dict(CALIBRATION)["gripper"]
    assert envelope.ranges["gripper"] == pytest.approx((c.range_radians[0] + 0.05, c.range_radians[1] - 0.05))
    home = dict.fromkeys(ARM_JOINTS, 0.0)
    envelope.check_path(home, {**home, "shoulder_pan": 1.0})
    # Down to the table: refused, with the lowest height and the floor.
    with pytest.raises(UnsafeMoveError) as error:
        envelope.check_path(home, {**home, "shoulder_lift": 1.6, "elbow_flex": 0.2})
    assert error.value.coordinate == "z" and error.value.value < error.value.limit == pytest.approx(0.02)
    with pytest.raises(UnsafeMoveError) as error:
        envelope.check_joints({"wrist_flex": 1.65})
    assert error.value.limit == pytest.approx(1.65806 - 0.05)
    with pytest.raises(UnsafeMoveError, match="acceleration"):
        envelope.check_speed(1.0, 7.0)
    with pytest.raises(ValueError, match="speed: expected a number > 0"):
        envelope.check_speed(0.0, 1.0)
    # A live arm's envelope cannot be loosened: not its limits, not its ranges.
    with pytest.raises(dataclasses.FrozenInstanceError):
        envelope.max_speed = 100.0
    with pytest.raises(TypeError):
        envelope.ranges["wrist_flex"] = (-10.0, 10.0)
    assert envelope.max_speed == 1.5 and envelope.ranges["wrist_flex"][1] == pytest.approx(1.65806 - 0.05)


def test_the_table_is_checked_along_the_move_not_only_at_its_ends():
    kinematics = ArmKinematics(so101_chain())
    # Flexing the wrist from up to down with the forearm low: the tool dips lowest mid-way
    # (a pose found by search, its premise checked here).
    start = dict(zip(ARM_JOINTS, (-1.23, -0.3, 0.6, 1.55, 1.55)))
    goal = {**start, "wrist_flex": -0.58}
    a, b = (np.array([pose[j] for j in ARM_JOINTS]) for pose in (start, goal))
    heights = kinematics.points(a + np.linspace(0, 1, 129)[:, None] * (b - a))[..., 2].min(axis=1)
    ends, dip = min(heights[0], heights[-1]), heights.min()
    assert dip < ends - 0.003, "the test's move must dip lower mid-way than at its ends"
    envelope = SO101Envelope(calibration_from_dict(CALIBRATION), kinematics, table_height=(ends + dip) / 2,
                             clearance=0.0, margin=0.0)
    envelope.check_path(start, start)
    envelope.check_path(goal, goal)
    with pytest.raises(UnsafeMoveError, match="below the table"):
        envelope.check_path(start, goal)
