"""A 3-D episode (the one ``EpisodeWidget`` on the UR5) reloaded mid-way in JupyterLab restores, as a planar one does.

The page (pages/space_episode.ipynb) shows ``EpisodeWidget("ur5-reach")``, a STATUS label and a button
giving two demonstrations. After a reload with the kernel still running, the live widget's views attach
again and must draw the third state with its words (mt_widgets/widgets/redraw.py: ipycanvas #322).
Expected pixels come from the same widget built here, restored to two demonstrations, without a kernel.
"""

import numpy as np
import pytest

from .helpers import OKABE, wait_for_color, wait_for_status

pytestmark = pytest.mark.browser

#: The page's one <canvas>: ipycanvas 0.14 composes a MultiCanvas's layers into one element.
ROBOT = 0
VIEWS = ("top", "side", "perspective")


def test_a_3d_episode_reloaded_mid_way_draws_the_state_it_had_reached(lab_page, lab_server, artifacts):
    from mt_widgets.widgets import EpisodeWidget
    page = lab_page
    fresh = EpisodeWidget("ur5-reach", seed=0, guidance=True)
    reached = EpisodeWidget("ur5-reach", seed=0, guidance=True, demonstrations=fresh.optimal[:2])
    page.goto(lab_server.url(f"/lab/tree/space_episode.ipynb?reset&token={lab_server.token}"), timeout=60_000)
    page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
    page.get_by_text("Run All Cells", exact=True).click()
    page.wait_for_selector("canvas", timeout=60_000)
    page.locator("canvas").first.scroll_into_view_if_needed()
    for view in VIEWS:
        wait_for_color(page, ROBOT, *fresh.teaching.tool_pixel(view), OKABE["yellow"], timeout=30_000)

    page.get_by_role("button", name="test: two demonstrations").click()
    state = wait_for_status(page, "s.state == 2 && s.phase == 'teaching'", timeout=30_000)
    # Logged before it was counted, each with the episode's index (the class progress reads it).
    assert state["logged"] == [[0, 2], [1, 2]]
    np.testing.assert_allclose(state["demos"], fresh.optimal[:2], atol=1e-12)
    tools = {view: reached.teaching.tool_pixel(view) for view in VIEWS}
    moved = [view for view in VIEWS if np.hypot(*(tools[view] - fresh.teaching.tool_pixel(view))) > 12]
    assert moved, "the third state's tool must be elsewhere than the first's for the check to mean anything"
    for view in VIEWS:
        wait_for_color(page, ROBOT, *tools[view], OKABE["yellow"])
    page.screenshot(path=artifacts("two-given"))

    # Save (the outputs carry the widget views) and reload: the live kernel's episode draws again.
    page.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
    page.get_by_text("Save Notebook", exact=True).first.click()
    page.wait_for_function("() => !document.querySelector('.jp-mod-dirty')", timeout=10_000)
    page.reload()
    page.wait_for_selector("canvas", timeout=60_000)
    page.locator("canvas").first.scroll_into_view_if_needed()
    for view in VIEWS:
        wait_for_color(page, ROBOT, *tools[view], OKABE["yellow"], timeout=30_000)
    # Where the first state's tool was (and nothing else is drawn), the reloaded page shows no hand.
    for view in moved:
        x, y = fresh.teaching.tool_pixel(view)
        color = page.evaluate("""([x, y]) => Array.from(document.querySelectorAll('canvas')[0].getContext('2d')
                                    .getImageData(Math.round(x), Math.round(y), 1, 1).data).slice(0, 3)""", [x, y])
        assert np.abs(np.array(color) - OKABE["yellow"]).sum() > 60, (view, color)
    state = wait_for_status(page, "s.state == 2 && s.demos.length == 2")
    assert state["phase"] == "teaching"
    # Its words too: the canvas's accessible name says the third state of four.
    page.wait_for_function("() => document.querySelector('canvas').getAttribute('aria-label')"
                           "?.includes('State 3 of 4')", timeout=15_000)
    page.screenshot(path=artifacts("reloaded"))
    page.locator("canvas").first.screenshot(path=artifacts("reloaded-canvas"))
