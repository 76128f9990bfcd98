"""Every button of the study path, double-clicked in Chromium: each acts once, none errors.

Issue 18: a double click on "Continue" (welcome) or "Continue to the study" stopped the study with
a SessionStateError; a double "Yes, withdraw" told the participant to "resume participant P04";
the stopped screen still offered "Withdraw". Here a participant double-clicks everything from
the welcome to the thank-you (the video, the forms, practice, an episode with guidance, the
reproduction), another double-clicks the withdrawal; the logs hold each step once.
"""

from __future__ import annotations

import numpy as np
import pytest

from browser_support import artifact_path
from mt_widgets import SKILLS
from mt_widgets.study.protocol import PROTOCOL_FOLDER
from mt_widgets.widgets import ArmView

from .support import assert_one_drag, button, drag_and_wait, log_events, open_and_fill, wait_for_log, wait_for_marker

pytestmark = pytest.mark.browser

VIDEO = PROTOCOL_FOLDER / "media" / "instructions.webm"
PROTOCOL = f"""
format = 1
name = "browser"
lambda = 0.01
seed = 5
reproduction_duration_s = 1.0
guidance_modality = "arrows"
[assignment]
block_size = 2
seed = 1
[texts]
welcome = "Welcome to the test study."
instructions = "How to teach."
reproduction = "This is what the robot learnt."
thank_you = "Thank you, all done."
[practice]
skill = "sim-point"
duration_s = 2
reproduction = false
text = "Practice freely."
[[phases]]
id = "P3"
skill = "sim-point"
episodes = 1
demonstrations = 2
guidance = ["target"]
instructions = "Teach skill 1."
[[before]]
id = "video"
kind = "video"
file = "{VIDEO}"
require_watched = true
[[before]]
id = "information"
kind = "information"
text = "What the study is."
[[before]]
id = "consent"
kind = "consent"
text = "Do you agree?"
[[before]]
id = "about"
kind = "demographics"
[[after]]
id = "questionnaire"
kind = "questionnaire"
[[after.items]]
id = "difficulty"
kind = "choice"
prompt = "Was it hard?"
options = ["no", "yes"]
"""

CALL = "Please call the experimenter"


def double(page, name, timeout=30_000):
    """Waits for the button to be enabled, then double-clicks it; the page must not stop."""
    target = button(page, name)
    page.wait_for_function("b => !b.disabled", arg=target.element_handle(timeout=timeout), timeout=timeout)
    target.dblclick()
    assert page.get_by_text(CALL).count() == 0, f"{name}: {page.inner_text('body')[:800]}"


def test_every_study_button_double_clicked_acts_once(page, voila_study, shot, tmp_path):
    protocol_path = tmp_path / "double.toml"
    protocol_path.write_text(PROTOCOL)
    participant = "D01"
    open_and_fill(page, voila_study, protocol_path, participant)
    page.get_by_label("Group").select_option(label="target")
    double(page, "Start new participant")
    page.get_by_text("Welcome to the test study.").wait_for(timeout=15_000)
    double(page, "Continue")
    video = page.locator("video")
    video.wait_for()
    # Scrubbed to its last 0.2 s: the end is reached, but the video was not watched.
    video.evaluate("v => new Promise(r => { const go = () => { v.muted = true; v.currentTime = v.duration - 0.2; "
                   "v.play(); r(); }; v.readyState >= 1 ? go() : v.addEventListener('loadedmetadata', go); })")
    page.get_by_text("skipped ahead").wait_for(timeout=15_000)
    assert button(page, "Continue").is_disabled()
    page.screenshot(path=shot("video-skipped"))
    page.get_by_role("button", name="Play again from the start").click()
    video.evaluate("v => { v.playbackRate = 8; }")
    double(page, "Continue", timeout=60_000)
    page.get_by_text("What the study is.").wait_for()
    double(page, "Continue")
    page.get_by_text("Do you agree?").wait_for()
    double(page, "I agree")
    page.get_by_text("Your age, in years").wait_for()
    page.get_by_placeholder("a number (years)").fill("-5")
    page.get_by_role("radio", name="female").check()
    double(page, "Continue")
    page.get_by_text("please type a whole number from 18 to 120").wait_for()
    assert page.get_by_text("answers[").count() == 0
    page.screenshot(path=shot("form-in-plain-words"))
    page.get_by_placeholder("a number (years)").fill("27")
    double(page, "Continue")
    page.get_by_text("How to teach.").wait_for()
    double(page, "Start the practice")
    page.get_by_text("Practice time is over.").wait_for(timeout=15_000)
    double(page, "Continue to the study")
    page.get_by_text("Teach skill 1.").wait_for()
    double(page, "Start")
    for index, name in enumerate(("Next state", "Finish and watch")):
        started = wait_for_log(voila_study, participant, lambda ev: any(e["type"] == "episode_started" for e in ev))
        state = [e for e in started if e["type"] == "episode_started"][-1]["query_states"][index]
        hand = ArmView(SKILLS["sim-point"]).end_effector_pixel(np.asarray(state))
        wait_for_marker(page, hand)
        drag_and_wait(page, hand, (50 - 30 * index, -40))
        try:
            double(page, "Confirm")
        except Exception:
            page.screenshot(path=shot(f"no-confirm-{index}"))
            raise
        wait_for_log(voila_study, participant, lambda ev, i=index: any(
            e["type"] == "demonstration" and e["index"] == i for e in ev))
        # The guidance arrow is named where it appears (this participant is in the guided group).
        page.get_by_text("arrow shows the optimal action").wait_for()
        if index == 0:
            page.screenshot(path=shot("guidance-named"))
        double(page, name)
    page.get_by_text("This is what the robot learnt.").wait_for(timeout=15_000)
    double(page, "Replay", timeout=30_000)
    double(page, "Continue", timeout=30_000)
    page.get_by_text("Was it hard?").wait_for()
    page.get_by_role("radio", name="no").check()
    double(page, "Continue")
    page.get_by_text("Thank you, all done.").wait_for()
    page.screenshot(path=shot("thank-you"))

    events = wait_for_log(voila_study, participant, lambda ev: ev[-1]["type"] == "session_finished")
    done = [e.get("step") or e.get("screen") for e in events if e["type"] in ("step_done", "screen_done")]
    assert done == ["welcome", "video", "information", "about", "instructions", "phase_intro", "reproduction",
                    "questionnaire"], done
    assert [e["type"] for e in events].count("consent_given") == 1
    assert [e["index"] for e in events if e["type"] == "demonstration"] == [0, 1]
    for demonstration in (e for e in events if e["type"] == "demonstration"):
        assert_one_drag(demonstration)
    video_done = [e for e in events if e.get("step") == "video"][0]
    assert video_done["watched_to_end"] is True


def test_a_double_clicked_withdrawal_ends_on_the_withdrawal_screen(page, voila_study, shot, tmp_path):
    protocol_path = tmp_path / "double.toml"
    protocol_path.write_text(PROTOCOL)
    open_and_fill(page, voila_study, protocol_path, "P04")
    button(page, "Start new participant").click()
    page.get_by_text("Welcome to the test study.").wait_for(timeout=15_000)
    double(page, "Withdraw from the study")
    page.get_by_text("Do you want to withdraw from the study?").wait_for()
    double(page, "Yes, withdraw")
    page.get_by_text("You have withdrawn from the study.").wait_for(timeout=15_000)
    # Both clicks reached the kernel before the withdrawal screen was sent back: it is final.
    page.get_by_text("Do you want to withdraw from the study?").wait_for(state="detached", timeout=15_000)
    page.screenshot(path=artifact_path("double-withdraw", "withdrawn"))
    text = page.inner_text("body")
    assert CALL not in text and "resume participant" not in text.lower()
    for name in ("Withdraw from the study", "Yes, withdraw", "No, continue the study", "Continue"):
        assert not [b for b in button(page, name).all() if b.is_visible()], name
    events = log_events(voila_study, "P04")
    assert [e["type"] for e in events].count("withdrawn") == 1
