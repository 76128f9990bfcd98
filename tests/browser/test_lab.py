"""The teaching widgets in JupyterLab, including a page reload with the kernel still running."""

import numpy as np
import pytest

from .helpers import (
    OKABE,
    ax_names,
    ee_pixel,
    reference_episode,
    to_canvas,
    to_page,
    touch_context,
    touch_drag,
    wait_for_color,
    wait_for_status,
)

pytestmark = pytest.mark.browser


def run_all(page, lab_server, ee) -> None:
    """Open the test page in Lab, run all cells, wait for the end-effector marker's pixels."""
    page.goto(lab_server.url(f"/lab/tree/episode_sim.ipynb?reset&token={lab_server.token}"), timeout=60_000)
    page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.get_by_text("Run All Cells", exact=True).click()
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee, OKABE["yellow"])


def test_lab_draws_takes_a_drag_and_redraws_after_a_page_reload(lab_page, lab_server, artifacts):
    page = lab_page
    reference = reference_episode()
    ee = ee_pixel(reference)
    run_all(page, lab_server, ee)
    page.screenshot(path=artifacts("run"))

    page.locator("canvas").first.scroll_into_view_if_needed()
    start = to_page(page, 0, *ee)
    end = tuple(float(round(v)) for v in to_page(page, 0, ee[0] - 50, ee[1] + 35))
    page.mouse.move(*start)
    page.mouse.down()
    page.mouse.move((start[0] + end[0]) / 2, (start[1] + end[1]) / 2)
    page.mouse.move(*end)
    page.mouse.up()
    origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
    view = reference.teaching.view
    expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
    one_pixel = 1.0 / view.transform.pixels_per_action
    wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[0] - {expected[0]}) < {one_pixel}"
                          f" && Math.abs(s.pending[1] - {expected[1]}) < {one_pixel}")
    tip = view.transform.action_tip(origin, expected)
    wait_for_color(page, 0, *(tip + 5 * (ee - tip) / np.hypot(*(ee - tip))), OKABE["blue"], radius=1)

    # Save (outputs carry the widget views), reload: the live kernel's canvases must draw again
    # in the new page, which is what ipycanvas issue #322 broke.
    # (through the menu: the focused canvas takes key presses, Ctrl+S included)
    page.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
    page.get_by_text("Save Notebook", exact=True).first.click()
    # The tab's dirty marker goes when the file is written.
    page.wait_for_function("() => !document.querySelector('.jp-mod-dirty')", timeout=10_000)
    page.reload()
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee, OKABE["yellow"])
    wait_for_color(page, 0, *view.transform.to_pixel(reference.skill.target.point), OKABE["vermillion"])
    wait_for_color(page, 0, *(tip + 5 * (ee - tip) / np.hypot(*(ee - tip))), OKABE["blue"], radius=1)
    page.screenshot(path=artifacts("reloaded"))
    page.locator("canvas").first.screenshot(path=artifacts("reloaded-canvas"))


def test_lab_keyboard_entry_draws_the_arrow_and_enter_confirms_it_without_lab_taking_the_keys(lab_page, lab_server,
                                                                                           artifacts):
    # In Lab the notebook has its own shortcuts (arrows move between cells, Enter edits one):
    # once the canvas has focus, the keys must reach the widget and not Lab.
    page = lab_page
    reference = reference_episode()
    view = reference.teaching.view
    ee = ee_pixel(reference)
    run_all(page, lab_server, ee)
    page.locator("canvas").first.scroll_into_view_if_needed()
    page.mouse.click(*to_page(page, 0, 60, 60))                        # focus the canvas, away from the marker
    for key in ("ArrowLeft", "ArrowLeft", "ArrowUp", "ArrowUp", "ArrowUp", "Shift+ArrowUp"):
        page.keyboard.press(key)
    step = view.transform.nice_action_step() / 10
    expected = np.array([-2 * step, 3 * step + step / 5])
    s = wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[1] - {expected[1]}) < 1e-9")
    assert np.allclose(s["pending"], expected)
    origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
    tip = view.transform.action_tip(origin, expected)
    wait_for_color(page, 0, *(tip + 4 * (ee - tip) / np.hypot(*(ee - tip))), OKABE["blue"], radius=1)
    page.screenshot(path=artifacts("keyboard"))
    page.keyboard.press("Enter")
    s = wait_for_status(page, "s.demos.length === 1 && s.phase === 'guidance'")
    assert np.allclose(s["demos"][0], expected)
    # Lab did not act on the keys: still one cell, in command mode, the notebook unchanged.
    assert page.locator(".jp-Notebook .jp-Cell").count() == 1
    assert page.locator(".jp-mod-editMode").count() == 0


def canvas_access(page) -> dict:
    """What the canvas's accessibility layer (widgets/canvas_access.js) set on the first canvas."""
    return page.evaluate("""() => { const c = document.querySelector('canvas');
        const words = [...document.querySelectorAll('[aria-live="polite"]')].map(e => e.textContent);
        return {role: c.getAttribute('role'), label: c.getAttribute('aria-label') || '',
                live: words.filter(w => w.startsWith('Teaching canvas')),
                focused: document.activeElement === c}; }""")


def test_lab_names_the_canvas_lets_tab_leave_it_and_scrolls_on_a_touch_away_from_the_hand(browser, lab_server,
                                                                                          artifacts):
    # The accessibility layer is an anywidget front end: in Lab as in Voila, and again after a reload.
    context, page = touch_context(browser, 1280, 900)
    try:
        reference = reference_episode()
        ee = ee_pixel(reference)
        run_all(page, lab_server, ee)
        page.locator("canvas").first.scroll_into_view_if_needed()
        page.wait_for_function("() => document.querySelector('canvas').getAttribute('role') === 'application'")
        access = canvas_access(page)
        assert access["label"].startswith("Teaching canvas, state 1 of 5"), access
        assert access["live"] == [access["label"]], access                   # the same words, read out on change
        assert any(name.startswith("Teaching canvas, state 1 of 5") for name in ax_names(page))

        # A finger from the hand draws; one away from it reaches neither ipycanvas nor the kernel.
        page.evaluate("""() => { window.mtTouches = [];
            window.addEventListener('touchstart', e => setTimeout(() => window.mtTouches.push(e.defaultPrevented)),
                                    true); }""")
        end = tuple(float(round(v)) for v in to_page(page, 0, ee[0] - 50, ee[1] + 35))
        touch_drag(page, to_page(page, 0, *ee), end)
        page.wait_for_function("() => window.mtTouches.length == 1")
        assert page.evaluate("window.mtTouches") == [True]                    # ipycanvas took this one
        origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
        view = reference.teaching.view
        expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
        one_pixel = 1.0 / view.transform.pixels_per_action
        wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[0] - {expected[0]}) < {one_pixel}"
                              f" && Math.abs(s.pending[1] - {expected[1]}) < {one_pixel}")
        far = to_page(page, 0, 40, 40)
        touch_drag(page, far, (far[0] + 60, far[1] + 80))
        page.wait_for_function("() => window.mtTouches.length == 2")
        assert page.evaluate("window.mtTouches") == [True, False]
        page.wait_for_function("() => (document.querySelector('canvas').getAttribute('aria-label') || '')"
                               ".includes('Your arrow')")
        assert "Your arrow" in canvas_access(page)["live"][0]
        page.screenshot(path=artifacts("touched"))

        # Tab onto the canvas and off it again: ipycanvas alone would keep the focus.
        page.locator("canvas").first.focus()
        assert canvas_access(page)["focused"]
        page.keyboard.press("Tab")
        assert not canvas_access(page)["focused"]
        page.keyboard.press("Shift+Tab")
        assert canvas_access(page)["focused"]

        # A reload with the kernel running: the new page's views are named again.
        page.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
        page.get_by_text("Save Notebook", exact=True).first.click()
        page.wait_for_function("() => !document.querySelector('.jp-mod-dirty')", timeout=10_000)
        page.reload()
        page.wait_for_selector("canvas", timeout=60_000)
        page.wait_for_function("() => (document.querySelector('canvas').getAttribute('aria-label') || '')"
                               ".includes('Your arrow')", timeout=60_000)
        assert canvas_access(page)["role"] == "application"
        page.screenshot(path=artifacts("reloaded"))
    finally:
        api = context.request
        headers = {"Authorization": f"token {lab_server.token}"}
        for session in api.get(lab_server.url("/api/sessions"), headers=headers).json():
            api.delete(lab_server.url(f"/api/sessions/{session['id']}"), headers=headers)
        context.close()
