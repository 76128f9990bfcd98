"""Every arm's and every skill's button on the demo page (notebooks/demo.ipynb in Voila) shows its whole
label, on a desktop and on a phone: a visitor reads "UR5: follow the conveyor", not "UR5: follow the con…"."""

import pytest

from browser_support import local_page

from .helpers import OKABE, ee_pixel, touch_context, wait_for_color

pytestmark = pytest.mark.browser

SCREENS = {"desktop": (1280, 900), "phone": (390, 844)}

#: The toggle buttons whose text the browser cuts (its content wider than the box), by label.
CUT_LABELS = """() => [...document.querySelectorAll('.widget-toggle-button')]
    .filter(b => b.offsetParent !== null && b.scrollWidth > b.clientWidth + 1).map(b => b.innerText)"""


def arms():
    from mt_widgets.widgets import DemoPage
    page = DemoPage()
    return page.episode, list(page.arms)


@pytest.mark.parametrize("screen", SCREENS)
def test_no_arm_or_skill_label_is_cut(browser, voila_server, artifacts, screen):
    planar, labels = arms()
    context, page = (touch_context if screen == "phone" else local_page)(browser, *SCREENS[screen])
    try:
        page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
        page.wait_for_selector("canvas", timeout=60_000)
        wait_for_color(page, 0, *ee_pixel(planar), OKABE["yellow"], timeout=60_000)
        cut = {}
        for label in labels:
            page.get_by_role("button", name=label, exact=True).click()
            # The arm's skills are shown: their buttons are the ones after the arms'.
            page.wait_for_function("n => document.querySelectorAll('.widget-toggle-button').length > n",
                                   arg=len(labels), timeout=30_000)
            page.wait_for_timeout(300)   # the new buttons laid out
            cut[label] = page.evaluate(CUT_LABELS)
        page.screenshot(path=artifacts(f"{screen}-last-arm"))
        assert not any(cut.values()), f"labels cut on the {screen}: {cut}"
    finally:
        context.close()
