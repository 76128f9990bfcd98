"""The payoff in view: after "Finish and watch" the reproduction, the result and the next action
are on screen where the visitor is looking, on a large screen, a laptop and a tablet."""

import pytest

from .helpers import OKABE, demo_at, teach_by_numbers, wait_for_color

pytestmark = pytest.mark.browser


def _in_view(page, locator, fraction: float = 1.0) -> float:
    """The share of ``locator``'s box inside the viewport (asserted >= ``fraction``)."""
    box = locator.bounding_box()
    assert box is not None, f"{locator} is not shown"
    size = page.viewport_size
    visible_w = max(0.0, min(box["x"] + box["width"], size["width"]) - max(box["x"], 0.0))
    visible_h = max(0.0, min(box["y"] + box["height"], size["height"]) - max(box["y"], 0.0))
    share = visible_w * visible_h / (box["width"] * box["height"])
    assert share >= fraction, f"{locator}: only {share:.0%} of {box} is inside the {size} viewport"
    return share


@pytest.mark.parametrize("width, height, canvas_share", [(1400, 1000, 1.0), (1920, 1080, 1.0), (1366, 768, 0.9),
                                                         (768, 1024, 0.9)])
def test_after_finish_and_watch_the_reproduction_the_result_and_try_again_are_in_view(
        browser, voila_server, artifacts, width, height, canvas_share):
    with demo_at(browser, voila_server, width, height) as (page, episode):
        teaching = page.locator("canvas").nth(0)
        box = teaching.bounding_box()
        assert box["width"] >= 300, f"the teaching canvas is only {box['width']:.0f} px wide"
        page.screenshot(path=artifacts(f"{width}x{height}-teaching"))
        teach_by_numbers(page, episode, guidance=True)   # ends with "Finish and watch"
        player = page.locator("canvas").nth(1)
        page.wait_for_timeout(1500)     # mid-reproduction: where is everything now?
        page.screenshot(path=artifacts(f"{width}x{height}-finished"))
        _in_view(page, player, canvas_share)
        _in_view(page, page.get_by_text("Your teaching error"))
        _in_view(page, page.get_by_role("button", name="Try again with new states"))
        _in_view(page, page.get_by_role("button", name="Replay"), 0.99 if width > height else 0.0)
        # The reproduction plays where the teaching canvas was, at the same size.
        played = player.bounding_box()
        assert abs(played["x"] - box["x"]) < 2 and abs(played["width"] - box["width"]) < 2
        assert page.locator("canvas").nth(0).is_hidden()
        final = episode.player.view.transform.to_pixel(episode.skill.target.point)
        wait_for_color(page, 1, *final, OKABE["vermillion"])
