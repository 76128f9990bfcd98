"""The teaching widgets in JupyterLab, including a page reload with the kernel still running."""

import numpy as np
import pytest

from .helpers import OKABE, ee_pixel, reference_episode, to_canvas, to_page, wait_for_color, wait_for_status

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
