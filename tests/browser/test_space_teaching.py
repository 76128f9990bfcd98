"""A 3-D demonstration drawn in Chromium (Voila): mouse, keyboard and a finger, desktop and phone.

The page (pages/space_teaching.ipynb) shows ``SpaceTeachingCanvas`` for ``ur5-reach`` and a STATUS
label with the pending action and the recorded demonstrations; expected pixels come from the same
widget built here without a kernel.
"""

import numpy as np
import pytest

from .helpers import OKABE, ax_names, drag, to_page, touch_context, touch_drag, wait_for_color, wait_for_status

pytestmark = pytest.mark.browser

#: The page's one <canvas>: ipycanvas 0.14 composes a MultiCanvas's layers into one element.
ROBOT = 0


def reference():
    from mt_widgets.widgets.space_teaching import SpaceTeachingCanvas
    return SpaceTeachingCanvas("ur5-reach", seed=0, play=False)


def open_page(page, voila_server, widget):
    page.goto(voila_server.url("/voila/render/space_teaching.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    for view in ("top", "side", "perspective"):
        wait_for_color(page, ROBOT, *widget.tool_pixel(view), OKABE["yellow"], timeout=20_000)


def expected_action(widget, top_end, side_end):
    """The action a drag to canvas pixel ``top_end`` (top view), then ``side_end`` (side view) gives."""
    top, side = widget.panel("top"), widget.panel("side")
    start_top, start_side = widget.tool_pixel("top"), widget.tool_pixel("side")
    length = widget.action_length
    # x is in both views: the side view's drag moves it on from the x the top view set.
    return np.array([((top_end[0] - start_top[0]) / top.scale + (side_end[0] - start_side[0]) / side.scale) / length,
                     -(top_end[1] - start_top[1]) / top.scale / length,
                     -(side_end[1] - start_side[1]) / side.scale / length])


def wait_pending(page, expected, tolerance):
    checks = " && ".join(f"Math.abs(s.pending[{i}] - {float(v)}) < {tolerance}" for i, v in enumerate(expected))
    return wait_for_status(page, f"s.pending !== null && {checks}")


def test_mouse_then_keyboard_draw_3d_demonstrations_and_guidance_shows_in_every_view(browser, voila_server, page,
                                                                                    artifacts):
    widget = reference()
    open_page(page, voila_server, widget)
    page.screenshot(path=artifacts("desktop-opened"))
    # The mouse: horizontal components in the top view, then the height (and x) in the side view.
    top_end = widget.tool_pixel("top") + (40.0, -30.0)
    side_end = widget.tool_pixel("side") + (-20.0, -35.0)
    drag(page, ROBOT, widget.tool_pixel("top"), top_end)
    wait_for_status(page, "s.pending !== null")
    drag(page, ROBOT, widget.tool_pixel("side"), side_end)
    # Chromium reports whole CSS pixels: a pixel's worth of action is the tolerance.
    tolerance = 1.5 / widget.panel("top").scale / widget.action_length
    expected = expected_action(widget, top_end, side_end)
    wait_pending(page, expected, tolerance)
    # The user's arrow (blue) drawn in the perspective view too: its tip's pixel.
    tip = widget.panel("perspective").pixels(widget._tool() + widget.action_length * expected)
    wait_for_color(page, ROBOT, *tip, OKABE["blue"], radius=4)
    page.screenshot(path=artifacts("desktop-drawn"))

    # Enter on the canvas confirms (focus by a click in the empty fourth cell, which draws nothing).
    cell = widget.panel_size
    page.mouse.click(*to_page(page, ROBOT, 1.5 * cell, 1.8 * cell))
    page.keyboard.press("Enter")
    state = wait_for_status(page, "s.demos.length == 1 && s.guidance")
    np.testing.assert_allclose(state["demos"][0], expected, atol=tolerance)
    assert state["methods"] == ["pointer"]
    # Guidance: the optimal arrow (orange, dashed) points where the optimal action says. At this
    # state it is 3-5 px to scale, under the hand's dot: it is drawn at its shortest visible length.
    optimal = widget.episode.optimal_actions[0]
    for view in ("top", "side"):
        optimal_tip, lengthened = widget._optimal_tip(widget.panel(view), widget._tool(), optimal)
        assert lengthened
        wait_for_color(page, ROBOT, *optimal_tip, OKABE["orange"], radius=4)
    page.screenshot(path=artifacts("desktop-guidance"))

    # The keyboard: Enter goes on; x +2 steps, Space (to y) -1 step, z +1 fine step; Enter confirms.
    page.keyboard.press("Enter")
    wait_for_status(page, "!s.guidance && s.demos.length == 1")
    for name in ("ArrowUp", "ArrowUp", " ", "ArrowDown", "z", "Shift+ArrowUp"):
        page.keyboard.press(name)
    span = float(np.max(widget.drawing.bounds.high - widget.drawing.bounds.low))
    step = 0.02 * span / widget.action_length
    wait_pending(page, [2 * step, -step, step / 5], 1e-9)
    page.keyboard.press("Enter")
    state = wait_for_status(page, "s.demos.length == 2")
    assert state["methods"] == ["pointer", "keyboard"]
    # The keys a/d turn the 3-D view.
    azimuth = state["azimuth"]
    page.keyboard.press("Enter")
    page.keyboard.press("d")
    wait_for_status(page, f"Math.abs(s.azimuth - {(azimuth + 10.0) % 360}) < 1e-9")
    page.screenshot(path=artifacts("desktop-keyboard-turned"))
    # A screen reader gets the canvas's words (its accessible name), and Tab leaves the canvas.
    page.wait_for_function("() => document.querySelector('canvas').getAttribute('aria-label')"
                           "?.includes('turned 45 degrees round')")
    assert any("State 3 of 4: the robot's hand is at" in name for name in ax_names(page))
    page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.tagName") != "CANVAS"


def test_a_finger_draws_a_3d_demonstration_on_a_phone(browser, voila_server, artifacts):
    context, page = touch_context(browser, 390, 844)
    try:
        widget = reference()
        open_page(page, voila_server, widget)
        canvas = page.locator("canvas").nth(ROBOT)
        canvas.scroll_into_view_if_needed()
        box = canvas.bounding_box()
        assert box["width"] >= 0.9 * 390 - 40, box  # the canvas fills the phone's width
        page.screenshot(path=artifacts("phone-opened"))
        top_end = widget.tool_pixel("top") + (50.0, -40.0)
        side_end = widget.tool_pixel("side") + (-30.0, -40.0)
        for view, end in (("top", top_end), ("side", side_end)):
            start = to_page(page, ROBOT, *widget.tool_pixel(view))
            finish = tuple(float(round(v)) for v in to_page(page, ROBOT, *end))
            touch_drag(page, start, finish)
            wait_for_status(page, "s.pending !== null")
        scale = box["width"] / (2 * widget.panel_size)  # CSS px per canvas px: whole CSS pixels are coarser
        tolerance = 1.5 / scale / widget.panel("top").scale / widget.action_length
        expected = expected_action(widget, top_end, side_end)
        wait_pending(page, expected, tolerance)
        page.screenshot(path=artifacts("phone-drawn"))
        page.get_by_role("button", name="Confirm").click()
        state = wait_for_status(page, "s.demos.length == 1 && s.guidance")
        np.testing.assert_allclose(state["demos"][0], expected, atol=tolerance)
        assert state["methods"] == ["pointer"]
        canvas.scroll_into_view_if_needed()
        page.screenshot(path=artifacts("phone-guidance"))
    finally:
        context.close()


def test_the_reproduction_plays_in_all_three_views_and_ends_on_the_last_frame(browser, voila_server, page, artifacts):
    widget = reference()
    for action in widget.episode.optimal_actions:
        widget.set_action(action)
        widget.confirm()
        widget.advance()
    trajectory = widget.episode.reproduction
    final_tool = widget.skill.plant.sketch(trajectory.states[-1:]).chain[0, -1]
    open_page(page, voila_server, reference())
    page.get_by_role("button", name="test: finish with optimal").click()
    wait_for_status(page, "s.demos.length == 4 && !s.guidance", timeout=30_000)
    # Where the tool ends, in each view: the final frame (yellow hand) over the tool's path (sky-blue).
    for view in ("top", "side", "perspective"):
        wait_for_color(page, ROBOT, *widget.panel(view).pixels(final_tool), OKABE["yellow"],
                       timeout=1000 * (float(trajectory.times[-1]) + 30.0))
    assert page.get_by_text("replays what it learnt").count() >= 1
    page.screenshot(path=artifacts("played"))


def test_in_jupyterlab_a_drag_and_keys_draw_the_3d_arrow_and_a_reload_redraws_it(lab_page, lab_server, artifacts):
    page, widget = lab_page, reference()
    page.goto(lab_server.url(f"/lab/tree/space_teaching.ipynb?reset&token={lab_server.token}"), timeout=60_000)
    page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.get_by_text("Run All Cells", exact=True).click()
    page.wait_for_selector("canvas", timeout=60_000)
    for view in ("top", "side", "perspective"):
        wait_for_color(page, ROBOT, *widget.tool_pixel(view), OKABE["yellow"], timeout=60_000)
    page.locator("canvas").first.scroll_into_view_if_needed()
    top_end = widget.tool_pixel("top") + (45.0, 25.0)
    drag(page, ROBOT, widget.tool_pixel("top"), top_end)
    # Then the keyboard (the canvas has the focus after the drag): z up two steps; Lab must not take the keys.
    page.keyboard.press("z")
    page.keyboard.press("ArrowUp")
    page.keyboard.press("ArrowUp")
    span = float(np.max(widget.drawing.bounds.high - widget.drawing.bounds.low))
    step = 0.02 * span / widget.action_length
    scale = widget.panel("top").scale * widget.action_length
    tolerance = 1.5 / scale
    expected = [45.0 / scale, -25.0 / scale, 2 * step]
    wait_pending(page, expected, tolerance)
    tip = widget.panel("top").pixels(widget._tool() + widget.action_length * np.array(expected))
    wait_for_color(page, ROBOT, *tip, OKABE["blue"], radius=4)
    page.screenshot(path=artifacts("lab-drawn"))
    # Save and reload with the kernel running: the canvas draws again (ipycanvas issue #322).
    page.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
    page.get_by_text("Save Notebook", exact=True).first.click()
    page.wait_for_function("() => !document.querySelector('.jp-mod-dirty')", timeout=10_000)
    page.reload()
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, ROBOT, *tip, OKABE["blue"], radius=4)
    wait_for_color(page, ROBOT, *widget.tool_pixel("side"), OKABE["yellow"])
    page.screenshot(path=artifacts("lab-reloaded"))
