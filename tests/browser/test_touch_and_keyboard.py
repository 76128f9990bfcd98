"""The demo page for a finger, the keyboard and a screen reader (notebooks/demo.ipynb in Voila).

A finger draws an arrow from the robot's hand as the mouse does, on a tablet and on a phone; a
swipe that starts elsewhere on the canvas scrolls the page (canvas_access.py says why ipycanvas
alone would block it). Tab reaches the canvas and leaves it again, every control on the way has a
visible focus, Enter confirms and goes on, and the accessibility tree holds the canvas's words.
"""

import numpy as np
import pytest

from .helpers import OKABE, ax_names, ee_pixel, to_canvas, to_page, touch_context, touch_drag, wait_for_color

pytestmark = pytest.mark.browser

TOUCH_SCREENS = {"tablet": (768, 1024), "phone": (390, 844)}
#: The canvas's scrolling box (Voila's page scrolls a div, not the window): its scrollTop and
#: whether its content is taller than it.
SCROLLER = """() => { let e = document.querySelector('canvas');
    while (e && !(e.scrollHeight > e.clientHeight && /(auto|scroll)/.test(getComputedStyle(e).overflowY))) {
        e = e.parentElement; }
    e = e || document.scrollingElement;
    return [e.scrollTop, e.scrollHeight > e.clientHeight + 100]; }"""


def reference_demo(skill: str = "sim-point"):
    from mt_widgets.widgets import DemoPage
    return DemoPage(skill=skill).episode


def open_demo(page, voila_server, reference):
    page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["yellow"], timeout=60_000)


@pytest.mark.parametrize("screen", TOUCH_SCREENS)
def test_a_finger_draws_from_the_hand_and_a_swipe_elsewhere_scrolls(browser, voila_server, artifacts, screen):
    context, page = touch_context(browser, *TOUCH_SCREENS[screen])
    try:
        reference = reference_demo()
        view = reference.teaching.view
        ee = ee_pixel(reference)
        open_demo(page, voila_server, reference)
        canvas = page.locator("canvas").nth(0)
        canvas.scroll_into_view_if_needed()
        page.screenshot(path=artifacts(f"{screen}-opened"))
        box = canvas.bounding_box()
        # On a phone the canvas fills the width (the controls go below it).
        if screen == "phone":
            assert box["width"] >= 0.9 * TOUCH_SCREENS[screen][0], box

        # A swipe up from a corner of the canvas far from the hand: the browser may scroll (no script
        # cancels the touch), and does where the page is taller than the screen (a phone); nothing is drawn.
        page.evaluate("""() => { window.mtTouches = [];
            window.addEventListener('touchstart', e => setTimeout(() => window.mtTouches.push(e.defaultPrevented)),
                                    true); }""")
        far = np.array([view.transform.width, view.transform.height]) - 40
        far = far if np.hypot(*(far - ee)) > 150 else np.array([40.0, 40.0])
        start = to_page(page, 0, *far)
        before, scrollable = page.evaluate(SCROLLER)
        assert scrollable or screen != "phone"
        touch_drag(page, start, (start[0], start[1] - 200))
        page.wait_for_function("() => window.mtTouches.length == 1")
        assert page.evaluate("window.mtTouches") == [False]
        if scrollable:
            page.wait_for_function(f"y => ({SCROLLER})()[0] > y + 50", arg=before, timeout=10_000)
        assert page.get_by_text("your arrow").count() == 0
        page.screenshot(path=artifacts(f"{screen}-swiped"))

        # A finger from the hand draws the arrow; the readout gives what it drew.
        canvas.scroll_into_view_if_needed()
        start = to_page(page, 0, *ee)
        end = to_page(page, 0, ee[0] - 70, ee[1] - 60)
        end = (float(round(end[0])), float(round(end[1])))
        scroll = page.evaluate(SCROLLER)[0]
        touch_drag(page, start, end)
        page.wait_for_function("() => window.mtTouches.length == 2")
        assert page.evaluate("window.mtTouches") == [False, True]        # this touch draws: no scrolling
        origin = reference.skill.end_effector(reference.query_states[:1])[0][0]
        expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
        page.get_by_text(f"your arrow ({expected[0]:+.2f}, {expected[1]:+.2f}) N").wait_for(timeout=10_000)
        assert abs(page.evaluate(SCROLLER)[0] - scroll) < 2      # drawing did not scroll the page
        tip = view.transform.action_tip(origin, expected)
        wait_for_color(page, 0, *(tip + 0.3 * (view.transform.to_pixel(origin) - tip)), OKABE["blue"])
        page.screenshot(path=artifacts(f"{screen}-drawn"))

        # A tap on Confirm records it: the page is usable to the end with a finger.
        page.get_by_role("button", name="Confirm").tap()
        page.get_by_text("Teaching effort: 1 of 5 demonstrations").wait_for(timeout=10_000)
    finally:
        context.close()


def focused(page) -> dict:
    return page.evaluate("""() => { const e = document.activeElement;
        const s = getComputedStyle(e);
        return {tag: e.tagName, text: (e.textContent || '').trim(), label: e.getAttribute('aria-label') || '',
                outline: s.outlineStyle !== 'none' && parseFloat(s.outlineWidth) >= 2}; }""")


def test_tab_moves_through_the_canvas_enter_confirms_and_goes_on_and_the_tree_names_the_canvas(page, voila_server,
                                                                                                artifacts):
    reference = reference_demo()
    open_demo(page, voila_server, reference)
    seen = []
    for _ in range(40):
        page.keyboard.press("Tab")
        now = focused(page)
        seen.append(now)
        if now["tag"] == "CANVAS":
            break
    assert seen[-1]["tag"] == "CANVAS", seen
    assert all(step["outline"] for step in seen), [step for step in seen if not step["outline"]]
    assert seen[-1]["label"].startswith("Teaching canvas, state 1 of 5"), seen[-1]
    page.screenshot(path=artifacts("canvas-focused"))

    # Tab leaves the canvas forward, Shift+Tab comes back to it, and again leaves it backwards.
    page.keyboard.press("Tab")
    assert focused(page)["tag"] != "CANVAS"
    page.keyboard.press("Shift+Tab")
    assert focused(page)["tag"] == "CANVAS"
    page.keyboard.press("Shift+Tab")
    assert focused(page)["tag"] != "CANVAS"
    page.keyboard.press("Tab")
    assert focused(page)["tag"] == "CANVAS"

    # Arrow keys draw, Enter confirms; with guidance on, Enter goes on to the next state.
    page.keyboard.press("ArrowUp")
    page.keyboard.press("ArrowRight")
    step = reference.teaching.view.transform.nice_action_step() / 10.0
    page.get_by_text(f"your arrow ({step:+.2f}, {step:+.2f}) N").wait_for(timeout=10_000)
    names = ax_names(page)
    said = f"Your arrow: {step:.2f} N right and {step:.2f} N up"
    assert any(name.startswith("Teaching canvas, state 1 of 5") and said in name
               for name in names), [n for n in names if "canvas" in n.lower()]
    page.keyboard.press("Enter")
    page.get_by_role("button", name="Next state").wait_for(timeout=10_000)
    # The guidance reaches the screen reader too: the best arrow and the words.
    page.wait_for_function("() => (document.activeElement.getAttribute('aria-label') || '').includes('The best arrow')")
    label = focused(page)["label"]
    assert "Direction" in label and "Enter goes on" in label, label
    page.screenshot(path=artifacts("guidance-by-keyboard"))
    page.keyboard.press("Enter")
    page.wait_for_function("() => (document.activeElement.getAttribute('aria-label') || '')"
                           ".startsWith('Teaching canvas, state 2 of 5')")
    page.get_by_text("Teaching effort: 1 of 5 demonstrations").wait_for(timeout=10_000)

    # Space presses a focused button: Tab on to "Set arrow" after typing numbers.
    page.get_by_role("button", name="Set arrow").focus()
    assert focused(page)["outline"]
    page.keyboard.press(" ")
    page.get_by_text("your arrow (+0.00, +0.00) N").wait_for(timeout=10_000)
