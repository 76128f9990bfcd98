"""A participant on a tablet or a phone draws the study's arrows with a finger (notebooks/study_sim.ipynb).

The study page is reached through the helpers of test_study_page.py (the page's own flow is
tested there); here only the finger: a drag from the hand in the practice and in an episode, the
demonstration logged as drawn with the pointer, and a swipe elsewhere on the canvas drawing nothing.
"""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.widgets import ArmView
from tests.browser.helpers import touch_context, touch_drag

from .support import PROTOCOL, button, current_episode, open_and_fill, wait_for_log, wait_for_marker

pytestmark = pytest.mark.browser

SCREENS = {"tablet": (768, 1024), "phone": (390, 844)}


def to_page(page, x, y):
    element = page.locator("canvas").first
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")
    return box["x"] + x * box["width"] / width, box["y"] + y * box["height"] / height


def finger_drag(page, ee, offset):
    page.locator("canvas").first.scroll_into_view_if_needed()
    touch_drag(page, to_page(page, *ee), to_page(page, ee[0] + offset[0], ee[1] + offset[1]))


@pytest.mark.parametrize("screen", SCREENS)
def test_a_finger_draws_the_practice_and_the_study_arrows(browser, voila_study, shot, tmp_path, screen):
    protocol_path = tmp_path / "browser.toml"
    protocol_path.write_text(PROTOCOL)
    participant = f"T{list(SCREENS).index(screen) + 1:02d}"
    context, page = touch_context(browser, *SCREENS[screen])
    try:
        open_and_fill(page, voila_study, protocol_path, participant)
        button(page, "Start new participant").click()
        button(page, "Continue").click()
        button(page, "I agree").click()
        button(page, "Start the practice").click()
        page.get_by_text("Practice freely.").wait_for()
        view = ArmView(SKILLS["sim-point"])
        practice_states = SKILLS["sim-point"].query_states(seed=np.random.SeedSequence(12345).spawn(1)[0])
        ee = view.end_effector_pixel(practice_states[0])
        wait_for_marker(page, ee)
        # A swipe from a far corner of the canvas draws nothing; a finger from the hand draws.
        far = (40.0, 40.0) if np.hypot(*(np.array([40.0, 40.0]) - ee)) > 150 else (view.transform.width - 40.0, 40.0)
        finger_drag(page, far, (0, -150))
        finger_drag(page, ee, (60, -30))
        page.get_by_text("your arrow").first.wait_for(timeout=10_000)
        page.screenshot(path=shot(f"{screen}-practice"))
        page.get_by_text("Practice time is over.").wait_for(timeout=10_000)
        button(page, "Continue to the study").click()

        page.get_by_text("First part: teach skill 1.").wait_for()
        button(page, "Start").click()
        wait_for_log(voila_study, participant, lambda events: any(
            e["type"] == "episode_started" and e["phase"] == "P1" for e in events))
        episode = current_episode(voila_study, participant)
        ee = view.end_effector_pixel(np.asarray(episode["query_states"][0]))
        wait_for_marker(page, ee)
        finger_drag(page, ee, (50, -40))
        confirm = button(page, "Confirm")
        page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(), timeout=10_000)
        page.screenshot(path=shot(f"{screen}-episode"))
        confirm.tap()
        events = wait_for_log(voila_study, participant, lambda events: any(
            e["type"] == "demonstration" for e in events))
        (drawn,) = [e for e in events if e["type"] == "demonstration"]
        assert drawn["input"]["method"] == "pointer" and drawn["time_to_first_input_s"] is not None
        expected = view.transform.action_from_drag(
            SKILLS["sim-point"].end_effector(np.asarray(episode["query_states"][:1]))[0][0], ee + (50, -40))
        np.testing.assert_allclose(drawn["action"], expected, atol=0.1)
    finally:
        context.close()
