"""A lagging browser (a phone, a loaded machine) while the demo's view is replaced mid-reproduction.

The kernel closes a replaced view's canvases only once the page answers a receipt queued behind
everything sent to them (``mt_widgets/widgets/receipt.py``). A close decided on the kernel's own
estimate of playback reaches a browser that lags behind it before the commands for those canvases
have run: ipycanvas' one command chain then fails ("widget model not found") and stops drawing for
every canvas of the page. Here the browser's CPU is slowed 20 times (Chrome DevTools Protocol) while
another skill replaces the episode whose reproduction is playing.

The page's traffic is read from its kernel websocket: the receipt canvas' picture sent back
(``image_data``) and the kernel's ``comm_close`` messages, the retired widgets being closed.
"""

import time

import pytest

from .helpers import (
    OKABE,
    ee_pixel,
    mark_canvases,
    model_errors,
    open_demo,
    reference,
    set_guidance,
    teach_by_numbers,
    wait_for_color,
    wait_for_new_canvases,
    watch_kernel_traffic,
)

pytestmark = pytest.mark.browser

#: How many times slower the browser's CPU runs while the view is replaced.
CPU_SLOWDOWN = 20
#: Seconds within which the retired widgets must be closed once the page has caught up: well
#: before the close that comes without any answer from the page (``animation.CLOSE_FALLBACK_S``, 60 s).
CLOSED_WITHIN_S = 20.0


def closes_after(log, since: float) -> int:
    return sum(1 for at, direction, data in log
               if at >= since and direction == "received" and b'"comm_close"' in data)


def receipts_after(log, since: float) -> int:
    """Pictures the page sent back to the kernel (only the receipt canvas syncs its image data)."""
    return sum(1 for at, direction, data in log
               if at >= since and direction == "sent" and b'"image_data"' in data)


def test_a_lagging_browser_draws_the_new_view_and_the_retired_one_is_closed_after_its_receipt(
        page, voila_server, artifacts):
    console, traffic = [], []
    watch_kernel_traffic(page, traffic)
    open_demo(page, voila_server, console)
    mark_canvases(page)
    set_guidance(page, False)
    wait_for_new_canvases(page)
    episode = reference(guidance=False)
    wait_for_color(page, 0, *ee_pixel(episode), OKABE["yellow"])
    teach_by_numbers(page, episode, guidance=False)   # the last confirm starts the 10 s reproduction

    cdp = page.context.new_cdp_session(page)
    cdp.send("Emulation.setCPUThrottlingRate", {"rate": CPU_SLOWDOWN})
    time.sleep(1.0)   # the reproduction plays in a slow browser
    mark_canvases(page)
    replaced = time.monotonic()
    page.get_by_role("button", name="Arm: reach a line", exact=True).click()
    time.sleep(3.0)   # the kernel's estimate of playback (plus its 2 s margin) passes; the page lags
    page.screenshot(path=artifacts("lagging"))
    cdp.send("Emulation.setCPUThrottlingRate", {"rate": 1})

    new = reference("sim-line", guidance=False)
    wait_for_new_canvases(page)
    start = new.player.view.transform.to_pixel(new.skill.end_effector(new.skill.start[None])[0][0])
    try:
        wait_for_color(page, 0, *ee_pixel(new), OKABE["yellow"])
        wait_for_color(page, 1, *start, OKABE["yellow"])
    except Exception:
        page.screenshot(path=artifacts("not-drawn"))
        raise AssertionError(f"the new episode's canvases were not drawn once the browser caught up; "
                             f"the console's model errors: {model_errors(console)}") from None
    page.screenshot(path=artifacts("after"))

    # The old episode's widgets (its two canvases among them) are closed once the page answered.
    deadline = replaced + CLOSED_WITHIN_S
    while closes_after(traffic, replaced) < 2 and time.monotonic() < deadline:
        page.wait_for_timeout(200)   # Playwright delivers the websocket events meanwhile
    closed, answered = closes_after(traffic, replaced), receipts_after(traffic, replaced)
    firsts = {kind: min((at - replaced for at, direction, data in traffic if at >= replaced and direction == way
                         and marker in data), default=None)
              for kind, way, marker in [("receipt", "sent", b'"image_data"'), ("close", "received", b'"comm_close"')]}
    seen = (f"after the replacement: first receipt answered at {firsts['receipt']} s, first close at "
            f"{firsts['close']} s; {answered} receipts, {closed} closes")
    assert answered >= 1, f"the page sent no receipt (image_data) back after the view was replaced: {seen}"
    assert closed >= 2, f"the retired widgets were not closed within {CLOSED_WITHIN_S} s: {seen}"
    # Nothing of the old view is closed before the page has said it drew what was queued for it.
    assert firsts["close"] >= firsts["receipt"], seen
    assert not model_errors(console), model_errors(console)
