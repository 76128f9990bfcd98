"""The teaching widgets in a real Chromium, served by Voila (which renders after the kernel ran)."""

import time

import numpy as np
import pytest

from .helpers import (
    OKABE,
    drag,
    ee_pixel,
    reference_episode,
    to_canvas,
    to_page,
    wait_for_color,
    wait_for_pending,
    wait_for_status,
)

pytestmark = pytest.mark.browser

def open_page(page, voila_server, name: str = "episode_sim.ipynb"):
    page.goto(voila_server.url(f"/voila/render/{name}"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)


def test_arm_state_and_target_are_drawn_and_a_drag_gives_the_action_and_guidance(page, voila_server, artifacts):
    reference = reference_episode()
    view = reference.teaching.view
    open_page(page, voila_server)
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["yellow"])                      # end-effector marker
    wait_for_color(page, 0, *view.transform.to_pixel(reference.skill.target.point), OKABE["vermillion"])
    page.screenshot(path=artifacts("drawn"))

    # A real drag, in page coordinates of the CSS-scaled canvas (480 canvas px shown as 360 px).
    end = drag(page, 0, ee, (ee[0] + 70, ee[1] - 45))
    origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
    expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
    one_pixel = 1.0 / view.transform.pixels_per_action
    s = wait_for_pending(page, expected, one_pixel)
    assert np.allclose(s["pending"], expected, atol=one_pixel), (s["pending"], expected)
    page.screenshot(path=artifacts("dragged"))

    page.get_by_role("button", name="Confirm").click()
    wait_for_status(page, "s.phase === 'guidance'")
    tip = view.transform.action_tip(origin, reference.optimal[0])
    base = view.transform.to_pixel(origin)
    head = tip - 6 * (tip - base) / np.hypot(*(tip - base))           # inside the solid arrow head
    wait_for_color(page, 0, *head, OKABE["orange"], radius=1)
    assert page.get_by_text("optimal action (dashed)").count() >= 1
    page.screenshot(path=artifacts("guidance"))


def test_keyboard_and_numeric_entry_reach_python(page, voila_server, artifacts):
    reference = reference_episode()
    open_page(page, voila_server)
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["yellow"])
    page.mouse.click(*to_page(page, 0, 30, 30))                       # focus the canvas, away from the marker
    for key in ("ArrowRight", "ArrowRight", "ArrowRight", "ArrowUp"):
        page.keyboard.press(key)
    step = reference.teaching.view.transform.nice_action_step() / 10
    s = wait_for_status(page, "s.pending !== null && s.pending[1] > 0")
    assert np.allclose(s["pending"], [3 * step, step])
    page.keyboard.press("Enter")
    s = wait_for_status(page, "s.demos.length === 1")
    assert np.allclose(s["demos"][0], [3 * step, step])

    page.get_by_role("button", name="Next state").click()
    wait_for_status(page, "s.phase === 'teaching' && s.index === 1")
    u1, u2 = page.get_by_label("u1 (N)"), page.get_by_label("u2 (N)")
    u1.fill("1.25")
    u1.press("Tab")
    u2.fill("-0.5")
    u2.press("Tab")
    page.get_by_role("button", name="Set arrow").click()
    s = wait_for_status(page, "s.pending !== null")
    assert np.allclose(s["pending"], [1.25, -0.5])
    page.screenshot(path=artifacts("numeric"))


def test_reproduction_plays_to_its_last_frame_and_a_reload_draws_again(page, voila_server, artifacts):
    reference = reference_episode()
    open_page(page, voila_server)
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["yellow"])
    for action in reference.optimal:
        reference.demonstrate(action)
        reference.next()
    final = reference.player.view.transform.to_pixel(reference.result.trajectory.positions[-1])
    start = reference.player.view.transform.to_pixel(reference.skill.end_effector(reference.skill.start[None])[0][0])
    wait_for_color(page, 1, *start, OKABE["yellow"])                  # the player waits at the start
    clicked = time.monotonic()
    page.get_by_role("button", name="test: finish with optimal").click()
    wait_for_status(page, "s.phase === 'finished'")
    wait_for_color(page, 1, *final, OKABE["yellow"], timeout=20_000)
    elapsed = time.monotonic() - clicked
    assert elapsed >= 1.5, f"a 2 s reproduction cannot reach its last frame in {elapsed:.2f} s"
    page.screenshot(path=artifacts("reproduced"))

    page.reload()
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["yellow"])
    wait_for_color(page, 1, *start, OKABE["yellow"])
    page.screenshot(path=artifacts("reloaded"))


def test_uarm_top_view_shows_state_and_target_and_a_real_drag_gives_an_action_in_cm(page, voila_server, artifacts):
    name = "episode_uarm.ipynb"
    reference = reference_episode(name)
    view = reference.teaching.view
    open_page(page, voila_server, name)
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["black"], tolerance=20)                       # the current state
    wait_for_color(page, 0, *view.transform.to_pixel(reference.skill.target.point), OKABE["vermillion"])
    page.screenshot(path=artifacts("drawn"))

    # 304 x 480 canvas pixels shown 260 px wide: the drag is mapped through the scaled box.
    end = drag(page, 0, ee, (ee[0] + 45, ee[1] - 60))
    origin = reference.query_states[0]
    expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
    one_pixel = 1.0 / view.transform.pixels_per_action
    s = wait_for_pending(page, expected, one_pixel)
    assert expected[0] > 2 and expected[1] > 3, expected          # right and up, several centimetres
    assert np.allclose(s["pending"], expected, atol=one_pixel)
    readout = f"({expected[0]:+.2f}, {expected[1]:+.2f}) cm"
    page.get_by_text(readout).wait_for(timeout=10_000)            # the action in words, in centimetres
    tip = view.transform.action_tip(origin, expected)
    wait_for_color(page, 0, *(tip + 5 * (ee - tip) / np.hypot(*(ee - tip))), OKABE["blue"], radius=1)
    page.screenshot(path=artifacts("dragged"))
