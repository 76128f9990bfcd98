"""One notebook open in two JupyterLab tabs on one kernel: replacing a view in one tab closes nothing the
other still draws.

Each tab runs its own ipycanvas command chain at its own pace, and each sends its own receipt back
(``mt_widgets/widgets/receipt.py``). The kernel closes a replaced view once EVERY tab has answered: a
close on the fast tab's answer alone reaches the slow tab while its chain still holds commands for the
closed canvases ("widget model not found"), and that tab's drawing stops for good. Here tab B lags (its
CPU slowed 20 times) while tab A replaces the demo's episode mid-reproduction.
"""

import time

import pytest

from browser_support import local_page

from .helpers import (
    OKABE,
    ee_pixel,
    mark_canvases,
    model_errors,
    reference,
    teach_by_numbers,
    wait_for_color,
    wait_for_new_canvases,
    watch_kernel_traffic,
)

pytestmark = pytest.mark.browser

#: Seconds within which the retired widgets must be closed once the slow tab has caught up: well
#: before the close that comes without any answer (``animation.CLOSE_FALLBACK_S``, 60 s).
CLOSED_WITHIN_S = 20.0
#: How many times slower the second tab's CPU runs while the view is replaced.
CPU_SLOWDOWN = 20


def open_in_lab(page, lab_server, console) -> None:
    page.on("console", lambda message: console.append(message.text))
    page.on("pageerror", lambda error: console.append(str(error)))
    page.goto(lab_server.url(f"/lab/tree/demo.ipynb?reset&token={lab_server.token}"), timeout=60_000)
    page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)


def test_two_tabs_on_one_kernel_a_view_replaced_in_one_is_closed_only_once_the_other_has_drawn_it(
        browser, lab_server, artifacts):
    first_context, tab_a = local_page(browser, 1280, 1100)
    second_context, tab_b = local_page(browser, 1280, 1100)
    console_a, console_b, traffic_a, traffic_b = [], [], [], []
    watch_kernel_traffic(tab_a, traffic_a)
    watch_kernel_traffic(tab_b, traffic_b)
    episode = reference(guidance=True)
    try:
        open_in_lab(tab_a, lab_server, console_a)
        tab_a.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click()
        tab_a.get_by_text("Run All Cells", exact=True).click()
        tab_a.wait_for_selector("canvas", timeout=60_000)
        wait_for_color(tab_a, 0, *ee_pixel(episode), OKABE["yellow"], timeout=60_000)
        # Saved, the notebook's output names the live widgets: the second tab shows them from the kernel.
        tab_a.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
        tab_a.get_by_text("Save Notebook", exact=True).first.click()
        tab_a.wait_for_function("() => !document.querySelector('.jp-mod-dirty')", timeout=10_000)
        open_in_lab(tab_b, lab_server, console_b)
        tab_b.wait_for_selector("canvas", timeout=60_000)
        wait_for_color(tab_b, 0, *ee_pixel(episode), OKABE["yellow"], timeout=60_000)

        teach_by_numbers(tab_a, episode, guidance=True)   # the last click starts the 10 s reproduction
        cdp = tab_b.context.new_cdp_session(tab_b)
        cdp.send("Emulation.setCPUThrottlingRate", {"rate": CPU_SLOWDOWN})
        time.sleep(1.0)   # the reproduction plays in both tabs; tab B falls behind
        mark_canvases(tab_a)
        mark_canvases(tab_b)
        replaced = time.monotonic()
        tab_a.get_by_role("button", name="Arm: reach a line", exact=True).click()
        new = reference("sim-line", guidance=True)
        wait_for_new_canvases(tab_a)
        wait_for_color(tab_a, 0, *ee_pixel(new), OKABE["yellow"])   # tab A has answered long before tab B
        time.sleep(3.0)   # the kernel's estimate of playback (plus its 2 s margin) passes; tab B lags
        tab_b.screenshot(path=artifacts("slow-tab-lagging"))
        cdp.send("Emulation.setCPUThrottlingRate", {"rate": 1})

        def first(log, way, marker):
            return min((at - replaced for at, direction, data in log
                        if at >= replaced and direction == way and marker in data), default=None)

        def seen():
            return (f"after the replacement: the fast tab's first receipt at "
                    f"{first(traffic_a, 'sent', b'image_data')} s, the slow tab's at "
                    f"{first(traffic_b, 'sent', b'image_data')} s, the first close at "
                    f"{first(traffic_b, 'received', b'comm_close')} s")

        try:
            wait_for_new_canvases(tab_b)
            wait_for_color(tab_b, 0, *ee_pixel(new), OKABE["yellow"])
        except Exception:
            tab_b.screenshot(path=artifacts("slow-tab-not-drawn"))
            raise AssertionError(f"the slow tab did not draw the new episode once it caught up; its console's "
                                 f"model errors: {model_errors(console_b)}; {seen()}") from None
        tab_a.screenshot(path=artifacts("fast-tab"))
        tab_b.screenshot(path=artifacts("slow-tab-after"))

        # The old episode's widgets are closed, after the slow tab's answer and well before the fallback.
        deadline = time.monotonic() + CLOSED_WITHIN_S
        while not any(direction == "received" and b'"comm_close"' in data and at >= replaced
                      for at, direction, data in traffic_b) and time.monotonic() < deadline:
            tab_b.wait_for_timeout(200)   # Playwright delivers the websocket events meanwhile

        slow_answer = first(traffic_b, "sent", b'"image_data"')
        close = first(traffic_b, "received", b'"comm_close"')
        assert slow_answer is not None, f"the slow tab sent no receipt back: {seen()}"
        assert close is not None, f"the retired widgets were not closed within {CLOSED_WITHIN_S} s: {seen()}"
        assert close >= slow_answer, f"a retired widget was closed before the slow tab had drawn it: {seen()}"
        assert not model_errors(console_b), model_errors(console_b)
        assert not model_errors(console_a), model_errors(console_a)
    finally:
        api = tab_a.context.request
        headers = {"Authorization": f"token {lab_server.token}"}
        for session in api.get(lab_server.url("/api/sessions"), headers=headers).json():
            api.delete(lab_server.url(f"/api/sessions/{session['id']}"), headers=headers)
        first_context.close()
        second_context.close()
