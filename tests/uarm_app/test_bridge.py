"""The bridge between the teaching plant (cm) and the arm (mm), against the simulated arm."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
import pytest

from mt_widgets.core import SKILLS, Trajectory
from mt_widgets.hardware import TEACHING_HEIGHT_MM, SwiftPro, SwiftProDisconnected, SwiftProStopped, UnsafeMoveError
from mt_widgets.hardware.bridge import (
    MM_PER_CM,
    UArmBridge,
    arm_to_plant_cm,
    connect_arm,
    describe_error,
    is_simulated,
    plant_to_arm_mm,
    polar_waypoints,
)

from .helpers import InThread, arm_is_moving, device_of, is_move, is_stop, moves, received, sim_url, wait_until


# ----------------------------------------------------------------------------- mapping
def test_plant_centimetres_are_arm_millimetres_on_the_same_axes():
    assert MM_PER_CM == 10.0
    np.testing.assert_allclose(plant_to_arm_mm([23.0, 11.0]), [230.0, 110.0])
    np.testing.assert_allclose(plant_to_arm_mm([[14.0, -3.5], [30.0, 0.0]]), [[140.0, -35.0], [300.0, 0.0]])
    np.testing.assert_allclose(arm_to_plant_cm([230.0, 110.0, 80.0]), [23.0, 11.0])
    points = np.random.default_rng(0).uniform(-30, 30, size=(50, 2))
    np.testing.assert_allclose(arm_to_plant_cm(plant_to_arm_mm(points)), points)


def test_mapping_rejects_points_of_the_wrong_shape_naming_the_argument():
    with pytest.raises(ValueError, match=r"points_cm: .*shape \(\.\.\., 2\).*\(3,\)"):
        plant_to_arm_mm([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="points_mm"):
        arm_to_plant_cm([1.0])


def test_a_query_state_goes_to_the_arm_at_the_teaching_height(bridge, arm):
    assert bridge.state_to_arm_mm([20.0, -5.0]) == (200.0, -50.0, TEACHING_HEIGHT_MM)
    bridge.show_state([20.0, -5.0])
    x, y, z = arm.position()
    assert (x, y, z) == pytest.approx((200.0, -50.0, TEACHING_HEIGHT_MM), abs=0.01)
    np.testing.assert_allclose(bridge.position_cm(), [20.0, -5.0], atol=1e-3)
    with pytest.raises(ValueError, match="state_cm"):
        bridge.show_state([20.0, math.nan])


def test_every_query_state_of_both_skills_is_shown_on_the_arm(bridge, arm):
    for key in ("uarm-point", "uarm-line"):
        for state in SKILLS[key].query_states(seed=3):
            bridge.show_state(state)
            np.testing.assert_allclose(arm_to_plant_cm(arm.position()), state, atol=1e-3)


def test_moves_across_the_sector_go_round_the_base_not_through_it(bridge, arm):
    # (15, -25.98) and (15, 25.98) cm are at yaw -60 and +60: the straight chord passes 75 mm
    # from the base axis, inside the envelope's hole; the polar path stays out of it.
    a = 30.0 * np.array([math.cos(math.radians(-60)), math.sin(math.radians(-60))])
    b = a * [1, -1]
    bridge.show_state(a)
    before = len(received(arm))
    bridge.show_state(b)
    sent = moves(received(arm)[before:])
    assert len(sent) >= 5
    path = [plant_to_arm_mm(a)] + [np.array([m["X"], m["Y"]]) for m in sent]
    for p, q in zip(path, path[1:]):
        assert np.linalg.norm(q - p) <= bridge.waypoint_mm + 1e-6
        assert math.hypot(*q) >= arm.envelope.min_radius_mm
    np.testing.assert_allclose(path[-1], plant_to_arm_mm(b), atol=1e-3)


def test_polar_waypoints_keep_segments_short_and_end_exactly():
    points = polar_waypoints((150.0, -100.0, 100.0), (150.0, 100.0, 80.0), 25.0)
    previous = np.array([150.0, -100.0, 100.0])
    for point in points:
        assert np.linalg.norm(point - previous) <= 25.0
        previous = point
    np.testing.assert_allclose(points[-1], (150.0, 100.0, 80.0))
    with pytest.raises(ValueError, match="max_segment_mm"):
        polar_waypoints((150, 0, 80), (200, 0, 80), 0)


# ----------------------------------------------------------------------------- reproduction
@pytest.mark.parametrize("key", ["uarm-point", "uarm-line"])
def test_a_reproduction_is_executed_step_by_step_within_the_limits(bridge, arm, key):
    skill = SKILLS[key]
    theta_hat = skill.theta + np.array([[0.05, 0.0, -1.0], [0.0, 0.03, 0.8]])  # a learnt, imperfect skill
    trajectory = skill.reproduce(theta_hat)
    reached = []
    before = len(received(arm))
    report = bridge.execute(trajectory, on_step=lambda k, xy: reached.append((k, xy)))
    assert report.completed, report
    assert report.steps_done == report.steps_planned == len(trajectory.positions) - 1
    lines = received(arm)[before:]
    sent = moves(lines)
    # Every move is a connector move_to: asked first (M2222 for the same target), at the teaching height.
    for line_index, line in enumerate(lines):
        if is_move(line):
            assert lines[line_index - 1].split()[1] == "M2222"
    envelope = arm.envelope
    assert all(envelope.contains(m["X"], m["Y"], m["Z"]) and m["Z"] == TEACHING_HEIGHT_MM for m in sent)
    assert all(0 < m["F"] <= envelope.max_speed_mm_s for m in sent)
    # After the approach, one move per plant step: at most 50 mm, sent at step / 0.5 s.
    targets = plant_to_arm_mm(trajectory.positions)
    step_moves = sent[-report.steps_planned:] if all(
        np.linalg.norm(np.diff(targets, axis=0), axis=1) >= bridge.min_move_mm) else None
    if step_moves is not None:
        for k, move in enumerate(step_moves, start=1):
            np.testing.assert_allclose([move["X"], move["Y"]], targets[k], atol=1e-3)
            step = np.linalg.norm(targets[k] - targets[k - 1])
            assert step <= 50.0 + 1e-6
            assert move["F"] == pytest.approx(min(max(step / 0.5, 1.0), 100.0), abs=1e-3)
    np.testing.assert_allclose(arm_to_plant_cm(arm.position()), trajectory.final_position, atol=0.06)
    assert [k for k, _ in reached] == list(range(len(trajectory.positions)))


def test_tiny_steps_of_a_converged_skill_are_not_sent(bridge, arm):
    trajectory = SKILLS["uarm-point"].reproduce(SKILLS["uarm-point"].theta, duration=30.0)
    steps = np.linalg.norm(np.diff(plant_to_arm_mm(trajectory.positions), axis=0), axis=1)
    assert (steps < bridge.min_move_mm).sum() > 10  # the skill converges: late steps are tiny
    before = len(received(arm))
    bridge.show_state(trajectory.positions[0])
    after_approach = len(received(arm))
    report = bridge.execute(trajectory)
    assert report.completed
    targets, here, expected = plant_to_arm_mm(trajectory.positions), plant_to_arm_mm(trajectory.positions[0]), 0
    for target in targets[1:]:
        if np.linalg.norm(target - here) >= bridge.min_move_mm:
            expected, here = expected + 1, target
    assert expected < len(steps)
    # Already at the start: no approach move; then only the steps that go somewhere.
    assert len(moves(received(arm)[after_approach:])) == expected
    assert before < after_approach
    np.testing.assert_allclose(arm_to_plant_cm(arm.position()), trajectory.final_position, atol=bridge.min_move_mm / 10)


def test_a_step_longer_than_the_plants_limit_is_refused_and_nothing_more_is_sent(bridge, arm):
    positions = np.array([[20.0, 0.0], [21.0, 0.0], [29.0, 0.0], [29.5, 0.0]])  # an 80 mm jump
    zeros = np.zeros_like(positions)
    trajectory = Trajectory(np.arange(4) * 0.5, positions, positions, zeros, zeros, False, None, "cm")
    report = bridge.execute(trajectory)
    assert report.error is not None and "max_step_mm" in report.error and report.steps_done == 1
    assert all(m["X"] < 285.0 for m in moves(received(arm)))
    with pytest.raises(ValueError, match="units 'cm'"):
        bridge.execute(SKILLS["sim-point"].reproduce(SKILLS["sim-point"].theta, duration=0.1))


def test_stop_halts_the_reproduction_and_no_move_is_sent_after_it():
    with SwiftPro(sim_url(motion_scale=1), timeout=1.0) as arm:  # real-time moves: 0.5 s a step
        bridge = UArmBridge(arm)
        skill = SKILLS["uarm-point"]
        trajectory = skill.reproduce(skill.theta)
        bridge.show_state(trajectory.positions[0])
        reports, steps = [], []
        worker = threading.Thread(target=lambda: reports.append(bridge.execute(trajectory, on_step=lambda k, xy:
                                                                                steps.append(k))))
        worker.start()
        wait_until(lambda: steps and steps[-1] >= 2 and arm_is_moving(arm), what="step 3 under way")
        assert bridge.stop() is None
        worker.join(timeout=5.0)  # a guard against a hang; the stop itself is immediate
        assert not worker.is_alive()
        report = reports[0]
        assert report.stopped and report.error is None and 2 <= report.steps_done < report.steps_planned
        lines = received(arm)
        last_stop = max(i for i, line in enumerate(lines) if is_stop(line))
        assert not any(is_move(line) for line in lines[last_stop + 1:])
        now = time.monotonic()   # the simulated arm's clock, asked ahead instead of waited for
        held = device_of(arm).position_at(now)
        assert device_of(arm).position_at(now + 0.6) == pytest.approx(held)
        # Stopped means stopped: the arm is short of where the skill would have taken it.
        assert np.linalg.norm(np.array(held[:2]) - plant_to_arm_mm(trajectory.final_position)) > 20.0
        # Stop is sticky: nothing moves until someone resumes.
        before = len(received(arm))
        again = bridge.execute(skill.reproduce(skill.theta, duration=1.0))
        assert again.stopped and again.steps_done == 0 and not any(is_move(x) for x in received(arm)[before:])
        bridge.resume()
        here_cm = arm_to_plant_cm(np.array(held))
        positions = np.array([here_cm, here_cm + [1.0, 0.0]])  # one 1 cm step, 0.5 s
        short = Trajectory(np.array([0.0, 0.5]), positions, positions, 0 * positions, 0 * positions, False, None, "cm")
        assert bridge.execute(short).completed
        np.testing.assert_allclose(arm_to_plant_cm(arm.position()), positions[-1], atol=1e-3)


def test_after_stop_no_query_state_is_shown_until_resume(bridge, arm):
    bridge.stop()
    before = len(received(arm))
    with pytest.raises(SwiftProStopped):
        bridge.show_state([21.0, 0.0])
    assert not any(is_move(line) for line in received(arm)[before:])
    bridge.resume()
    bridge.show_state([21.0, 0.0])
    assert arm.position()[:2] == pytest.approx((210.0, 0.0), abs=0.01)


def test_a_disconnection_mid_reproduction_gives_a_message_not_a_crash(bridge, arm):
    skill = SKILLS["uarm-point"]
    trajectory = skill.reproduce(skill.theta)
    bridge.show_state(trajectory.positions[0])
    device_of(arm).disconnect_on_command(7)  # a few steps in
    report = bridge.execute(trajectory)
    assert not report.completed and not report.stopped
    assert 1 <= report.steps_done < report.steps_planned
    assert "disconnected" in report.error and "nothing is lost" in report.error
    assert "SwiftProDisconnected" in report.error
    # Stop on a dead link reports, it does not raise.
    assert "disconnected" in bridge.stop()


def test_an_arm_that_stops_answering_gives_a_message_not_a_crash():
    with SwiftPro(sim_url(), timeout=0.3) as arm:
        bridge = UArmBridge(arm)
        skill = SKILLS["uarm-line"]
        trajectory = skill.reproduce(skill.theta)
        bridge.show_state(trajectory.positions[0])
        device_of(arm).drop_next_reply(50)
        report = bridge.execute(trajectory)
        assert report.error is not None and "stopped answering" in report.error
        assert report.steps_done < report.steps_planned


def test_connect_arm_falls_back_on_the_simulated_arm_when_none_is_plugged(monkeypatch):
    monkeypatch.setattr(SwiftPro, "find_ports", staticmethod(lambda: []))
    arm = connect_arm(None, simulator_url=sim_url(), timeout=1.0)
    try:
        assert arm.connected and is_simulated(arm)
    finally:
        arm.close()
    arm = connect_arm(sim_url(), timeout=1.0)
    try:
        assert arm.port_used == sim_url()
    finally:
        arm.close()


def test_error_messages_name_the_problem_and_say_nothing_is_lost():
    text = describe_error(SwiftProDisconnected("port 'x' failed"))
    assert text.startswith("The robot arm is disconnected") and "nothing is lost" in text and "port 'x'" in text


def test_the_bridge_checks_its_arguments(arm):
    with pytest.raises(ValueError, match="arm: expected a connected SwiftPro"):
        UArmBridge("uarm-sim://")
    with pytest.raises(ValueError, match="step_period_s"):
        UArmBridge(arm, step_period_s=0)
    with pytest.raises(ValueError, match="waypoint_mm"):
        UArmBridge(arm, waypoint_mm=500.0)


# ----------------------------------------------------------------------------- stop always wins
class _StopRightAfterTheCheck(threading.Event):
    """The stop switch's held flag, which presses Stop right after a job read it as clear: the
    window between a job's check and its move being sent."""

    def __init__(self, bridge):
        super().__init__()
        self.bridge, self.armed = bridge, False

    def is_set(self):
        answer = super().is_set()
        if self.armed and not answer:
            self.armed = False
            assert self.bridge.stop() is None
        return answer


def test_a_stop_right_after_a_job_checked_the_flag_still_keeps_its_move_from_being_sent(bridge, arm):
    flag = _StopRightAfterTheCheck(bridge)
    arm.stop_switch._held = flag
    flag.armed = True
    with pytest.raises(SwiftProStopped):
        bridge.show_state([25.0, 5.0])
    lines = received(arm)
    last_stop = max(i for i, line in enumerate(lines) if is_stop(line))
    assert not any(is_move(line) for line in lines[last_stop + 1:])
    assert sum(is_stop(line) for line in lines) == 1  # one stop command is enough
    assert arm.position()[:2] == pytest.approx((200.0, 0.0))


def test_resume_on_firmware_4_2_moves_the_arm_again_and_the_cut_move_never_comes_back():
    # Before 4.5 stop pauses (S1000 V0); resume must un-pause and finish the cut move first.
    with SwiftPro(sim_url(version="4.2", motion_scale=1), timeout=1.0) as arm:
        bridge = UArmBridge(arm)
        worker = InThread(bridge.show_state, [29.0, 0.0])  # 90 mm at 60 mm/s
        wait_until(lambda: arm_is_moving(arm), what="the move to start")
        assert bridge.stop() is None
        assert isinstance(worker.raised(timeout=5.0), SwiftProStopped)
        assert bridge.stop_requested
        bridge.resume()
        assert not bridge.stop_requested
        bridge.show_state([21.0, 2.0])  # the arm answers: not left paused
        wait_until(lambda: not arm_is_moving(arm), what="the move to end")
        assert arm.position() == pytest.approx((210.0, 20.0, TEACHING_HEIGHT_MM), abs=0.01)
        assert not arm_is_moving(arm) and not arm.paused


def test_a_stop_while_resuming_wins():
    with SwiftPro(sim_url(version="4.2", motion_scale=1), timeout=1.0) as arm:
        bridge = UArmBridge(arm)
        worker = InThread(bridge.show_state, [29.0, 0.0])
        wait_until(lambda: arm_is_moving(arm), what="the move to start")
        bridge.stop()
        assert isinstance(worker.raised(timeout=5.0), SwiftProStopped)
        errors = []

        def resume():
            try:
                bridge.resume()
            except SwiftProStopped as exc:
                errors.append(exc)

        resumer = threading.Thread(target=resume)
        resumer.start()
        wait_until(lambda: arm_is_moving(arm), what="the cut move to carry on")
        bridge.stop()
        resumer.join(timeout=5.0)
        assert errors and bridge.stop_requested and arm.paused
        held = arm.position()
        assert device_of(arm).position_at(time.monotonic() + 0.3) == pytest.approx(held)   # and 0.3 s later
        with pytest.raises(SwiftProStopped):
            bridge.show_state([21.0, 0.0])


def test_an_arm_outside_the_envelope_is_brought_in_once_by_home(tmp_path):
    with SwiftPro(sim_url(start="120,0,150"), timeout=1.0) as arm:
        bridge = UArmBridge(arm)
        with pytest.raises(UnsafeMoveError, match="home"):
            bridge.show_state([20.0, 0.0])
        assert bridge.home_if_outside() is True
        assert arm.envelope.contains(*arm.position())
        assert all(m["F"] <= arm.envelope.entry_speed_mm_s for m in moves(received(arm)))
        assert bridge.home_if_outside() is False
        bridge.show_state([25.0, 0.0])
        assert arm.position()[:2] == pytest.approx((250.0, 0.0), abs=0.01)
