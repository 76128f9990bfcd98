"""Fuzz: random sequences of the SO-101 connector's public calls against the simulated arm never
command a goal outside the envelope, checked on the servos' side of the wire: every goal
position a servo received is inside its joint's range (or is where the shaft already is: the
emergency stop's hold), and every arm pose a move's SYNC_WRITE asked for keeps every link above
the table."""

from __future__ import annotations

import math
import sys
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mt_widgets.hardware.feetech import ARM_JOINTS, SO101, SO101_IDS, SO101Error
from mt_widgets.hardware.feetech.control_table import REGISTERS, decode
from mt_widgets.hardware.feetech.packet import Instruction
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort

from .so101_support import CALIBRATION, calibrated_bus, so101_chain

pytestmark = [pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX"), pytest.mark.slow]

angle = st.floats(-3.5, 3.5, allow_nan=False)
call = st.one_of(
    st.tuples(st.just("move_joints"), st.dictionaries(st.sampled_from(list(SO101_IDS)), angle, min_size=1),
              st.floats(0.05, 3.0)),
    st.tuples(st.just("move_to"), st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-0.2, 0.5)),
    st.tuples(st.just("gripper"), angle),
    st.tuples(st.just("torque"), st.booleans()),
    st.tuples(st.just("hand"), st.dictionaries(st.sampled_from(list(SO101_IDS.values())), st.integers(0, 4095),
                                               min_size=1)),
    st.tuples(st.just("stop")),
)


def _goal_packets(bus):
    """{id: goal steps} of every SYNC_WRITE of a move (acceleration .. goal speed from address 41)."""
    for packet in bus.received:
        if packet.code == Instruction.SYNC_WRITE and packet.parameters[0] == REGISTERS["acceleration"].address:
            size = packet.parameters[1]
            body = packet.parameters[2:]
            yield {body[k]: decode(REGISTERS["goal_position"], body[k + 2:k + 4])
                   for k in range(0, len(body), size + 1)}


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(call, min_size=1, max_size=6))
def test_no_sequence_of_calls_commands_a_goal_outside_the_envelope(calls):
    bus = calibrated_bus(speed_scale=200.0)
    with SimulatedArmPort(bus) as server, SO101(server.path, CALIBRATION, so101_chain(), timeout=0.1) as arm:
        for name, *args in calls:
            try:
                if name == "move_joints":
                    arm.move_joints(args[0], speed=args[1], wait=False)
                elif name == "move_to":
                    arm.move_to(*args, wait=False)
                elif name == "gripper":
                    arm.gripper(args[0], wait=False)
                elif name == "torque":
                    arm.torque(args[0])
                elif name == "hand":
                    bus.hand_move(args[0], time.monotonic())
                else:
                    arm.stop()
                    arm.resume()
            except (ValueError, SO101Error):
                pass   # refused: nothing sent (checked below by what the servos received)
        envelope = arm.envelope
    for joint, servo_id in SO101_IDS.items():
        low, high = envelope.ranges[joint]
        c = arm.calibration[joint]
        servo = bus.servos[servo_id]
        for goal, hold in zip(servo.goals_written, servo.holds):
            # A stop holds the shaft where it is (no motion), wherever a hand left it.
            assert hold or low - 1e-3 <= c.to_radians(goal) <= high + 1e-3, (joint, goal)
    floor = envelope.table_height + envelope.clearance
    for goals in _goal_packets(bus):
        if set(goals) >= {SO101_IDS[j] for j in ARM_JOINTS}:
            q = [arm.calibration[j].to_radians(goals[SO101_IDS[j]]) for j in ARM_JOINTS]
            lowest = float(np.min(so101_chain().frame_origins(np.array(q))[2:, 2]))
            assert lowest >= floor - 1e-3 or math.isclose(lowest, floor, abs_tol=1e-3), (q, lowest)
