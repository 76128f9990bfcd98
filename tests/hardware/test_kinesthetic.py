"""Teaching by hand on the simulated arm: release, measured displacement, step limit, re-attach,
back to a known pose, and the faults (a stepper holding, a pulled cable), for both firmwares."""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from mt_widgets.hardware import SwiftPro, SwiftProDisconnected
from mt_widgets.hardware.bridge import UArmBridge
from mt_widgets.hardware.kinesthetic import HandMove, limit_step
from mt_widgets.hardware.simdevice import SimulatedSwiftPro

from .helpers import device_of, sim_url, wait_until

STATE = np.array([20.0, 5.0])  # cm: (200, 50) mm
MOVE = re.compile(r"^#\d+ (G0|G1)\s+(.*)$")


@pytest.fixture(params=[4, 3], ids=["4.x", "3.x"])
def arm(request):
    with SwiftPro(sim_url(firmware=request.param), timeout=1.0) as connected:
        yield connected


def hand_to(arm: SwiftPro, dx_mm: float, dy_mm: float, duration: float = 0.05) -> None:
    dev = device_of(arm)
    now = time.monotonic()
    x, y, z = dev.position_at(now)
    assert dev.hand_move((x + dx_mm, y + dy_mm, z), now, duration)


def poll_until(move: HandMove, expected_cm, timeout: float = 5.0) -> np.ndarray:
    deadline = time.monotonic() + timeout
    action = move.poll(0.05)
    while not np.allclose(action, expected_cm, atol=0.01):
        assert time.monotonic() < deadline, f"action {action} never reached {expected_cm}"
        action = move.poll(0.05)
    return action


def moves_sent(arm: SwiftPro) -> list[tuple[float, float, float]]:
    out = []
    for line in device_of(arm).received_lines:
        m = MOVE.match(line)
        if m:
            p = dict((tok[0], float(tok[1:])) for tok in m.group(2).split())
            out.append((p["X"], p["Y"], p["Z"]))
    return out


def test_the_demonstrated_action_is_the_measured_displacement_and_the_arm_comes_back(arm):
    bridge = UArmBridge(arm)
    move = HandMove(bridge, STATE)
    move.begin()
    dev = device_of(arm)
    assert move.released and dev.steppers_released()
    assert np.allclose(move.start_mm[:2], STATE * 10, atol=0.3)
    hand_to(arm, 30.0, -20.0)
    action = poll_until(move, [3.0, -2.0])
    assert move.reports >= 1
    assert action == pytest.approx([3.0, -2.0], abs=0.01)
    move.end()
    assert not move.released and not dev.steppers_released()
    assert np.allclose(arm.position()[:2], STATE * 10, atol=0.3)  # back at the known pose
    assert np.allclose(dev.position_at(time.monotonic())[:2], STATE * 10, atol=0.3)  # and really there
    for point in moves_sent(arm):
        assert bridge.envelope.contains(*point), point


def test_the_action_is_limited_to_the_step_limit(arm):
    move = HandMove(UArmBridge(arm), STATE)
    move.begin()
    hand_to(arm, 60.0, 80.0)  # 10 cm
    deadline = time.monotonic() + 5
    while not np.allclose(move.displacement_cm, [6.0, 8.0], atol=0.01):
        assert time.monotonic() < deadline
        move.poll(0.05)
    assert move.action_cm == pytest.approx([3.0, 4.0], abs=1e-6)  # 5 cm, same direction
    move.end()


def test_a_hand_that_left_the_envelope_is_brought_back_with_only_safe_moves(arm):
    bridge = UArmBridge(arm)
    move = HandMove(bridge, STATE)
    move.begin()
    hand_to(arm, 120.0, 0.0)  # radius about 326 mm: outside the envelope (135..310 mm)
    deadline = time.monotonic() + 5
    while move.displacement_cm[0] < 11.9:
        assert time.monotonic() < deadline
        move.poll(0.05)
    assert not bridge.envelope.contains(*move.latest_mm)
    move.end()
    assert np.allclose(arm.position()[:2], STATE * 10, atol=0.3)
    for point in moves_sent(arm):
        assert bridge.envelope.contains(*point), point


def test_a_powered_arm_does_not_give_way_to_the_hand(arm):
    dev = device_of(arm)
    now = time.monotonic()
    before = dev.position_at(now)
    assert not dev.hand_move((before[0] + 30, before[1], before[2]), now, 0.01)
    assert dev.hand_refusals == 1 and dev.position_at(time.monotonic()) == pytest.approx(before)


def test_a_pulled_cable_during_a_hand_move_leaves_the_arm_released_and_is_reported(arm):
    move = HandMove(UArmBridge(arm), STATE)
    move.begin()
    dev = device_of(arm)
    hand_to(arm, 10.0, 0.0, duration=1.0)
    move.poll(0.05)
    dev.pull_cable()
    with pytest.raises(SwiftProDisconnected):
        wait_until(lambda: not arm.connected, what="the link noticing the pulled cable")
        move.poll(0.05)
    assert dev.steppers_released()  # limp: it cannot move by itself
    assert not dev.moving_at(time.monotonic())
    assert dev.hand_is_moving(time.monotonic()) or dev.position_at(time.monotonic())[0] > 200.0


def test_3x_must_re_read_its_position_after_a_hand_move():
    # Without update_current_pos, 3.x plans from where it believes the arm is: it lands off.
    dev = SimulatedSwiftPro(firmware=3, boot_delay=0.0, motion_scale=0.01)
    dev.power_on(0.0)
    dev.write(b"#1 M2019\n", 0.0)
    assert dev.hand_move((230.0, 0.0, 100.0), 0.0, 0.0)
    dev.write(b"#2 M17\n#3 G0 X200 Y30 Z100 F6000\n", 0.1)
    landed = dev.position_at(5.0)
    assert abs(landed[0] - 200.0) > 10.0
    dev.write(b"#4 M2019\n", 5.0)
    dev.hand_move((230.0, 0.0, 100.0), 5.0, 0.0)
    dev.write(b"#5 M17\n#6 M2000\n#7 G0 X200 Y30 Z100 F6000\n", 5.1)
    assert dev.position_at(10.0) == pytest.approx((200.0, 30.0, 100.0))


def test_limit_step_keeps_short_actions_and_the_direction():
    assert limit_step([1.0, 2.0], 5.0) == pytest.approx([1.0, 2.0])
    assert limit_step([0.0, -10.0], 5.0) == pytest.approx([0.0, -5.0])


def test_bad_arguments_are_named():
    with pytest.raises(TypeError, match="bridge"):
        HandMove(object(), STATE)
    dev = SimulatedSwiftPro()
    with pytest.raises(ValueError, match="duration"):
        dev.hand_move((200, 0, 100), 0.0, -1)
    with pytest.raises(ValueError, match="target"):
        dev.hand_move((200, float("nan"), 100), 0.0, 1)
