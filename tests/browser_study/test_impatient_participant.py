"""An impatient participant on the study page: Replay, then at once Continue and Start.

The replay of a 10 s reproduction used to hold the browser's canvas queue, so the next
episode's canvas stayed blank for about 10 s. Every canvas must be drawn within a second of
the page settling.
"""

import time

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.widgets import ArmView

from .support import button, current_episode, open_and_fill, two_part_protocol, wait_for_log, wait_for_marker

pytestmark = pytest.mark.browser

# The second part unguided; a 10 s reproduction to replay.
PROTOCOL = two_part_protocol(second="P2", guided=False, seed=7, practice_s=0, practice_text="No practice.",
                             reproduction_s=10.0)

DRAWN_WITHIN_MS = 1000


def type_arrow(page, action):
    fields = page.locator(".widget-text input[type=number]")
    fields.nth(0).fill(f"{action[0]:.4f}")
    fields.nth(1).fill(f"{action[1]:.4f}")
    fields.nth(1).press("Tab")
    button(page, "Set arrow").click()
    confirm = button(page, "Confirm")
    page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(), timeout=10_000)
    confirm.click()


def test_replay_then_continue_then_start_draws_the_next_canvas_within_a_second(page, voila_study, shot, tmp_path):
    protocol_path = tmp_path / "impatient.toml"
    protocol_path.write_text(PROTOCOL)
    participant = "I01"
    open_and_fill(page, voila_study, protocol_path, participant)
    button(page, "Start new participant").click()
    page.get_by_text("Welcome to the test study.").wait_for(timeout=15_000)
    button(page, "Continue").click()
    button(page, "I agree").click()
    button(page, "Start").click()
    page.get_by_text("First part: teach skill 1.").wait_for()
    button(page, "Start").click()
    wait_for_log(voila_study, participant, lambda events: events[-1]["type"] == "episode_started")
    episode = current_episode(voila_study, participant)
    view = ArmView(SKILLS["sim-point"])
    for index in range(3):
        wait_for_marker(page, view.end_effector_pixel(np.asarray(episode["query_states"][index])))
        type_arrow(page, (1.0 - 0.5 * index, 0.5))
        wait_for_log(voila_study, participant, lambda events, i=index: any(
            e["type"] == "demonstration" and e["index"] == i and e["phase"] == "P1" for e in events))
    page.get_by_text("This is what the robot learnt.").wait_for()
    # The participant watches the whole reproduction (Continue waits for it), then replays it
    # and does not wait: Continue, Start.
    page.wait_for_function("b => !b.disabled", arg=button(page, "Continue").element_handle(), timeout=20_000)
    button(page, "Replay").click()
    time.sleep(0.5)
    button(page, "Continue").click()
    page.get_by_text("Second part: teach skill 1 again.").wait_for()
    button(page, "Start").click()
    page.get_by_text("Part 2 of 2, round 1 of 1").wait_for()
    events = wait_for_log(voila_study, participant, lambda events: events[-1]["type"] == "episode_started"
                          and events[-1]["phase"] == "P2")
    first = view.end_effector_pixel(np.asarray(events[-1]["query_states"][0]))
    settled = time.monotonic()
    try:
        wait_for_marker(page, first, timeout=DRAWN_WITHIN_MS)
    except Exception:
        page.screenshot(path=shot("blank"))
        raise AssertionError(f"the next episode's canvas was not drawn within {DRAWN_WITHIN_MS} ms of the page "
                             f"settling ({time.monotonic() - settled:.2f} s)") from None
    page.screenshot(path=shot("next-episode"))
