"""The demo page from a phone to a large monitor: the canvas uses the space, nothing is cut.

Screenshots of each size (teaching and finished) go to test-artifacts/ for a person to look at.
"""

import pytest

from .helpers import OKABE, demo_at, teach_by_numbers, wait_for_color

pytestmark = pytest.mark.browser

SCREENS = [(390, 844), (768, 1024), (1366, 768), (1920, 1080)]

#: Every button and text whose content is wider (or taller) than its box: cut or hidden text.
CUT = """() => Array.from(document.querySelectorAll('button, .widget-label, .widget-html-content'))
    .filter(e => e.offsetParent !== null && !e.closest('.mt-visually-hidden')
                 && (e.scrollWidth > e.clientWidth + 1
                     || (e.tagName === 'BUTTON' && e.scrollHeight > e.clientHeight + 1)))
    .map(e => e.tagName + ': ' + e.textContent.trim().slice(0, 40))"""


@pytest.mark.parametrize("width, height", SCREENS)
def test_the_canvas_uses_the_screen_and_no_label_is_cut(browser, voila_server, artifacts, width, height):
    with demo_at(browser, voila_server, width, height) as (page, episode):
        box = page.locator("canvas").nth(0).bounding_box()
        if width < 600:
            assert box["width"] >= 0.9 * width, box                  # a phone: the whole width
        else:
            # beside the side column, or above it on a tablet, and never less than 300 px
            assert box["width"] >= min(300, width - 40), box
        assert box["x"] >= 0 and box["x"] + box["width"] <= width, box
        assert page.evaluate(CUT) == []
        page.screenshot(path=artifacts("teaching"), full_page=True)
        teach_by_numbers(page, episode, guidance=True)
        wait_for_color(page, 1, *episode.player.view.transform.to_pixel(episode.skill.target.point),
                       OKABE["vermillion"], timeout=30_000)
        page.get_by_text("After ").first.wait_for(timeout=10_000)     # the reproduction's words
        assert page.evaluate(CUT) == []
        replay = page.get_by_role("button", name="Replay")
        assert replay.evaluate("b => b.scrollWidth <= b.clientWidth") and replay.inner_text().strip() == "Replay"
        if width > height:      # a landscape screen: the reproduction's words are on the first screen
            words = page.get_by_text("After ").first.bounding_box()
            assert words["y"] + words["height"] <= height, words
        page.screenshot(path=artifacts("finished"))
