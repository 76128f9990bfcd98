"""The SO-101 connector against the simulated arm on a pseudo-terminal: discovery, LeRobot's
calibration, moves inside the envelope, torque, the gripper, teaching by hand, faults in words,
the emergency stop."""

from __future__ import annotations

import json
import sys
import threading
import time

import numpy as np
import pytest

from mt_widgets.hardware.errors import UnsafeMoveError
from mt_widgets.hardware.feetech import (
    ARM_JOINTS,
    SO101,
    BusDisconnected,
    CalibrationError,
    CorruptReply,
    ServoFault,
    ServoNotAnswering,
    SimulatedServo,
    SO101Error,
    SO101Stopped,
    WrongServo,
    read_calibration,
)
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort

from .so101_support import CALIBRATION, calibrated_bus, so101_chain

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


@pytest.fixture
def sim():
    bus = calibrated_bus()
    with SimulatedArmPort(bus) as server:
        yield bus, server


@pytest.fixture
def slow_sim():
    """The servos at their real speed: a move of a few tenths of a radian lasts about a second,
    so a fault injected by the test comes while it is under way, however loaded the machine."""
    bus = calibrated_bus(speed_scale=1.0)
    with SimulatedArmPort(bus) as server:
        yield bus, server


@pytest.fixture
def slow_arm(slow_sim):
    _, server = slow_sim
    with SO101(server.path, CALIBRATION, so101_chain(), timeout=0.1) as arm:
        yield arm


@pytest.fixture
def arm(sim):
    bus, server = sim
    # 0.1 s for an answer: the simulated bus is a thread on a loaded test machine (a real arm
    # answers in well under a millisecond).
    with SO101(server.path, CALIBRATION, so101_chain(), timeout=0.1) as arm:
        yield arm


# ---------------------------------------------------------------- discovery and calibration
def test_connect_reads_the_calibration_lerobot_left_in_the_servos(sim):
    bus, server = sim
    with SO101(server.path, kinematics=so101_chain(), timeout=0.1) as arm:
        assert {j: c.__dict__ for j, c in arm.calibration.items()} == CALIBRATION
        # Each servo sits at the middle of its range: LeRobot's degrees give 0.
        assert arm.positions() == pytest.approx(dict.fromkeys(CALIBRATION, 0.0), abs=1e-3)
        # The answers now come at once (LeRobot's configure_motors), the EEPROM unchanged.
        assert all(s.value("return_delay") == 0 and s.eeprom[7] == 250 for s in bus.servos.values())


def test_a_lerobot_calibration_file_is_read_and_written_into_the_servos(sim, tmp_path):
    bus, server = sim
    other = {j: dict(c) for j, c in CALIBRATION.items()}
    other["elbow_flex"].update(range_min=1000, range_max=3000)
    path = tmp_path / "so101_follower" / "my_arm.json"
    path.parent.mkdir()
    path.write_text(json.dumps(other))
    with SO101(server.path, path, so101_chain(), timeout=0.1) as arm:
        assert arm.calibration["elbow_flex"].range_min == 1000
    servo = bus.servos[3]
    with bus.lock:   # the server's thread drives the bus too
        servo.power_on(time.monotonic())    # kept through a power cycle: written with the lock open
    assert (servo.value("min_position_limit"), servo.value("max_position_limit")) == (1000, 3000)
    assert servo.value("lock") == 1


def test_calibration_files_of_another_arm_are_refused(tmp_path):
    koch = {name: {"id": i, "drive_mode": 0, "homing_offset": 0, "range_min": 0, "range_max": 4095}
            for i, name in enumerate(["waist", "shoulder", "elbow", "wrist_flex", "wrist_roll", "gripper"], 1)}
    path = tmp_path / "koch.json"
    path.write_text(json.dumps(koch))
    with pytest.raises(CalibrationError, match="another arm"):
        read_calibration(path)
    swapped = {j: dict(c) for j, c in CALIBRATION.items()}
    swapped["gripper"]["id"] = 7
    with pytest.raises(CalibrationError, match="gripper: expected id 6"):
        SO101("/dev/null-no-such-port", swapped)
    with pytest.raises(CalibrationError, match="no file"):
        read_calibration(tmp_path / "missing.json")


def test_an_uncalibrated_arm_asks_for_a_calibration():
    bus = calibrated_bus(calibration={j: dict(c, homing_offset=0, range_min=0, range_max=4095)
                                      for j, c in CALIBRATION.items()})
    with SimulatedArmPort(bus) as server, SO101(server.path, timeout=0.1) as arm:
        assert arm.read_steps()["elbow_flex"] == 2048   # the middle of the factory range
        with pytest.raises(CalibrationError, match="not calibrated"):
            arm.positions()
        with pytest.raises(CalibrationError, match="not calibrated"):
            arm.move_joints({"elbow_flex": 0.1})


def test_a_wrong_port_a_missing_servo_and_another_model_are_named():
    with pytest.raises(BusDisconnected, match="cannot open the serial port '/dev/no-such-arm'"):
        SO101("/dev/no-such-arm", CALIBRATION)
    bus = calibrated_bus()
    bus.silence(4)
    with SimulatedArmPort(bus) as server, pytest.raises(WrongServo, match=r"wrist_flex \(id 4\) do not answer"):
        SO101(server.path, CALIBRATION, timeout=0.1)
    bus = calibrated_bus()
    bus.servos[2] = SimulatedServo(2, model=1284)
    with SimulatedArmPort(bus) as server, pytest.raises(WrongServo, match=r"shoulder_lift \(id 2\) is model 1284"):
        SO101(server.path, CALIBRATION, timeout=0.1)


def test_calibrate_an_arm_of_its_own_in_lerobots_format(tmp_path):
    bus = calibrated_bus(calibration={j: dict(c, homing_offset=0, range_min=0, range_max=4095)
                                      for j, c in CALIBRATION.items()})
    for servo in bus.servos.values():
        servo.position = 2500.0    # the middle pose, where the person holds the arm
    with SimulatedArmPort(bus) as server:

        def hand():
            # Once the middle pose is taken (the last servo's offset written), move every joint
            # to one end of its range and then to the other, while calibrate() reads.
            deadline = time.monotonic() + 5.0
            while bus.servos[6].value("homing_offset") != 453 and time.monotonic() < deadline:
                time.sleep(0.005)
            now = time.monotonic
            bus.hand_move({1: 1000, 2: 1200, 3: 900, 4: 1500, 6: 2047}, now())
            # Hold it until calibrate() has read the joints twice (SYNC_READs seen on the bus).
            seen = sum(p.code == 0x82 for p in bus.received)
            while sum(p.code == 0x82 for p in bus.received) < seen + 2 and time.monotonic() < deadline:
                time.sleep(0.005)
            bus.hand_move({1: 3000, 2: 2900, 3: 3100, 4: 2600, 6: 3000}, now())

        arm = SO101(server.path, timeout=0.1)   # uncalibrated: it reads steps, not angles
        thread = threading.Thread(target=hand)
        thread.start()
        result = arm.calibrate(tmp_path / "mine.json", seconds=0.5)
        thread.join()
        arm.close()
    assert read_calibration(tmp_path / "mine.json") == result
    offsets = {j: c.homing_offset for j, c in result.items()}
    # raw 2500 is the middle: present = 2500 - offset = 2047.
    assert offsets == dict.fromkeys(CALIBRATION, 2500 - 2047)
    assert (result["shoulder_pan"].range_min, result["shoulder_pan"].range_max) == (1000, 3000)
    assert (result["wrist_roll"].range_min, result["wrist_roll"].range_max) == (0, 4095)
    assert bus.servos[1].eeprom[31] == 2500 - 2047 - 256 and bus.servos[1].value("homing_offset") == 453


# ---------------------------------------------------------------- moves and the envelope
def test_joint_and_task_space_moves_arrive(arm):
    arm.torque(True)
    arm.move_joints({"shoulder_pan": 0.4, "elbow_flex": -0.3}, speed=1.5, acceleration=6.0)
    q = arm.positions()
    assert q["shoulder_pan"] == pytest.approx(0.4, abs=2e-3) and q["elbow_flex"] == pytest.approx(-0.3, abs=2e-3)
    arm.move_to(0.25, -0.05, 0.12, speed=1.5, acceleration=6.0)
    assert arm.tool_point() == pytest.approx((0.25, -0.05, 0.12), abs=3e-3)
    arm.gripper(0.5, speed=1.5)
    assert arm.positions()["gripper"] == pytest.approx(0.5, abs=2e-3)


def test_the_joints_of_a_move_are_sent_together_with_speeds_in_proportion_to_their_travel(sim, arm):
    bus, _ = sim
    arm.torque(True)
    sent = len(bus.received)
    arm.move_joints({"shoulder_pan": 0.6, "shoulder_lift": 0.15}, speed=1.0, acceleration=4.0)
    (packet,) = [p for p in bus.received[sent:] if p.code == 0x83]   # one SYNC_WRITE for the move
    address, size, body = packet.parameters[0], packet.parameters[1], packet.parameters[2:]
    assert (address, size) == (41, 7)
    blocks = {body[k]: body[k + 1:k + 8] for k in range(0, len(body), 8)}
    assert sorted(blocks) == [1, 2, 3, 4, 5]   # the whole arm: the joints not named hold
    acceleration = {i: b[0] for i, b in blocks.items()}
    speed = {i: int.from_bytes(b[5:7], "little") for i, b in blocks.items()}
    # The fastest joint at the speed and acceleration asked (steps/s; 100 steps/s^2 units)...
    assert speed[1] == round(1.0 * 4096 / (2 * np.pi)) and acceleration[1] == round(4.0 * 4096 / (2 * np.pi) / 100)
    # ...the other in proportion to its travel, so both arrive together on the line checked.
    assert speed[2] / speed[1] == pytest.approx(0.25, abs=0.01)
    assert acceleration[2] / acceleration[1] == pytest.approx(0.25, abs=0.05)
    assert arm.positions()["shoulder_lift"] == pytest.approx(0.15, abs=2e-3)


def test_goals_outside_the_envelope_send_nothing(sim, arm):
    bus, _ = sim
    arm.torque(True)
    sent = len(bus.received)
    with pytest.raises(UnsafeMoveError) as error:
        arm.move_joints({"elbow_flex": 2.5})
    assert error.value.coordinate == "elbow_flex"
    with pytest.raises(UnsafeMoveError, match="below the table"):
        arm.move_joints({"shoulder_lift": 1.6, "elbow_flex": 0.2})
    with pytest.raises(UnsafeMoveError, match="below the table"):
        arm.move_to(0.2, 0.0, 0.0)
    with pytest.raises(UnsafeMoveError, match="reach"):
        arm.move_to(0.8, 0.0, 0.2)
    with pytest.raises(UnsafeMoveError, match="speed"):
        arm.move_joints({"shoulder_pan": 0.1}, speed=10.0)
    with pytest.raises(ValueError, match="wait: expected a bool"):
        arm.move_joints({"shoulder_pan": 0.1}, wait=1)
    with pytest.raises(ValueError, match="goal: expected joints"):
        arm.move_joints({"elbow": 0.1})
    goal_writes = [p for p in bus.received[sent:] if p.code == 0x83]
    assert goal_writes == []


def test_a_move_with_the_torque_off_is_refused(sim, arm):
    bus, _ = sim
    sent = len(bus.received)
    with pytest.raises(SO101Error, match="torque is off on shoulder_pan, shoulder_lift"):
        arm.move_joints({"shoulder_pan": 0.1})
    assert not [p for p in bus.received[sent:] if p.code == 0x83]


def test_without_a_model_given_the_arm_moves_on_the_so101s_own_from_the_shipped_urdf(sim):
    _, server = sim
    with SO101(server.path, CALIBRATION, timeout=0.1) as arm:
        arm.torque(True)
        q = arm.positions()
        expected = so101_chain().forward_kinematics([q[j] for j in ARM_JOINTS])
        assert arm.tool_point() == pytest.approx(tuple(expected), abs=1e-12)
        with pytest.raises(UnsafeMoveError, match="below the table"):
            arm.move_to(0.2, 0.0, -0.05)


# ---------------------------------------------------------------- teaching by hand
def test_a_hand_moves_the_arm_with_torque_off_and_every_reading_is_kept(sim, arm):
    bus, _ = sim
    arm.torque(True)
    assert not bus.hand_move({1: 1500}, time.monotonic())
    samples = []

    def hand(t, q):
        if len(samples) == 3:
            bus.hand_move({1: 1500, 3: 2500}, time.monotonic())

    arm.follow_by_hand(0.2, rate=50.0, into=samples, on_sample=hand)
    # One reading a tick of 20 ms at most (a loaded machine may skip ticks: no lower bound here).
    assert 5 <= len(samples) <= 11
    assert np.all(np.diff(np.floor(np.array([t for t, _ in samples]) * 50.0 + 1e-9)) >= 1)
    assert samples[0][1]["shoulder_pan"] == pytest.approx(0.0, abs=2e-3)
    assert samples[-1][1]["shoulder_pan"] == pytest.approx(arm.calibration["shoulder_pan"].to_radians(1500))
    assert np.all(np.diff([t for t, _ in samples]) > 0)


def test_a_pulled_cable_while_teaching_keeps_the_samples(sim, arm):
    bus, _ = sim
    samples = []

    def pull(t, q):
        if len(samples) == 4:
            bus.pull_cable()

    with pytest.raises(BusDisconnected, match="USB cable"):
        arm.follow_by_hand(1.0, into=samples, on_sample=pull)
    assert len(samples) == 4


# ---------------------------------------------------------------- faults and the stop
def move_in_a_thread(arm, goal, speed=1.0):
    """Start ``arm.move_joints(goal)`` (waiting for arrival) in a thread: (thread, [its exception])."""
    raised = []

    def move():
        try:
            arm.move_joints(goal, speed=speed)
        except Exception as error:  # noqa: BLE001 (handed to the test)
            raised.append(error)

    thread = threading.Thread(target=move)
    thread.start()
    time.sleep(0.02)   # the move is under way (it takes about a second)
    return thread, raised


def test_an_overload_mid_move_stops_the_arm_and_says_why(slow_sim, slow_arm):
    bus, _ = slow_sim
    arm = slow_arm
    arm.torque(True)
    thread, raised = move_in_a_thread(arm, {"shoulder_pan": 0.8})
    bus.overload(1, time.monotonic())
    thread.join()
    (error,) = raised
    assert isinstance(error, ServoFault)
    assert "the shoulder_pan servo (id 1) stopped the move: it was blocked" in str(error)
    assert "holds where it is" in str(error) and arm.faults
    arm.positions()   # a round trip: the simulated bus has taken the hold (a SYNC_WRITE has no answer)
    # Every servo was told to hold where it was (the overloaded one has no torque left to move).
    assert all(s.holds[-1] for i, s in bus.servos.items() if i != 1)
    # Nothing moves until the torque is turned on again; then it does.
    with pytest.raises(ServoFault, match="shoulder_pan servo .id 1. cannot move"):
        arm.move_joints({"shoulder_pan": 0.3})
    arm.torque(True)
    here = arm.positions()["shoulder_pan"]
    arm.move_joints({"shoulder_pan": here - 0.05}, speed=1.5, acceleration=6.0)
    assert arm.positions()["shoulder_pan"] == pytest.approx(here - 0.05, abs=2e-3)


def test_a_voltage_drop_stops_the_move(slow_sim, slow_arm):
    bus, _ = slow_sim
    arm = slow_arm
    arm.torque(True)
    thread, raised = move_in_a_thread(arm, {"wrist_flex": 0.6})
    bus.voltage_drop(3.2, time.monotonic())
    thread.join()
    (error,) = raised
    assert isinstance(error, ServoFault) and "stopped the move: its power supply is too low" in str(error)
    with pytest.raises(ServoFault, match=r"shoulder_pan servo \(id 1\) cannot move: its power supply"):
        arm.move_joints({"wrist_flex": 0.3})


def test_a_servo_that_stops_answering_mid_move_is_named(slow_sim, slow_arm):
    bus, _ = slow_sim
    arm = slow_arm
    arm.torque(True)
    arm.move_joints({"elbow_flex": 0.4}, wait=False)
    bus.silence(3)
    with pytest.raises(ServoNotAnswering, match="elbow_flex servo .id 3. stopped answering: check the cable"):
        arm.move_joints({"elbow_flex": 0.4})
    assert "servos that still answer hold" in arm.faults[-1][1]


def test_one_damaged_answer_is_read_again_two_stop_the_arm(sim, arm):
    bus, _ = sim
    bus.corrupt_next_reply()
    assert set(arm.positions()) == set(CALIBRATION)
    bus.corrupt_next_reply(7)
    with pytest.raises(CorruptReply, match="arrive damaged"):
        arm.positions()


def test_the_emergency_stop_holds_the_arm_until_resume(slow_sim, slow_arm):
    bus, _ = slow_sim
    arm = slow_arm
    arm.torque(True)
    arm.move_joints({"shoulder_pan": 1.0}, speed=1.0, acceleration=6.0, wait=False)
    time.sleep(0.02)
    arm.stop()
    arm.positions()   # a round trip: the simulated bus has taken the hold
    servo = bus.servos[1]
    # The stop's goal is where each servo was when it was read: the still ones hold exactly.
    assert len(servo.goals) == 2 and all(s.holds[-1] for i, s in bus.servos.items() if i != 1)
    # It brakes at its acceleration, comes back to the hold and stays there. Braking overshoots the
    # hold, so the shaft passes its step once on the way out: wait for the end of the move (its
    # `moving` register), not the first reading of that step (which a loaded machine may sample).
    deadline = time.monotonic() + 2.0
    while ((bus.present_positions(time.monotonic())[1] != servo.goals[-1] or servo.value("moving"))
           and time.monotonic() < deadline):
        time.sleep(0.01)
    time.sleep(0.05)
    assert bus.present_positions(time.monotonic())[1] == servo.goals[-1]
    assert servo.goals[-1] < arm.calibration["shoulder_pan"].to_steps(1.0) - 50
    with pytest.raises(SO101Stopped):
        arm.move_joints({"shoulder_pan": 0.2})
    arm.resume()
    arm.move_joints({"shoulder_pan": 0.1}, speed=1.5, acceleration=6.0)
    assert arm.positions()["shoulder_pan"] == pytest.approx(0.1, abs=2e-3)
