"""Teaching by hand in the uArm app, kernel-free, on the simulated arm: a scripted hand moves
the released arm, the measured step is the pending arrow, confirming it records it with the
method "hand" and the arm holds itself again and goes back; a pulled cable mid-move loses no
confirmed demonstration and leaves the arm released; in the study the modality is protocol
data and is logged."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from mt_widgets.apps.uarm_study import UArmEpisodePage, UArmStudyApp, UArmTeaching
from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.bridge import arm_to_plant_cm

from .helpers import ONE_EPISODE, _click, device_of, sim_url, wait_until


@pytest.fixture(params=[4, 3], ids=["4.x", "3.x"])
def teaching(request):
    arm = SwiftPro(sim_url(firmware=request.param), timeout=1.0)
    arm.connect()
    wired = UArmTeaching(arm, demonstration_modality="hand")
    yield wired
    wired.close()


def hand_step(teaching: UArmTeaching, step_cm) -> None:
    """Wait for the arm to let go, then move its tip by ``step_cm`` as a hand would."""
    dev = device_of(teaching.bridge.arm)
    # As a person does: move the arm once the app says it is released (the arm's "ok" to the
    # release has then been read; the device alone is limp a moment earlier).
    wait_until(lambda: dev.steppers_released() and "The arm is released" in teaching.panel.message.value,
               what="the app to say the arm is released")
    now = time.monotonic()
    x, y, z = dev.position_at(now)
    assert dev.hand_move((x + 10 * step_cm[0], y + 10 * step_cm[1], z), now, 0.05)


def wait_pending(episode, expected, timeout=10.0):
    wait_until(lambda: episode.teaching.pending_action is not None
               and np.allclose(episode.teaching.pending_action, expected, atol=0.02), timeout,
               what=f"the arrow to show {expected}")


def test_a_whole_episode_taught_by_hand(teaching):
    page = UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=False)
    episode = page.episode
    dev = device_of(teaching.bridge.arm)
    assert teaching.panel.hand_button.layout.display is None and page.children[-1] is teaching.hand_view
    steps = [np.array([2.0, -1.0]), np.array([-1.5, 1.0]), np.array([9.0, 0.0])]
    for index, step in enumerate(steps):
        teaching.wait(10)
        state = episode.query_states[index]
        np.testing.assert_allclose(arm_to_plant_cm(teaching.bridge.position_mm()), state, atol=1e-2)
        if index == 1:
            teaching._on_key_down("h", False, False, False)  # the H key on the canvas
        else:
            teaching.panel.hand_button.click()
        assert teaching.panel.hand_button.disabled
        hand_step(teaching, step)
        shown = step if np.hypot(*step) <= 5.0 else step * 5.0 / np.hypot(*step)  # the step limit: 5 cm
        wait_pending(episode, shown)
        episode.teaching.confirm()
        assert episode.records[-1].method == "hand"
        np.testing.assert_allclose(episode.records[-1].action, shown, atol=0.02)
    teaching.wait(20)
    assert episode.phase == "finished" and not dev.steppers_released()
    assert teaching.last_report is not None and teaching.last_report.completed
    assert not teaching.panel.hand_button.disabled


def test_nothing_happens_outside_the_teaching_phase_or_twice(teaching):
    page = UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=True)
    teaching.wait(10)
    first = teaching.teach_by_hand()
    assert first is not None and teaching.teach_by_hand() is None  # a double click starts one
    hand_step(teaching, (1.0, 0.0))
    wait_pending(page.episode, (1.0, 0.0))
    page.episode.teaching.confirm()
    first.result(20)
    assert page.episode.phase == "guidance" and teaching.teach_by_hand() is None


def test_a_pulled_cable_during_a_hand_move_keeps_the_confirmed_and_leaves_the_arm_released(teaching):
    page = UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=False)
    episode = page.episode
    dev = device_of(teaching.bridge.arm)
    teaching.wait(10)
    teaching.teach_by_hand()
    hand_step(teaching, (1.0, 1.0))
    wait_pending(episode, (1.0, 1.0))
    episode.teaching.confirm()
    teaching.wait(10)
    job = teaching.teach_by_hand()
    hand_step(teaching, (0.5, 0.0))
    dev.pull_cable()  # mid-move
    job.result(20)
    message = teaching.panel.message.value
    assert "released" in message and "safe" in message and "nothing is lost" in message
    assert dev.steppers_released() and not dev.moving_at(time.monotonic())
    assert len(episode.teaching.demonstrations) == 1
    np.testing.assert_allclose(episode.teaching.demonstrations[0], (1.0, 1.0), atol=0.02)
    assert not teaching.panel.hand_button.disabled
    assert teaching.teach_by_hand() is None and "disconnected" in teaching.panel.message.value


@pytest.mark.parametrize("version", ["4.10", "4.2"])  # 4.2: the stop is a pause
def test_stop_during_a_hand_move_keeps_the_arm_released_until_resume_attaches_and_returns(version):
    arm = SwiftPro(sim_url(version=version), timeout=1.0)
    arm.connect()
    teaching = UArmTeaching(arm, demonstration_modality="hand")
    try:
        page = UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=False)
        dev = device_of(arm)
        teaching.wait(10)
        job = teaching.teach_by_hand()
        hand_step(teaching, (2.0, 0.0))
        teaching.stop()
        job.result(20)
        assert dev.steppers_released() and "stopped and released" in teaching.panel.message.value
        teaching.resume().result(20)
        assert not dev.steppers_released()
        np.testing.assert_allclose(arm_to_plant_cm(arm.position()), page.episode.query_states[0], atol=1e-2)
        assert page.episode.teaching.demonstrations == []  # nothing was confirmed
    finally:
        teaching.close()


def test_a_slow_stop_command_still_ends_on_the_words_that_the_arm_is_released():
    # The hand move's worker sees the stop as soon as the bridge holds it, while the kernel's
    # stop() may still be waiting for the arm's answer: its generic words must not come last.
    arm = SwiftPro(sim_url(), timeout=1.0)
    arm.connect()
    teaching = UArmTeaching(arm, demonstration_modality="hand")
    try:
        UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=False)
        teaching.wait(10)
        job = teaching.teach_by_hand()
        hand_step(teaching, (1.0, 0.0))
        real_stop = teaching.bridge.stop

        def slow_stop():
            message = real_stop()
            time.sleep(0.5)  # a slow link: five of the worker's 0.1 s polls
            return message

        teaching.bridge.stop = slow_stop
        teaching.stop()
        job.result(20)
        assert "stopped and released" in teaching.panel.message.value
    finally:
        teaching.close()


def test_drawn_modality_hides_teaching_by_hand():
    arm = SwiftPro(sim_url(), timeout=1.0)
    arm.connect()
    teaching = UArmTeaching(arm)
    try:
        UArmEpisodePage(teaching, "uarm-point", seed=0)
        assert teaching.panel.hand_button.layout.display == "none"
        assert teaching.hand_view.layout.display == "none"
        assert teaching.teach_by_hand() is None
        with pytest.raises(ValueError, match="demonstration_modality"):
            UArmTeaching(arm, demonstration_modality="voice")
        with pytest.raises(TypeError, match="demonstration_modality"):
            UArmTeaching(arm, demonstration_modality=1)
    finally:
        teaching.close()


def test_in_the_study_the_modality_is_protocol_data_and_logged(tmp_path):
    protocol = tmp_path / "hand.toml"
    protocol.write_text('demonstration_modality = "hand"\n' + ONE_EPISODE)
    arm = SwiftPro(sim_url(), timeout=1.0)
    arm.connect()
    app = UArmStudyApp(protocol=str(protocol), log_folder=tmp_path / "logs", arm=arm)
    try:
        app.start_participant("P01", group="control")
        for label in ("Continue", "I agree", "Start", "Start"):
            _click(app, label)
        teaching = app.arm_teaching
        assert teaching.demonstration_modality == "hand" and teaching.panel.hand_button.layout.display is None
        episode = app.episode
        teaching.wait(10)
        teaching.teach_by_hand()
        hand_step(teaching, (1.5, 0.0))
        wait_pending(episode, (1.5, 0.0))
        episode.teaching.confirm()
        teaching.wait(10)
        episode.demonstrate(episode.skill.target_actions(episode.query_states[1:2])[0])  # drawn (code)
        log_file = next((tmp_path / "logs").rglob("P01*.jsonl"))
        events = [json.loads(line) for line in log_file.read_text().splitlines()]
        demos = [e for e in events if e["type"] == "demonstration"]
        assert [d["modality"] for d in demos] == ["hand", "drawn"]
        assert demos[0]["input"]["method"] == "hand"
        np.testing.assert_allclose(demos[0]["action"], (1.5, 0.0), atol=0.02)
    finally:
        app.arm_teaching.close()


def test_the_simulated_hand_drags_the_tip_only_when_released_and_pulls_the_cable():
    from mt_widgets.apps.uarm_hand import SimulatedHand, arm_to_view
    from mt_widgets.hardware import SimulatedSwiftPro
    dev = SimulatedSwiftPro(boot_delay=0.0)
    dev.power_on(time.monotonic())
    hand = SimulatedHand(dev, floating=False)
    start = dev.position_at(time.monotonic())
    tip = arm_to_view(start[0], start[1])
    hand._down(*tip)
    hand._move(tip[0], tip[1] - 10)  # 20 mm forward
    hand._up(0, 0)
    assert dev.hand_refusals >= 1 and dev.position_at(time.monotonic()) == pytest.approx(start)
    assert "hold" in hand.note.value  # powered: it does not give way
    dev.write(b"#1 M2019\n", time.monotonic())
    hand._down(*tip)
    hand._move(tip[0], tip[1] - 10)
    hand._up(0, 0)
    wait_until(lambda: not dev.hand_is_moving(time.monotonic()), what="the hand move to end")
    assert dev.position_at(time.monotonic())[0] == pytest.approx(start[0] + 20.0, abs=0.01)
    hand._down(tip[0] + 100, tip[1])  # a press away from the tip grabs nothing
    assert not hand.dragging
    hand.pull_cable()
    assert dev.disconnected and hand.cable_button.disabled and "pulled" in hand.note.value
    with pytest.raises(TypeError, match="device"):
        SimulatedHand(object())
    with pytest.raises(TypeError, match="floating"):
        SimulatedHand(dev, floating="yes")
