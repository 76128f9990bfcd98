"""The reward-learning study's page in Voila, in Chromium: a participant of the target group draws a
demonstration for the reward-learning robot and sees its machine teaching's arrow."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.core.learner_teaching import teach
from mt_widgets.core.reward_learner import RewardLearner
from mt_widgets.widgets import ArmView
from protocols import BROWSER_TEXTS, phase, protocol_toml
from tests.browser.helpers import OKABE, wait_for_color

from .support import button, drag_and_wait, open_and_fill, wait_for_log

pytestmark = pytest.mark.browser

#: reward-sim's guided training phase, on its own: 8 demonstrations, the reward learner.
PROTOCOL = protocol_toml("browser", [phase("P3", "uarm-point", demonstrations=8, guidance=["target"],
                                           instructions="Teach the robot to reach the goal.")],
                         practice_s=0, texts=BROWSER_TEXTS, top={"learner": "reward", "guidance_modality": "arrows"})


def test_a_participant_teaches_the_reward_robot_and_sees_its_guidance(page, voila_study, shot, tmp_path):
    path = tmp_path / "browser.toml"
    path.write_text(PROTOCOL)
    open_and_fill(page, voila_study, path, "R01")
    page.get_by_label("Group").select_option(label="target")
    button(page, "Start new participant").click()
    page.get_by_text("Welcome to the test study.").wait_for(timeout=15_000)
    button(page, "Continue").click()
    button(page, "I agree").click()
    page.get_by_text("How to teach.").wait_for()
    button(page, "Start").click()   # no practice (0 s)
    try:
        page.get_by_text("Teach the robot to reach the goal.").wait_for()
    except Exception:
        page.screenshot(path=shot("reward-intro-failed"))
        raise AssertionError(f"no phase introduction; the page says: {page.inner_text('body')[:1500]}") from None
    button(page, "Start").click()

    started = wait_for_log(voila_study, "R01", lambda events: any(e["type"] == "episode_started" for e in events))
    episode = [e for e in started if e["type"] == "episode_started"][-1]
    skill, states = SKILLS["uarm-point"], np.asarray(episode["query_states"])
    assert episode["learner"] == "reward" and len(states) == 8
    optimal = teach(RewardLearner(), skill, states).optimal
    np.testing.assert_allclose(episode["optimal"], optimal, atol=1e-9)

    # A drag across the optimal arrow (perpendicular to it), so the guidance is not drawn beside it.
    view = ArmView(skill)
    ee = np.asarray(view.end_effector_pixel(states[0]))
    tip = np.asarray(view.transform.action_tip(states[0], optimal[0]))
    along = (tip - ee) / np.linalg.norm(tip - ee)
    # The uArm's screen shows the robot's position as a black dot.
    wait_for_color(page, 0, *ee, OKABE["black"], tolerance=20)
    drag_and_wait(page, ee, tuple(40 * np.array([along[1], -along[0]]))).click()
    events = wait_for_log(voila_study, "R01", lambda events: any(e["type"] == "demonstration" for e in events))
    demonstration = next(e for e in events if e["type"] == "demonstration")
    assert demonstration["guidance_shown"] and demonstration["input"]["method"] == "pointer"
    # The reward learner's MT arrow: its solid head, just behind the tip, in the optimal arrow's orange.
    wait_for_color(page, 0, *(tip - 6 * along), OKABE["orange"], radius=3)
    page.screenshot(path=shot("reward-guidance"))
    page.get_by_text("optimal action (dashed)").wait_for()   # the guidance's legend came with it
