"""A visitor on a phone picks the Franka Panda on the demo page (notebooks/demo.ipynb in Voila) and draws
a demonstration with a finger: the seven-joint arm, read from its URDF at run time, is taught in 3-D by
the same episode widget as every other arm.

Expected pixels come from the same page built here without a kernel.
"""

import numpy as np
import pytest

from .helpers import OKABE, ee_pixel, to_page, touch_context, touch_drag, wait_for_color

pytestmark = pytest.mark.browser

PANDA = "Franka Panda (3-D)"
PHONE = (390, 844)


def references():
    """The page's first planar episode and its first Panda episode, built without a kernel."""
    from mt_widgets.widgets import DemoPage
    page = DemoPage()
    planar = page.episode
    page.arm_chooser.value = PANDA
    return planar, page.episode


def test_a_finger_on_a_phone_draws_a_panda_demonstration_and_the_guidance_answers(browser, voila_server, artifacts):
    planar, panda = references()
    canvas = panda.teaching
    budget = len(canvas.controller.episode.query_states)
    context, page = touch_context(browser, *PHONE)
    try:
        page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
        page.wait_for_selector("canvas", timeout=60_000)
        wait_for_color(page, 0, *ee_pixel(planar), OKABE["yellow"], timeout=60_000)
        page.get_by_role("button", name=PANDA, exact=True).tap()
        page.wait_for_function("() => document.querySelectorAll('canvas').length === 1", timeout=60_000)
        for view in ("top", "side", "perspective"):
            wait_for_color(page, 0, *canvas.tool_pixel(view), OKABE["yellow"], timeout=30_000)
        page.get_by_text(f"Teaching effort: 0 of {budget} demonstrations").wait_for(timeout=10_000)
        element = page.locator("canvas").first
        element.scroll_into_view_if_needed()
        box = element.bounding_box()
        assert box["width"] >= 0.9 * PHONE[0] - 40, box   # the 3-D canvas fills the phone's width
        page.screenshot(path=artifacts("panda-opened"))

        # A finger from the hand in the top view: the arrow's horizontal part, drawn in the user's colour.
        start = canvas.tool_pixel("top")
        end = start + np.array([45.0, -35.0])
        touch_drag(page, to_page(page, 0, *start), tuple(float(round(v)) for v in to_page(page, 0, *end)))
        tip = start + 0.8 * (end - start)
        wait_for_color(page, 0, *tip, OKABE["blue"], radius=3, timeout=20_000)
        page.screenshot(path=artifacts("panda-drawn"))
        confirm = page.get_by_role("button", name="Confirm")
        page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(timeout=10_000), timeout=20_000)
        confirm.tap()
        page.get_by_text(f"Teaching effort: 1 of {budget} demonstrations").wait_for(timeout=20_000)
        page.get_by_text("The optimal arrow (dashed)").first.wait_for(timeout=20_000)
        element.scroll_into_view_if_needed()
        page.screenshot(path=artifacts("panda-guidance"))
    finally:
        context.close()
