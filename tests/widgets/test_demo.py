"""The visitors' demo page: choosing a skill, guidance or new states starts a fresh episode."""

import numpy as np
import pytest

from mt_widgets.widgets import DemoPage
from mt_widgets.widgets.demo import DEMO_SKILLS


def finish(episode):
    while episode.phase != "finished":
        if episode.phase == "guidance":
            episode.next()
        else:
            episode.demonstrate(episode.optimal[episode.state_index] + [0.3, -0.2])


def test_the_page_offers_the_four_skills_and_starts_with_the_chosen_one(recorder):
    page = DemoPage(skill="uarm-line", guidance=False, duration=1.0)
    assert [key for _, key in DEMO_SKILLS] == ["sim-point", "sim-line", "uarm-point", "uarm-line"]
    assert page.episode.skill.key == "uarm-line" and page.episode.guidance is False
    with pytest.raises(ValueError, match="skill"):
        DemoPage(skill="sim-circle")


def test_switching_the_skill_or_guidance_replaces_the_episode_and_closes_the_old_one(recorder):
    page = DemoPage(duration=1.0)
    first = page.episode
    first_canvas = first.teaching.view.canvas
    page.skill_chooser.value = "uarm-point"
    assert page.episode is not first and page.episode.skill.key == "uarm-point"
    assert page.episode_slot.children == (page.episode,)
    assert first_canvas.comm is None and first_canvas[0].comm is None          # closed, not leaked
    page.guidance_switch.value = False
    assert page.episode.guidance is False and page.episode.skill.key == "uarm-point"


def test_try_again_gives_new_query_states_of_the_same_skill(recorder):
    page = DemoPage(duration=1.0)
    before = page.episode.query_states
    page.new_states_button.click()
    assert page.episode.skill.key == "sim-point"
    assert page.episode.query_states.shape == before.shape and not np.allclose(page.episode.query_states, before)


def test_the_teaching_error_is_shown_after_the_episode_and_compared_with_earlier_tries(recorder):
    page = DemoPage(duration=1.0)
    assert page.result_line.value == ""
    finish(page.episode)
    first = page.episode.result.theta_error
    assert first > 0.01
    assert f"{first:.3f}" in page.result_line.value and "best before" not in page.result_line.value
    page.new_states_button.click()
    assert page.result_line.value == ""
    finish(page.episode)
    assert f"{page.episode.result.theta_error:.3f}" in page.result_line.value
    assert f"best before on this skill (with guidance): {first:.3f}" in page.result_line.value


def test_switching_guidance_mid_episode_keeps_the_arrows_and_says_so(recorder):
    page = DemoPage(duration=1.0)
    page.episode.demonstrate([1.0, 0.5])
    page.episode.next()
    page.episode.demonstrate([-0.5, 0.25])
    page.episode.next()
    page.episode.teaching.set_action([0.3, 0.3])                 # drawn, not confirmed
    states = page.episode.query_states
    page.guidance_switch.value = False
    episode = page.episode
    assert episode.guidance is False and np.array_equal(episode.query_states, states)
    assert episode.demonstrations == [[1.0, 0.5], [-0.5, 0.25]] and episode.state_index == 2
    assert episode.progress.demonstrations_done == 2
    assert episode.teaching.pending_action == [0.3, 0.3]
    assert "Guidance is now off; your 2 arrows so far are kept" in page.result_line.value
    page.guidance_switch.value = True                           # and back: still kept
    assert page.episode.guidance is True and page.episode.demonstrations == [[1.0, 0.5], [-0.5, 0.25]]
    finish(page.episode)
    assert page.episode.phase == "finished" and len(page.episode.result.demonstrations) == 5
    page.guidance_switch.value = False                          # after the end: a fresh episode
    assert page.episode.demonstrations == [] and page.result_line.value == ""


def test_the_visitor_picks_the_ur5_and_back_and_each_arm_gets_its_own_widget_and_skills():
    from mt_widgets.widgets import EpisodeWidget, SpaceTeachingCanvas, TeachingCanvas
    page = DemoPage(duration=1.0)
    assert page.arm_chooser.layout.display is None and page.arm_chooser.options == (
        "Planar arms", "UR5 arm (3-D)", "Franka Panda (3-D)", "SO-101 (3-D)")
    assert isinstance(page.episode, EpisodeWidget) and page.skill_chooser.value == "sim-point"
    assert isinstance(page.episode.teaching, TeachingCanvas)   # the plant's drawing chose the renderer
    started = []
    original = page.start_episode

    def counted(*args, **kwargs):
        started.append(page.skill_chooser.value)
        return original(*args, **kwargs)
    page.start_episode = counted
    page.arm_chooser.value = "UR5 arm (3-D)"
    # one episode per switch, of the arm's first skill; the chooser offers the UR5's skills only
    assert started == ["ur5-reach"] and [key for _, key in page.skill_chooser.options] == [
        "ur5-reach", "ur5-place", "ur5-conveyor"]
    episode = page.episode
    assert isinstance(episode, EpisodeWidget) and episode.skill.key == "ur5-reach"
    assert isinstance(episode.teaching, SpaceTeachingCanvas)
    assert page.episode_slot.children == (episode,) and page.new_states_button in episode.next_actions.children
    # twice, quickly: back to the planar arms and to the UR5 again
    page.arm_chooser.value = "Planar arms"
    page.arm_chooser.value = "UR5 arm (3-D)"
    assert started == ["ur5-reach", "sim-point", "ur5-reach"]
    assert isinstance(page.episode.teaching, SpaceTeachingCanvas) and page.episode is not episode
    # the UR5 episode teaches and reports its error like the planar one
    page.skill_chooser.value = "ur5-place"
    shown = page.episode
    assert shown.skill.key == "ur5-place" and shown.guidance
    for index in range(shown.episode.n_states):
        shown.demonstrate(shown.episode.optimal_actions[index])
        shown.next()
    assert shown.phase == "finished" and shown.theta_error < 1e-9
    assert page.errors[-1][0] == "ur5-place" and "Your teaching error: 0.000" in page.result_line.value
    page.guidance_switch.value = False   # after a finished 3-D episode: a fresh one, unguided
    assert not page.episode.guidance and page.episode.skill.key == "ur5-place"


def test_a_page_of_given_skills_has_no_arm_chooser_and_both_at_once_are_refused():
    page = DemoPage(skills=[("Arm: reach a point", "sim-point")], duration=1.0)
    assert page.arm_chooser.layout.display == "none" and list(page.skills) == ["sim-point"]
    with pytest.raises(ValueError, match="skills, arms: expected one of them"):
        DemoPage(skills=[("a", "sim-point")], arms=[("x", [("a", "sim-point")])])


def test_switching_guidance_mid_episode_keeps_the_3d_arrows_too(recorder):
    # One EpisodeWidget for every arm: the UR5's arrows (and the one drawn) survive the switch as the planar do.
    page = DemoPage(skill="ur5-reach", duration=1.0)
    first = page.episode
    given = [[0.1, -0.2, 0.05], [0.0, 0.3, -0.1]]
    for action in given:
        first.demonstrate(action)
        first.next()
    first.set_action([0.2, 0.1, 0.0])                            # drawn, not confirmed
    page.guidance_switch.value = False
    episode = page.episode
    assert episode is not first and episode.guidance is False and episode.skill.key == "ur5-reach"
    np.testing.assert_array_equal(episode.query_states, first.query_states)
    assert episode.demonstrations == given and episode.state_index == 2 and episode.phase == "teaching"
    assert episode.progress.demonstrations_done == 2
    assert episode.pending_action == [0.2, 0.1, 0.0]
    assert "Guidance is now off; your 2 arrows so far are kept" in page.result_line.value
    # Switched while guidance is shown: the confirmed arrow is kept, no arrow is pending.
    page.guidance_switch.value = True
    page.episode.demonstrate([0.1, 0.1, 0.1])
    assert page.episode.phase == "guidance"
    page.guidance_switch.value = False
    assert page.episode.demonstrations == [*given, [0.1, 0.1, 0.1]] and page.episode.pending_action is None
