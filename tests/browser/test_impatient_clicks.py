"""An impatient visitor on the demo page: clicks while the reproduction or a replay plays.

Whatever is clicked and whenever, every canvas must be drawn without waiting for the frames of
the reproduction that was cut short (it used to wait for them: about 10 s), and the browser's
console must not report a widget model that is gone (ipycanvas' canvas manager stops drawing
for the whole page after one failed command).
"""

import time

import pytest

from .helpers import (
    OKABE,
    ee_pixel,
    mark_canvases,
    open_demo,
    reference,
    set_guidance,
    teach_by_numbers,
    wait_for_color,
    wait_for_new_canvases,
)

pytestmark = pytest.mark.browser

#: The reproduction plays 10 s; a canvas that waited for its frames (the bug this file guards
#: against) is drawn 10 s or more after it began. Every canvas must be drawn before 8.5 s: that is
#: the behaviour, not a speed (how fast a canvas is drawn is for benchmarks/, never asserted).
REPRODUCTION_S, DRAWN_BEFORE_S = 10.0, 8.5


def expect_drawn(page, episode, what: str, playing_since: float) -> None:
    """Both canvases show the episode's first state (teaching) and the start pose (player) before the
    reproduction that began at ``playing_since`` (time.monotonic()) would have played to its end:
    the marked canvases replaced by the new episode's, its texts shown."""
    def left_ms() -> float:
        return max(0.0, playing_since + DRAWN_BEFORE_S - time.monotonic()) * 1000

    wait_for_new_canvases(page)
    page.get_by_text(f"Teaching effort: 0 of {len(episode.query_states)} demonstrations").wait_for(timeout=10_000)
    page.get_by_text("Your teaching error").wait_for(state="detached", timeout=10_000)
    start = episode.player.view.transform.to_pixel(episode.skill.end_effector(episode.skill.start[None])[0][0])
    try:
        wait_for_color(page, 0, *ee_pixel(episode), OKABE["yellow"], timeout=left_ms() + 1)
        wait_for_color(page, 1, *start, OKABE["yellow"], timeout=left_ms() + 1)
    except Exception:
        raise AssertionError(f"{what}: a canvas was not drawn {DRAWN_BEFORE_S} s after the {REPRODUCTION_S} s "
                             f"reproduction began ({time.monotonic() - playing_since:.2f} s)") from None


@pytest.mark.parametrize("scenario", ["try-again", "replay-then-try-again", "another-skill", "guidance-toggle"])
def test_every_canvas_is_drawn_without_waiting_for_the_cut_reproduction_whatever_is_clicked(
        page, voila_server, artifacts, scenario):
    console = []
    open_demo(page, voila_server, console)
    mark_canvases(page)
    set_guidance(page, False)
    wait_for_new_canvases(page)  # the episode without guidance has replaced the first one
    episode = reference(guidance=False)
    wait_for_color(page, 0, *ee_pixel(episode), OKABE["yellow"])
    teach_by_numbers(page, episode, guidance=False)
    playing = time.monotonic()  # the last arrow is confirmed: the reproduction's frames are on their way
    time.sleep(1.0)  # the reproduction (10 s) is playing
    page.screenshot(path=artifacts("playing"))
    mark_canvases(page)
    if scenario == "try-again":
        page.get_by_role("button", name="Try again with new states").click()
        expect_drawn(page, reference(guidance=False, seed=1), scenario, playing)
    elif scenario == "replay-then-try-again":
        page.get_by_role("button", name="Replay").click()
        playing = time.monotonic()  # the replay plays the 10 s again
        time.sleep(0.5)
        page.get_by_role("button", name="Try again with new states").click()
        expect_drawn(page, reference(guidance=False, seed=1), scenario, playing)
    elif scenario == "another-skill":
        page.get_by_role("button", name="Arm: reach a line", exact=True).click()
        expect_drawn(page, reference("sim-line", guidance=False), scenario, playing)
    else:
        set_guidance(page, True)   # a fresh episode, guidance on, while the reproduction's frames are queued
        wait_for_new_canvases(page)
        mark_canvases(page)
        page.get_by_role("button", name="Try again with new states").click()
        expect_drawn(page, reference(guidance=True, seed=1), scenario, playing)
    page.screenshot(path=artifacts("after"))
    assert not [text for text in console if "not found" in text.lower()], console
