"""Teaching the SO-101 by hand in the page (kernel-free), against the simulated arm: a scripted hand
teaches a whole episode, the arrow follows it, guidance and the reproduction on the arm follow; a
fault mid-teach is said in words and loses nothing; a simulated leader arm is the hand-held input."""

from __future__ import annotations

import sys
import threading
import time

import numpy as np
import pytest

from mt_widgets.apps.so101_study import SO101EpisodePage, SO101StudyApp, SO101Teaching, open_so101
from mt_widgets.hardware.feetech import SO101, SO101_IDS
from mt_widgets.hardware.feetech.sim_bus import SIMULATED_CALIBRATION, calibrated_bus
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


def wait_until(predicate, teaching, timeout=30.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out; the arm's message: {teaching.panel.message.value}")


def released_at(teaching, state) -> bool:
    move = teaching.hand_demonstration
    return move is not None and move.released and np.allclose(move.query_state, state[:5])


@pytest.fixture
def page():
    teaching = open_so101("sim", speed_scale=20.0)
    yield SO101EpisodePage(teaching, "so101-reach", seed=0, guidance=True)
    teaching.close()


@pytest.mark.slow
def test_a_scripted_hand_teaches_a_whole_episode_and_the_arm_reproduces_it(page):
    teaching, episode = page.teaching, page.episode
    hand = teaching.hand_views[0].hand
    length = episode.skill.plant.drawing().action_length
    for k, state in enumerate(episode.query_states):
        wait_until(lambda state=state: released_at(teaching, state), teaching)
        shown = episode.optimal[k]                             # MT's arrow (what guidance shows)
        assert hand.move_tool_by(shown * length)
        wait_until(lambda shown=shown: episode.pending_action is not None
                   and np.linalg.norm(np.subtract(episode.pending_action, shown)) < 0.01, teaching)
        episode.teaching.confirm()
        assert episode.phase == "guidance"                      # MT's optimal arrow beside the person's
        episode.next()
    wait_until(lambda: episode.phase == "finished", teaching)
    assert [r.method for r in episode.records] == ["hand"] * len(episode.query_states)
    teaching.wait(60)
    assert teaching.last_report.complete
    # The arm ended where the reproduction ended, within a servo step.
    end = episode.result.trajectory.states[-1]
    assert hand.joints() == pytest.approx(end, abs=0.005)


@pytest.mark.slow
def test_the_hand_view_follows_the_arm_when_it_moves_by_itself_in_a_reproduction():
    teaching = open_so101("sim", speed_scale=20.0, release_at_each_state=False)
    try:
        page = SO101EpisodePage(teaching, "so101-reach", seed=0)
        teaching.wait(60)
        view, skill = teaching.hand_views[0], page.episode.skill
        at_state = view.hand.tool_point()
        assert np.allclose(view.drawn_tool, at_state, atol=1e-3)   # drawn where the arm went to the query state
        drawn = []
        refresh = view.refresh
        view.refresh = lambda: (refresh(), drawn.append(view.drawn_tool.copy()))
        report = teaching.execute(skill.reproduce(skill.theta)).result(120)
        assert report.complete, report
        # redrawn at every waypoint the arm reached by itself, each time where the arm then was
        assert len(drawn) >= report.waypoints
        end = view.hand.tool_point()
        assert np.linalg.norm(end - at_state) > 0.02 and np.allclose(drawn[-1], end, atol=1e-3)
        assert np.linalg.norm(end - np.array(skill.target.point)) < 0.01
    finally:
        teaching.close()


@pytest.mark.slow
def test_a_query_state_the_arms_envelope_refuses_is_said_and_drawn_instead():
    # An arm calibrated with a wrist that bends only about 0.5 rad either way: the skill's query states
    # (about 1 rad) are beyond its envelope. The page says so, the hand is not offered, a drawn arrow goes on.
    calibration = {**SIMULATED_CALIBRATION,
                   "wrist_flex": {**SIMULATED_CALIBRATION["wrist_flex"], "range_min": 1700, "range_max": 2400}}
    bus = calibrated_bus(speed_scale=20.0, calibration=calibration)
    with SimulatedArmPort(bus) as server:
        teaching = SO101Teaching(SO101(server.path, calibration, timeout=0.25), port_text="narrow arm")
        try:
            episode = SO101EpisodePage(teaching, "so101-reach", seed=0).episode
            first = np.asarray(episode.query_states[0])
            assert first[3] > teaching.arm.envelope.ranges["wrist_flex"][1]
            teaching.wait(60)
            message = teaching.panel.message.value
            assert "cannot go to this situation" in message and "wrist_flex" in message and "Draw" in message
            assert teaching.state_refused(first) and teaching.hand_demonstration is None
            assert teaching.teach_by_hand() is None                 # not offered by hand, said again in words
            assert "cannot be shown by hand" in teaching.panel.message.value
            episode.demonstrate(episode.skill.theta @ episode.features[0])
            episode.next()
            assert episode.state_index == 1 and len(episode.records) == 1
        finally:
            teaching.close()


@pytest.mark.slow
def test_a_servo_lost_mid_teach_is_said_in_words_and_the_arrow_and_demonstrations_stay(page):
    teaching, episode = page.teaching, page.episode
    hand_view = teaching.hand_views[0]
    first = episode.query_states[0]
    wait_until(lambda: released_at(teaching, first), teaching)
    episode.demonstrate([0.0, 0.0, 0.01])                       # one confirmed (drawn) demonstration
    episode.next()
    wait_until(lambda: released_at(teaching, episode.query_states[1]), teaching)
    hand_view.hand.move_tool_by([0.01, 0.0, 0.0])
    wait_until(lambda: episode.pending_action is not None and episode.pending_action[0] > 0.015, teaching)
    shown = list(episode.pending_action)
    hand_view.loosen_cable()                                    # the elbow's servo stops answering
    wait_until(lambda: "stopped answering" in teaching.panel.message.value, teaching)
    message = teaching.panel.message.value
    assert "elbow_flex" in message and "cable" in message and "saved" in message
    assert "Traceback" not in message
    assert len(episode.records) == 1 and episode.pending_action == shown
    episode.teaching.confirm()                                  # the arrow shown by hand is still taken
    assert len(episode.records) == 2


@pytest.mark.slow
def test_a_simulated_leader_arm_is_the_hand_held_input():
    teaching = open_so101("sim", leader_port="sim", speed_scale=20.0)
    try:
        page = SO101EpisodePage(teaching, "so101-reach", seed=0, guidance=False)
        assert [title for title in (v.children[0].value for v in teaching.hand_views)][0].count("leader") == 1
        leader_hand = teaching.hand_views[0].hand
        wait_until(lambda: released_at(teaching, page.episode.query_states[0]), teaching)
        start = leader_hand.joints()
        turned = start + np.array([0.1, -0.05, 0.08, 0.0, 0.0])    # the leader's joints turned by hand
        assert leader_hand.move_joints(turned)
        state = page.episode.query_states[0]
        chain = teaching.arm.kinematics
        expected = (chain.tool_point(state + turned - start) - chain.tool_point(state)) / 0.5   # 0.5 m per m/s
        wait_until(lambda: page.episode.pending_action is not None
                   and np.linalg.norm(np.subtract(page.episode.pending_action, expected)) < 0.005, teaching)
        servos = teaching.simulated_ports[0].bus.servos
        assert all(servos[SO101_IDS[j]].torque for j in ("shoulder_pan", "elbow_flex"))  # the arm held on
    finally:
        teaching.close()


def test_bad_input_is_refused_with_its_name():
    with pytest.raises(ValueError, match="port: expected a serial port"):
        open_so101("")
    with pytest.raises(ValueError, match="leader_port"):
        open_so101("/dev/ttyACM0", leader_port="/dev/ttyACM0")


@pytest.mark.slow
def test_the_study_app_runs_the_so101_protocol_by_hand(tmp_path):
    app = SO101StudyApp(log_folder=tmp_path / "study", teaching=open_so101("sim", speed_scale=20.0))
    try:
        assert app.arm_teaching.panel in app.participant_view.children
        assert "simulated SO-101" in app.arm_status.value
    finally:
        app.arm_teaching.close()


def test_closing_while_the_arm_drives_to_a_state_ends_the_hand_loop():
    # Closed right after the page is built, the worker is still driving the arm to the first query state;
    # it then started the hand loop with the stop cleared, and close() waited for a hand that never came.
    teaching = open_so101("sim", speed_scale=20.0)
    SO101EpisodePage(teaching, "so101-reach", seed=0)
    closer = threading.Thread(target=teaching.close, daemon=True)
    closer.start()
    closer.join(20.0)
    assert not closer.is_alive(), "close() is still waiting for the hand loop"
