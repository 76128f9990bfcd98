"""The visitors' demo (notebooks/demo.ipynb) in Voila: no code, a drawn canvas, a real drag, a skill switch."""

import numpy as np
import pytest

from .helpers import OKABE, drag, ee_pixel, to_canvas, wait_for_color

pytestmark = pytest.mark.browser


def reference_demo(skill: str = "sim-point"):
    """The demo page's episode for ``skill``, built without a kernel (same defaults as the page)."""
    from mt_widgets.widgets import DemoPage
    return DemoPage(skill=skill).episode


def test_demo_page_shows_no_code_draws_takes_a_drag_and_redraws_for_another_skill(page, voila_server, artifacts):
    page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    reference = reference_demo()
    view = reference.teaching.view
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["yellow"])
    wait_for_color(page, 0, *view.transform.to_pixel(reference.skill.target.point), OKABE["vermillion"])
    page.screenshot(path=artifacts("opened"))

    # No code: no input areas, and none of the notebook's source text on the page.
    text = page.locator("body").inner_text()
    assert page.locator(".jp-InputArea, .jp-CodeMirrorEditor, .CodeMirror, pre").count() == 0
    assert "DemoPage" not in text and "import" not in text
    assert "Teach a robot by showing it what to do" in text
    for label in ("Arm: reach a point", "Arm: reach a line", "uArm: reach a point", "uArm: reach a line"):
        assert page.get_by_role("button", name=label, exact=True).count() == 1, label

    end = drag(page, 0, ee, (ee[0] - 60, ee[1] - 50))
    origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
    expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
    # The readout gives the released arrow in newtons; it is what the visitor reads.
    page.get_by_text(f"({expected[0]:+.2f}, {expected[1]:+.2f}) N").wait_for(timeout=10_000)
    page.get_by_role("button", name="Confirm").click()
    page.get_by_text("Teaching effort: 1 of 5 demonstrations").wait_for(timeout=10_000)
    page.get_by_role("button", name="Next state").wait_for(timeout=10_000)          # guidance is on
    tip = view.transform.action_tip(origin, reference.optimal[0])
    base = view.transform.to_pixel(origin)
    wait_for_color(page, 0, *(tip - 6 * (tip - base) / np.hypot(*(tip - base))), OKABE["orange"], radius=1)
    page.screenshot(path=artifacts("guidance"))

    # Another skill: a fresh episode, the uArm's top view with its black dot and target.
    page.get_by_role("button", name="uArm: reach a point", exact=True).click()
    uarm = reference_demo("uarm-point")
    uarm_view = uarm.teaching.view
    wait_for_color(page, 0, *ee_pixel(uarm), OKABE["black"], tolerance=20)
    wait_for_color(page, 0, *uarm_view.transform.to_pixel(uarm.skill.target.point), OKABE["vermillion"])
    page.get_by_text("Teaching effort: 0 of 3 demonstrations").wait_for(timeout=10_000)
    assert page.locator("canvas").nth(0).evaluate("c => [c.width, c.height]") == [uarm_view.transform.width,
                                                                                   uarm_view.transform.height]
    page.screenshot(path=artifacts("uarm"))
