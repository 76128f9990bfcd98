"""The one stop mechanism: the switch itself, and the connector and the bridge sharing it."""

from __future__ import annotations

import threading

import pytest

from mt_widgets.hardware import StopSwitch, SwiftPro, SwiftProStopped
from mt_widgets.hardware.bridge import UArmBridge

from .helpers import sent_lines, sim_url


def test_a_press_counts_holds_and_runs_its_action_under_the_lock():
    switch = StopSwitch()
    assert (switch.generation, switch.held) == (0, False)
    assert switch.press(lambda: "cut") == "cut"
    assert (switch.generation, switch.held) == (1, True)
    switch.release(1)
    assert (switch.generation, switch.held) == (1, False)


def test_a_release_that_saw_a_press_since_it_began_fails_and_the_switch_stays_held():
    switch = StopSwitch()
    seen = switch.generation
    switch.press()
    undone = []
    with pytest.raises(SwiftProStopped):
        switch.release(seen, while_locked=lambda: undone.append(True))
    assert switch.held and undone == []


def test_nothing_is_sent_under_a_generation_a_press_has_ended():
    switch = StopSwitch()
    generation = switch.generation
    with switch.unless_pressed_since(generation, "'G1'"):
        pass
    switch.press()
    with pytest.raises(SwiftProStopped, match="'G1' was not sent"):
        with switch.unless_pressed_since(generation, "'G1'"):
            raise AssertionError("the body must not run")


def test_a_press_waits_for_a_send_under_way_and_then_counts():
    # The body holds the lock (a line being written): the press comes after it, never inside.
    switch, order = StopSwitch(), []
    inside, go = threading.Event(), threading.Event()

    def send():
        with switch.unless_pressed_since(0, "'G1'"):
            inside.set()
            go.wait(5)
            order.append("sent")

    sender = threading.Thread(target=send)
    sender.start()
    inside.wait(5)
    presser = threading.Thread(target=lambda: order.append(("pressed", switch.press())))
    presser.start()
    presser.join(0.2)  # time enough for a press that did not wait to get in first
    go.set()
    sender.join(5)
    presser.join(5)
    assert order == ["sent", ("pressed", None)] and switch.generation == 1


def test_the_bridge_and_the_arm_share_one_switch():
    with SwiftPro(sim_url(), timeout=1.0) as arm:
        bridge = UArmBridge(arm)
        assert bridge.stop() is None
        assert arm.stop_switch.held and bridge.stop_requested
        arm.resume()  # a resume on the arm ends the bridge's stop too
        assert not bridge.stop_requested
        arm.stop()  # and a stop on the arm stops the bridge's jobs
        before = len(sent_lines(arm))
        with pytest.raises(SwiftProStopped):
            bridge.show_state([21.0, 0.0])
        assert sent_lines(arm)[before:] == []
        bridge.resume()
        bridge.show_state([21.0, 0.0])
        assert arm.position()[:2] == pytest.approx((210.0, 0.0), abs=0.01)
