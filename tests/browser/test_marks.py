"""What the canvas shows, checked on pixels in Chromium (issue 10: bug 6, the legend, the arrows).

- the legend under the canvas names every mark, in the words and colours drawn;
- the velocity arrow is green, clearly apart from the user's blue arrow;
- an optimal arrow aligned with the user's and shorter stays visible (drawn over it, outlined);
- during the reproduction the arm's base and elbow are drawn in every frame (bug 6).
Screenshots go to test-artifacts/ and the layout ones at three screen sizes are looked at.
"""

import numpy as np
import pytest

from browser_support import local_page

from .helpers import OKABE, drag, draw_arrow_pair_offset, ee_pixel, reference_episode, wait_for_color, wait_for_status

pytestmark = pytest.mark.browser

GREEN = (0, 158, 115)          # Okabe-Ito bluish green: the velocity arrow
ARM = (77, 77, 77)             # the theme's arm grey: links and base


def open_page(page, voila_server, name: str = "episode_sim.ipynb"):
    page.goto(voila_server.url(f"/voila/render/{name}"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)


def pixel(page, index: int, x: float, y: float):
    return page.locator("canvas").nth(index).evaluate(
        "(c, [x, y]) => Array.from(c.getContext('2d').getImageData(Math.round(x), Math.round(y), 1, 1).data)",
        [float(x), float(y)])


def test_the_legend_names_every_mark_and_the_arrows_stay_apart(page, voila_server, artifacts):
    reference = reference_episode()
    view = reference.teaching.view
    open_page(page, voila_server)
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["yellow"])
    legend = page.locator(".mt-canvas-legend").first
    text = legend.inner_text()
    for words in ("goal: the red-orange point to reach", "the robot's fixed base", "the robot's hand (the yellow dot)",
                  "its velocity (green arrow)", "your action (solid)"):
        assert words in text, (words, text)
    # The target is drawn in the colour its words name (red-orange: Okabe-Ito vermillion).
    wait_for_color(page, 0, *view.transform.to_pixel(reference.skill.target.point), OKABE["vermillion"], tolerance=25)

    # The velocity arrow: green on the canvas, far from the user's blue.
    origin, velocity = reference.skill.end_effector(reference.query_states[:1])
    tip = view.transform.to_pixel(origin[0] + view.painter.velocity_length * velocity[0])
    head = tip - 3 * (tip - ee) / np.hypot(*(tip - ee))
    wait_for_color(page, 0, *head, GREEN, tolerance=30, radius=1)
    # Every entry of the legend is inside the page's width and fully shown (no clipped words).
    clipped = legend.evaluate("l => Array.from(l.querySelectorAll('.mt-legend-entry')).filter("
                              "e => e.scrollWidth > e.clientWidth + 1).length")
    assert clipped == 0
    page.screenshot(path=artifacts("legend"))

    # The user's arrow along the optimal one, 1.6 times as long: the optimal arrow is the
    # shorter one, yet its head stays visible in its own colour over the user's arrow.
    optimal_tip = view.transform.action_tip(origin[0], reference.optimal[0])
    drag(page, 0, ee, ee + 1.6 * (optimal_tip - ee))
    wait_for_status(page, "s.pending !== null")
    page.get_by_role("button", name="Confirm").click()
    wait_for_status(page, "s.phase === 'guidance'")
    # Aligned, the two are drawn side by side: the optimal one moved a few pixels to its left.
    along = (optimal_tip - ee) / np.hypot(*(optimal_tip - ee))
    side = np.array([along[1], -along[0]]) * draw_arrow_pair_offset(view.theme)
    wait_for_color(page, 0, *(optimal_tip + side - 5 * along), OKABE["orange"], tolerance=30, radius=1)
    # ... while the user's arrow shows beside it all along, and beyond its tip.
    for fraction in (0.4, 0.8):
        wait_for_color(page, 0, *(ee + fraction * (optimal_tip - ee)), OKABE["blue"], tolerance=30, radius=1)
    wait_for_color(page, 0, *(optimal_tip + 25 * along), OKABE["blue"], tolerance=30, radius=1)
    assert "optimal action (dashed)" in legend.inner_text()
    page.screenshot(path=artifacts("aligned"))


def test_every_reproduction_frame_draws_the_base_and_the_elbow_issue_10_bug_6(page, voila_server, artifacts):
    reference = reference_episode()
    open_page(page, voila_server)
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["yellow"])
    for action in reference.optimal:
        reference.demonstrate(action)
        reference.next()
    player = reference.player.view
    base = player.transform.to_pixel([0.0, 0.0])
    upper_arm = reference.skill.plant.arm.link_lengths[0] * player.transform.pixels_per_unit
    final = player.transform.to_pixel(reference.result.trajectory.positions[-1])
    page.get_by_role("button", name="test: finish with optimal").click()
    # A frame while the arm moves (its hand not yet at the last position): the base block is
    # there, and on the circle the elbow moves on there is the elbow's pin (light) at the end
    # of the upper arm's grey link.
    page.wait_for_function(
        """([base, r, fin, arm]) => {
            const c = document.querySelectorAll('canvas')[1];
            const ctx = c.getContext('2d');
            const px = (x, y) => ctx.getImageData(Math.round(x), Math.round(y), 1, 1).data;
            const near = (d, rgb, tol) => Math.abs(d[0] - rgb[0]) <= tol && Math.abs(d[1] - rgb[1]) <= tol
                                          && Math.abs(d[2] - rgb[2]) <= tol;
            const hand = px(fin[0], fin[1]);
            if (near(hand, [240, 228, 66], 40)) return false;              // the last frame: too late
            if (!near(px(base[0] - 9, base[1] + 9), arm, 25)) return false;  // the base block
            for (let a = 0; a < 360; a += 0.5) {
                const ux = Math.cos(a * Math.PI / 180), uy = -Math.sin(a * Math.PI / 180);
                const x = base[0] + r * ux, y = base[1] + r * uy;
                const pin = px(x, y), link = px(x - 6 * ux, y - 6 * uy);
                if (pin[0] > 200 && pin[1] > 200 && pin[2] > 200 && near(link, arm, 25)) return true;
            }
            return false;
        }""", arg=[base.tolist(), float(upper_arm), final.tolist(), list(ARM)], timeout=20_000, polling=30)
    page.screenshot(path=artifacts("mid-frame"))
    wait_for_color(page, 1, *final, OKABE["yellow"], timeout=20_000)


@pytest.mark.parametrize("width, height", [(1920, 1080), (1366, 768), (768, 1024)])
def test_demo_page_layout_screenshots(browser, voila_server, artifacts, width, height):
    """The demo page at a desktop, a laptop and a tablet size, in guidance, for people to look at."""
    context, page = local_page(browser, width, height)
    try:
        page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
        page.wait_for_selector("canvas", timeout=60_000)
        from mt_widgets.widgets import DemoPage
        reference = DemoPage().episode
        view = reference.teaching.view
        ee = ee_pixel(reference)
        page.locator("canvas").first.scroll_into_view_if_needed()
        wait_for_color(page, 0, *ee, OKABE["yellow"])
        legend = page.locator(".mt-canvas-legend").first
        assert legend.is_visible() and "goal: the red-orange point" in legend.inner_text()
        page.screenshot(path=artifacts("opened"))
        origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
        drag(page, 0, ee, view.transform.action_tip(origin, 0.7 * reference.optimal[0]))
        page.get_by_role("button", name="Confirm").click()
        page.get_by_role("button", name="Next state").wait_for(timeout=10_000)
        tip = view.transform.action_tip(origin, reference.optimal[0])
        along = (tip - ee) / np.hypot(*(tip - ee))
        side = np.array([along[1], -along[0]]) * draw_arrow_pair_offset(view.theme)     # aligned: beside
        wait_for_color(page, 0, *(tip + side - 5 * along), OKABE["orange"], radius=1, tolerance=30)
        wait_for_color(page, 0, *(ee + 0.5 * (tip - ee)), OKABE["blue"], radius=1, tolerance=30)
        # Everything of the canvas fits the screen's width (no sideways scrolling to see it).
        box = page.locator("canvas").first.bounding_box()
        assert box["x"] >= 0 and box["x"] + box["width"] <= width + 1, box
        page.screenshot(path=artifacts("guidance"))
    finally:
        context.close()
