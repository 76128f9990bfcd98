"""The arm wired to teaching episodes and to the study runner, kernel-free, on the simulated arm."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from blinding_support import participant_texts
from mt_widgets.apps.uarm_study import UArmEpisodePage, UArmStudyApp, UArmTeaching
from mt_widgets.core import Trajectory
from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.bridge import arm_to_plant_cm

from .helpers import ONE_EPISODE, _click, arm_is_moving, device_of, is_move, moves, received, sim_url, wait_until


@pytest.fixture
def teaching():
    arm = SwiftPro(sim_url(), timeout=1.0)
    arm.connect()
    wired = UArmTeaching(arm)
    yield wired
    wired.close()


def test_each_query_state_is_shown_on_the_arm_and_the_reproduction_played_on_it(teaching):
    page = UArmEpisodePage(teaching, "uarm-point", seed=0, guidance=True)
    episode = page.episode
    for state in episode.query_states:
        teaching.wait(5)
        np.testing.assert_allclose(arm_to_plant_cm(teaching.bridge.position_mm()), state, atol=1e-3)
        assert teaching.panel.position_label.value == "arm at x = {:.1f} mm, y = {:.1f} mm".format(*state * 10)
        episode.demonstrate(episode.skill.target_actions(state[None])[0])
        episode.next()
    teaching.wait(10)
    report = teaching.last_report
    assert report.completed
    np.testing.assert_allclose(arm_to_plant_cm(teaching.bridge.position_mm()),
                               episode.result.trajectory.final_position, atol=0.06)
    assert "finished its reproduction" in teaching.panel.message.value
    # Effort cues: one per demonstration, rising, then the episode's end, in the browser and on the buzzer.
    pitches = [f for f, _ in teaching.cues.played]
    assert len(pitches) == 4 and pitches == sorted(pitches)
    assert [f for f, _ in device_of(teaching.bridge.arm).beeps] == pytest.approx(pitches, abs=1e-3)


def test_the_stop_button_halts_the_arm_until_resume(teaching):
    page = UArmEpisodePage(teaching, "uarm-line", seed=1, guidance=False)
    teaching.wait(5)
    teaching.panel.stop_button.click()
    assert teaching.panel.resume_button.layout.display is None
    assert "stopped" in teaching.panel.message.value
    before = len(received(teaching.bridge.arm))
    episode = page.episode
    episode.demonstrate(episode.skill.target_actions(episode.query_states[:1])[0])  # next state: no move
    teaching.wait(5)
    assert not any(is_move(line) for line in received(teaching.bridge.arm)[before:])
    teaching.panel.resume_button.click()
    teaching.wait(5)
    np.testing.assert_allclose(arm_to_plant_cm(teaching.bridge.position_mm()), episode.query_states[1], atol=1e-3)


def test_in_the_study_a_lost_arm_gives_a_message_and_the_demonstrations_are_logged(tmp_path):
    protocol = tmp_path / "one.toml"
    protocol.write_text(ONE_EPISODE)
    arm = SwiftPro(sim_url(), timeout=0.5)
    arm.connect()
    app = UArmStudyApp(protocol=str(protocol), log_folder=tmp_path / "logs", arm=arm)
    try:
        assert "simulated arm" in app.arm_status.value
        app.start_participant("P01", group="control")
        for label in ("Continue", "I agree", "Start", "Start"):
            _click(app, label)
        episode = app.episode
        app.arm_teaching.wait(5)
        for state in episode.query_states[:-1]:
            episode.demonstrate(episode.skill.target_actions(state[None])[0])
        app.arm_teaching.wait(5)
        device_of(arm).disconnect_on_command(1)  # the cable goes as the last arrow is confirmed
        episode.demonstrate(episode.skill.target_actions(episode.query_states[-1:])[0])
        app.arm_teaching.wait(10)
        message = app.arm_teaching.panel.message.value
        assert "disconnected" in message and "nothing is lost" in message
        log_file = next((tmp_path / "logs").rglob("P01*.jsonl"))
        events = [json.loads(line) for line in log_file.read_text().splitlines()]
        assert sum(e["type"] == "demonstration" for e in events) == len(episode.query_states)
        assert any(e["type"] == "episode_finished" for e in events)
        # Single-blind: the arm's texts name no group.
        texts = " ".join(participant_texts(app.participant_view)).lower()
        assert "control" not in texts and "target group" not in texts
    finally:
        app.arm_teaching.close()


def test_an_arm_outside_the_envelope_at_connection_is_brought_in_slowly_first():
    arm = SwiftPro(sim_url(start="120,0,150"), timeout=1.0)
    arm.connect()
    teaching = UArmTeaching(arm)
    try:
        teaching.wait(30)
        assert arm.envelope.contains(*arm.position())
        assert moves(received(arm)) and all(m["F"] <= arm.envelope.entry_speed_mm_s for m in moves(received(arm)))
        page = UArmEpisodePage(teaching, "uarm-point", seed=0)
        teaching.wait(10)
        np.testing.assert_allclose(arm_to_plant_cm(arm.position()), page.episode.query_states[0], atol=1e-3)
    finally:
        teaching.close()


def test_close_stops_the_arm_and_drops_queued_reproductions():
    arm = SwiftPro(sim_url(motion_scale=1), timeout=1.0)  # real-time moves
    arm.connect()
    teaching = UArmTeaching(arm)
    teaching.wait(5)
    out = np.array([[20.0 + k, 0.0] for k in range(10)])  # 9 steps of 1 cm, 0.5 s each
    positions = np.vstack([out, out[::-1][1:]])
    zeros = np.zeros_like(positions)
    reproduction = Trajectory(np.arange(len(positions)) * 0.5, positions, positions, zeros, zeros, False, None, "cm")
    running, queued = teaching.execute(reproduction), teaching.execute(reproduction)
    wait_until(lambda: arm_is_moving(arm), what="the reproduction to start")
    started = time.monotonic()
    teaching.close()
    assert time.monotonic() - started < 5.0  # two 9 s reproductions were queued
    assert running.result(0).stopped and queued.cancelled()
    assert not arm.connected
