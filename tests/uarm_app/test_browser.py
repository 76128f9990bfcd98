"""The uArm teaching view in Voila, in a real browser, against the simulated arm."""

from __future__ import annotations

import re

import numpy as np
import pytest

from browser.helpers import OKABE, status, to_page, wait_for_color, wait_for_status
from mt_widgets import SKILLS, RidgeLearner
from mt_widgets.core import DEFAULT_LAMBDA

# The page's screen: 600 x 400 mm at 1200 x 800 px (2 px per mm, 20 px per cm), the arm's base
# at canvas pixel (600, 690), its +X pointing up the screen.
PX_PER_CM, BASE = 20.0, np.array([600.0, 690.0])
# ipycanvas 0.14 composites a MultiCanvas into one <canvas>: the teaching view is the first.
ROBOT = BACKGROUND = ARROWS = 0


def pixel(point_cm) -> np.ndarray:
    r1, r2 = point_cm
    return BASE + PX_PER_CM * np.array([-r2, -r1])


@pytest.mark.browser
def test_the_uarm_view_draws_takes_a_real_drag_and_moves_the_simulated_arm(uarm_voila, tall_page, artifacts):
    page = tall_page
    skill = SKILLS["uarm-point"]
    states = skill.query_states(seed=0)
    page.goto(uarm_voila.url("/voila/render/uarm_view.ipynb"), timeout=60_000)
    # Drawn pixels: the black dot at the first query state, the red target at (23, 11) cm.
    # The kernel imports numba-compiled code first: slow on a loaded 2-core machine.
    wait_for_color(page, ROBOT, *pixel(states[0]), OKABE["black"], timeout=150_000)
    wait_for_color(page, BACKGROUND, *pixel((23.0, 11.0)), (255, 0, 0))
    page.screenshot(path=artifacts("first-state"))
    label = page.locator("text=/^arm at x = /").first
    x, y = map(float, re.findall(r"-?\d+\.\d", label.inner_text()))
    assert (x, y) == pytest.approx(tuple(states[0] * 10), abs=0.06)  # the arm shows the query state

    for index, state in enumerate(states):
        wait_for_color(page, ROBOT, *pixel(state), OKABE["black"])
        start = pixel(state)
        page.mouse.move(*to_page(page, ARROWS, *start))
        page.mouse.down()
        for fraction in (0.25, 0.5, 0.75, 1.0):  # 40 px up the screen: +2 cm in r1
            page.mouse.move(*to_page(page, ARROWS, start[0], start[1] - 40 * fraction))
        page.mouse.up()
        # The readout follows the drag; the final position of the pointer is the action.
        pending = wait_for_status(page, "s.pending !== null && s.pending[0] > 1.9")["pending"]
        assert pending == pytest.approx([2.0, 0.0], abs=0.1)
        if index == 0:
            wait_for_color(page, ARROWS, start[0], start[1] - 20, (124, 252, 0), tolerance=60)  # the user's arrow
            page.screenshot(path=artifacts("drag"))
        page.get_by_role("button", name="Confirm").click()
        wait_for_status(page, f"s.demonstrations.length === {index + 1}")

    # The reproduction of what was learnt runs on the simulated arm; its position is read back.
    wait_for_status(page, "s.phase === 'finished'")
    demonstrations = np.array(status(page)["demonstrations"])
    theta_hat = RidgeLearner(lam=DEFAULT_LAMBDA).fit(skill.features(states), demonstrations).theta
    final_mm = skill.reproduce(theta_hat).final_position * 10
    page.wait_for_function("() => document.body.innerText.includes('finished its reproduction')", timeout=30_000)
    x, y = map(float, re.findall(r"-?\d+\.\d", label.inner_text()))
    assert np.hypot(x - final_mm[0], y - final_mm[1]) < 0.6  # min_move_mm: tiny last steps are not sent
    assert np.hypot(x - states[-1][0] * 10, y - states[-1][1] * 10) > 5.0  # it did move
    page.screenshot(path=artifacts("reproduced"))


def _hand_canvas_point(page, px: float, py: float) -> tuple[float, float]:
    """A pixel of the simulated hand's canvas -> page coordinates (through its CSS box)."""
    box = page.evaluate("""() => {
        const host = document.querySelector('.mt-simulated-hand');
        const c = host.tagName === 'CANVAS' ? host : host.querySelector('canvas');
        const r = c.getBoundingClientRect();
        return [r.x, r.y, r.width, r.height, c.width, c.height];
    }""")
    x, y, w, h, cw, ch = box
    return x + px * w / cw, y + py * h / ch


def _drag_tip(page, state_cm, step_cm, fractions=(0.25, 0.5, 0.75, 1.0), release: bool = True) -> None:
    from mt_widgets.apps.uarm_hand import arm_to_view
    start = np.array(arm_to_view(state_cm[0] * 10, state_cm[1] * 10))
    end = np.array(arm_to_view((state_cm[0] + step_cm[0]) * 10, (state_cm[1] + step_cm[1]) * 10))
    page.mouse.move(*_hand_canvas_point(page, *start))
    page.mouse.down()
    for f in fractions:
        page.mouse.move(*_hand_canvas_point(page, *(start + f * (end - start))))
    if release:
        page.mouse.up()


@pytest.mark.browser
def test_teaching_by_hand_in_the_browser_with_a_pulled_cable_mid_move(uarm_voila, tall_page, artifacts):
    page = tall_page
    states = SKILLS["uarm-point"].query_states(seed=0)
    page.goto(uarm_voila.url("/voila/render/uarm_hand.ipynb"), timeout=60_000)
    wait_for_color(page, ROBOT, *pixel(states[0]), OKABE["black"], timeout=150_000)
    hand_button = page.get_by_role("button", name="Teach by hand (H)")
    steps = [(2.0, 0.0), (0.0, -1.5)]
    for index, step in enumerate(steps):
        wait_for_color(page, ROBOT, *pixel(states[index]), OKABE["black"])
        wait_for_status(page, "!s.hand_busy", timeout=30_000)
        if index == 0:
            hand_button.dblclick()  # an impatient double click starts one hand move
        else:
            page.locator("canvas").first.click(position={"x": 5, "y": 5})
            page.keyboard.press("h")  # the key, on the canvas
        wait_for_status(page, "s.released", timeout=30_000)
        if index == 0:
            page.screenshot(path=artifacts("hand-released"))
        _drag_tip(page, states[index], step)
        # A hand is not a ruler: the tip lands within a few mm of where the pointer went (0.5 px per mm).
        # The arrow follows the tip at the app's 0.1 s polling: once the tip rests, the arrow is the
        # measured displacement (a STATUS taken while the tip still moves shows an older poll).
        x0, y0 = states[index] * 10
        s = wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[0] - {step[0]}) < 0.3 "
                                  f"&& Math.abs(s.pending[1] - {step[1]}) < 0.3 "
                                  f"&& Math.abs(s.pending[0] - (s.tip_mm[0] - {x0}) / 10) < 0.02 "
                                  f"&& Math.abs(s.pending[1] - (s.tip_mm[1] - {y0}) / 10) < 0.02", timeout=30_000)
        measured = (np.array(s["tip_mm"][:2]) - states[index] * 10) / 10
        assert s["pending"] == pytest.approx(measured, abs=0.02)  # the arrow is the measured displacement
        if index == 0:
            page.screenshot(path=artifacts("hand-arrow"))
        page.get_by_role("button", name="Confirm").click()
        wait_for_status(page, f"s.demonstrations.length === {index + 1} && !s.released", timeout=30_000)
    s = status(page)
    assert s["methods"] == ["hand", "hand"]
    # The third state: the cable is pulled in the middle of the hand move.
    wait_for_color(page, ROBOT, *pixel(states[2]), OKABE["black"])
    wait_for_status(page, "!s.hand_busy", timeout=30_000)
    hand_button.click()
    wait_for_status(page, "s.released", timeout=30_000)
    _drag_tip(page, states[2], (1.0, 1.0), fractions=(0.25, 0.5), release=False)
    page.mouse.up()
    page.get_by_role("button", name="Pull the USB cable").click()
    s = wait_for_status(page, "s.message.includes('safe')", timeout=30_000)
    assert "released" in s["message"] and "nothing is lost" in s["message"]
    assert s["released"] and len(s["demonstrations"]) == 2 and s["phase"] == "teaching"
    assert page.get_by_text("Cable pulled").count() >= 1
    page.screenshot(path=artifacts("cable-pulled"))


@pytest.mark.browser
def test_the_uarm_study_app_taught_by_hand_logs_the_modality_and_survives_a_pulled_cable(uarm_voila, tall_page,
                                                                                         artifacts):
    page = tall_page
    page.goto(uarm_voila.url("/voila/render/uarm_study_hand.ipynb"), timeout=60_000)
    # Each screen is known by the protocol's text on it; its button is pressed through a locator
    # (found again if the view is rebuilt under the pointer), then the screen must leave. Two
    # screens in a row have a "Start": a press belongs to the screen whose text was seen.
    # The phase's text stays above its episode: the last press ends when the episode is there.
    for text, label in (("Welcome.", "Continue"), ("Consent.", "I agree"), ("Instructions.", "Start"),
                        ("Skill 1.", "Start")):
        screen = page.get_by_text(text, exact=True)
        screen.wait_for(timeout=150_000)
        page.get_by_role("button", name=label, exact=True).first.click()
        if text != "Skill 1.":
            screen.wait_for(state="detached", timeout=60_000)
    s = wait_for_status(page, "s.in_episode && s.hand_shown && !s.hand_busy", timeout=60_000)
    hand_button = page.get_by_role("button", name="Teach by hand (H)")
    for index, step in enumerate([(1.5, 0.0), (0.0, 1.0)]):
        s = wait_for_status(page, f"s.index === {index} && !s.hand_busy && !s.released", timeout=30_000)
        hand_button.click()
        s = wait_for_status(page, "s.released", timeout=30_000)
        state_cm = np.array(s["state_mm"][:2]) / 10
        _drag_tip(page, state_cm, step)
        s = wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[0] - {step[0]}) < 0.3 "
                                  f"&& Math.abs(s.pending[1] - {step[1]}) < 0.3", timeout=30_000)
        if index == 0:
            page.screenshot(path=artifacts("study-hand-arrow"))
        page.get_by_role("button", name="Confirm").click()
        wait_for_status(page, f"s.logged.length === {index + 1}", timeout=30_000)
    s = wait_for_status(page, "s.index === 2 && !s.hand_busy && !s.released", timeout=30_000)
    assert s["logged"] == [["hand", "hand"], ["hand", "hand"]]
    hand_button.click()
    s = wait_for_status(page, "s.released", timeout=30_000)
    _drag_tip(page, np.array(s["state_mm"][:2]) / 10, (1.0, 0.0), fractions=(0.3, 0.6), release=False)
    page.mouse.up()
    page.get_by_role("button", name="Pull the USB cable").click()
    s = wait_for_status(page, "s.message.includes('safe')", timeout=30_000)
    assert s["released"] and len(s["logged"]) == 2 and len(s["demonstrations"]) == 2
    page.screenshot(path=artifacts("study-cable-pulled"))
    # The participant can still finish by drawing: the confirmed arrow is logged as drawn.
    page.get_by_role("button", name="Clear").click()
    page.locator(".widget-inline-hbox:has-text('u1 (cm)') input").first.fill("1")
    page.locator(".widget-inline-hbox:has-text('u2 (cm)') input").first.fill("0.5")
    page.get_by_role("button", name="Set arrow").click()
    page.get_by_role("button", name="Confirm").click()
    s = wait_for_status(page, "s.logged.length === 3", timeout=30_000)
    assert s["logged"][2] == ["drawn", "numeric"]
