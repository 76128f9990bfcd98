"""The visitors' demo (notebooks/demo.ipynb, what the kiosk serves) in Voila: the visitor picks the UR5,
back to the planar arms and the UR5 again without waiting, gets the 3-D canvas once, draws an arrow in
its top view and confirms it; then the planar arm comes back on its own canvas."""

import numpy as np
import pytest

from .helpers import OKABE, drag, ee_pixel, wait_for_color

pytestmark = pytest.mark.browser

UR5, PLANAR = "UR5 arm (3-D)", "Planar arms"


def references():
    """The page's first UR5 and planar episodes, built without a kernel (same defaults as the page)."""
    from mt_widgets.widgets import DemoPage
    page = DemoPage()
    planar = page.episode
    page.arm_chooser.value = UR5
    return planar, page.episode


def canvases(page, count, timeout=60_000):
    page.wait_for_function("n => document.querySelectorAll('canvas').length === n", arg=count, timeout=timeout)


def test_the_visitor_switches_arms_twice_quickly_and_teaches_the_ur5_in_3d(page, voila_server, artifacts):
    planar, ur5 = references()
    page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee_pixel(planar), OKABE["yellow"])
    for label in (UR5, PLANAR):
        assert page.get_by_role("button", name=label, exact=True).count() == 1, label

    # Twice, quickly: each click goes out without waiting for the page to answer the last.
    for label in (UR5, PLANAR, UR5):
        page.get_by_role("button", name=label, exact=True).click()
    canvases(page, 1)   # one 3-D canvas (ipycanvas composes its layers), the planar ones gone
    canvas = ur5.teaching   # the one EpisodeWidget renders the UR5 with its 3-D canvas
    for view in ("top", "side", "perspective"):
        wait_for_color(page, 0, *canvas.tool_pixel(view), OKABE["yellow"], timeout=30_000)
    for label in ("UR5: reach the part", "UR5: place it", "UR5: follow the conveyor"):
        assert page.get_by_role("button", name=label, exact=True).count() == 1, label
    assert page.get_by_role("button", name="Arm: reach a point", exact=True).count() == 0
    page.get_by_text("Teaching effort: 0 of 4 demonstrations").wait_for(timeout=10_000)
    page.screenshot(path=artifacts("ur5"))

    # A drag in the top view sets the horizontal components; Confirm records it, guidance shows.
    start = canvas.tool_pixel("top")
    drag(page, 0, start, start + np.array([40.0, -30.0]))
    confirm = page.get_by_role("button", name="Confirm")
    page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(timeout=10_000), timeout=20_000)
    confirm.click()
    page.get_by_text("Teaching effort: 1 of 4 demonstrations").wait_for(timeout=20_000)
    page.get_by_text("The optimal arrow (dashed)").first.wait_for(timeout=20_000)
    page.screenshot(path=artifacts("ur5-guidance"))

    # Back to the planar arms: its teaching and reproduction canvases, the hand where it was.
    page.get_by_role("button", name=PLANAR, exact=True).click()
    canvases(page, 2)
    wait_for_color(page, 0, *ee_pixel(planar), OKABE["yellow"], timeout=30_000)
    page.get_by_text("Teaching effort: 0 of 5 demonstrations").wait_for(timeout=10_000)
    page.screenshot(path=artifacts("planar-again"))
