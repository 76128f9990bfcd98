"""Teaching the SO-101 by hand against the simulated arm: the arm moved by hand, a leader arm
moved by hand, and a cable pulled mid-demonstration."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from mt_widgets.core import SKILLS
from mt_widgets.hardware.feetech import ARM_JOINTS, SO101, SO101_IDS, BusDisconnected
from mt_widgets.hardware.feetech.hand import HandDemonstration
from mt_widgets.hardware.feetech.reproduction import play_on_arm, waypoints
from mt_widgets.hardware.feetech.sim_hand import SimulatedHand
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort

from .so101_support import CALIBRATION, calibrated_bus

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")

SKILL = SKILLS["so101-reach"]
#: The query states of the reach skill (seed 0), and the arrow's length per unit of action.
STATES = SKILL.query_states(seed=0)
LENGTH = SKILL.plant.drawing().action_length


@pytest.fixture
def sim_arm():
    bus = calibrated_bus()
    with SimulatedArmPort(bus) as server, SO101(server.path, CALIBRATION, timeout=0.25) as arm:
        yield bus, arm, SimulatedHand(bus, arm.calibration, arm.kinematics)


def joints(arm):
    q = arm.positions()
    return np.array([q[j] for j in ARM_JOINTS])


def test_the_tool_moved_by_hand_is_the_demonstrated_action_and_the_arm_goes_back(sim_arm):
    bus, arm, hand = sim_arm
    move = HandDemonstration(arm, STATES[0], LENGTH)
    move.begin()
    assert joints(arm) == pytest.approx(STATES[0], abs=0.003)   # the arm drove itself to the query state
    assert hand.limp and move.released
    shown = np.array([0.03, -0.02, 0.01])                         # m: where the hand takes the gripper
    assert hand.move_tool_by(shown)
    assert move.poll() == pytest.approx(shown / LENGTH, abs=0.004)
    move.end()
    assert not hand.limp and not move.released
    assert joints(arm) == pytest.approx(STATES[0], abs=0.003)   # and drove itself back
    assert len(move.samples) == 2


def test_a_leader_arm_teaches_at_the_follower_s_query_state_while_the_follower_holds(sim_arm):
    bus, arm, _ = sim_arm
    leader_bus = calibrated_bus()
    with SimulatedArmPort(leader_bus) as server, SO101(server.path, CALIBRATION, timeout=0.25) as leader:
        leader_hand = SimulatedHand(leader_bus, leader.calibration, leader.kinematics)
        move = HandDemonstration(arm, STATES[1], LENGTH, leader=leader)
        move.begin()
        start = leader_hand.joints()
        turned = start + np.array([0.1, -0.05, 0.08, 0.0, 0.0])   # the leader's joints turned by hand
        assert leader_hand.move_joints(turned)
        action = move.poll()
        chain = arm.kinematics
        expected = (chain.tool_point(STATES[1] + (turned - start)) - chain.tool_point(STATES[1])) / LENGTH
        assert action == pytest.approx(expected, abs=0.004)
        assert all(bus.servos[SO101_IDS[j]].torque for j in ARM_JOINTS)   # the follower held on
        assert joints(arm) == pytest.approx(STATES[1], abs=0.003)
        move.end()


def test_a_cable_pulled_mid_demonstration_is_said_and_keeps_every_reading(sim_arm):
    bus, arm, hand = sim_arm
    move = HandDemonstration(arm, STATES[2], LENGTH)
    move.begin()
    hand.move_tool_by([0.02, 0.0, 0.0])
    shown = move.poll()
    bus.pull_cable()
    with pytest.raises(BusDisconnected, match="switch its power off"):
        move.poll()
    assert len(move.samples) == 2 and move.action == pytest.approx(shown)   # nothing read is lost


def test_bad_input_is_refused_with_its_name():
    with pytest.raises(TypeError, match="arm: expected a connected SO101"):
        HandDemonstration("COM3", STATES[0], LENGTH)
    with pytest.raises(ValueError, match="times, states"):
        waypoints([0.0, 1.0], np.zeros((3, 5)))
    with pytest.raises(TypeError, match="arm: expected a connected SO101"):
        play_on_arm(None, [0.0], np.zeros((1, 5)))


def test_waypoints_keep_the_start_and_the_end_about_every_half_second():
    times = np.linspace(0.0, 2.0, 2001)
    states = np.column_stack([times] * 5)
    t, q = waypoints(times, states, 0.5)
    assert t == pytest.approx([0.0, 0.5, 1.0, 1.5, 2.0])
    assert q[:, 0] == pytest.approx(t)
