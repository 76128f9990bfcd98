"""Page helpers: canvas pixels, canvas-to-page coordinates, the STATUS label."""

from __future__ import annotations

import json
import time
from contextlib import contextmanager

import numpy as np

from mt_widgets.widgets.arrows import side_offset

OKABE = {"yellow": (240, 228, 66), "vermillion": (213, 94, 0), "orange": (230, 159, 0), "blue": (0, 114, 178),
         "black": (0, 0, 0)}


def canvas(page, index: int):
    return page.locator("canvas").nth(index)


def to_page(page, index: int, x: float, y: float) -> tuple[float, float]:
    """Canvas pixel (x, y) -> page coordinates, through the element's CSS-scaled box."""
    element = canvas(page, index)
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")
    return box["x"] + x * box["width"] / width, box["y"] + y * box["height"] / height


def to_canvas(page, index: int, px: float, py: float) -> tuple[float, float]:
    element = canvas(page, index)
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")
    return (px - box["x"]) * width / box["width"], (py - box["y"]) * height / box["height"]


def wait_for_color(page, index: int, x: float, y: float, rgb, tolerance: int = 40, timeout: float = 15_000,
                   radius: int = 2) -> float:
    """Wait until a pixel within ``radius`` of canvas pixel (x, y) has colour ``rgb``.

    Returns the page's ``performance.now()`` when the check first saw it. The check runs in the page,
    at once and then on every animation frame, so the time is the page's (within a frame) and not
    when the test's process heard of it.
    """
    return page.wait_for_function(
        """([index, x, y, rgb, tol, r]) => {
            const c = document.querySelectorAll('canvas')[index];
            if (!c) return false;
            const d = c.getContext('2d').getImageData(Math.round(x) - r, Math.round(y) - r, 2 * r + 1, 2 * r + 1).data;
            for (let i = 0; i < d.length; i += 4) {
                if (Math.abs(d[i] - rgb[0]) <= tol && Math.abs(d[i + 1] - rgb[1]) <= tol
                    && Math.abs(d[i + 2] - rgb[2]) <= tol && d[i + 3] > 200) return performance.now();
            }
            return false;
        }""", arg=[index, float(x), float(y), list(rgb), tolerance, radius], timeout=timeout,
        polling="raf").json_value()


def status(page) -> dict:
    text = page.locator("text=/^STATUS /").first.inner_text()
    return json.loads(text[len("STATUS "):])


def wait_for_status(page, predicate: str, timeout: float = 10_000) -> dict:
    """Wait until the STATUS label's JSON satisfies a JS predicate on ``s``; fail with the last one."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
    try:
        _wait_status(page, predicate, timeout)
    except PlaywrightTimeout:
        raise AssertionError(f"STATUS never satisfied {predicate!r}; last: {status(page)}") from None
    return status(page)


def _wait_status(page, predicate, timeout):
    page.wait_for_function(
        """(pred) => {
            const el = Array.from(document.querySelectorAll('.widget-label'))
                .find(e => e.textContent.startsWith('STATUS '));
            if (!el) return false;
            const s = JSON.parse(el.textContent.slice(7));
            return eval(pred);
        }""", arg=predicate, timeout=timeout)


# The episodes the test pages build (pages/*.ipynb), to compute expected pixels without a kernel.
PAGE_EPISODES = {
    "episode_sim.ipynb": dict(skill="sim-point", seed=0, guidance=True, duration=2.0, css_width="360px"),
    "episode_uarm.ipynb": dict(skill="uarm-point", seed=0, guidance=True, css_width="260px"),
}


def reference_episode(page_name: str = "episode_sim.ipynb"):
    """The same episode as a test page, built here without a kernel, for expected pixels."""
    from mt_widgets.widgets import EpisodeWidget
    return EpisodeWidget(**PAGE_EPISODES[page_name])


def ee_pixel(episode, index: int = 0) -> np.ndarray:
    return episode.teaching.view.end_effector_pixel(episode.query_states[index])


def drag(page, index: int, start_px, end_px, steps: int = 5) -> tuple[float, float]:
    """A real drag on canvas ``index`` from canvas pixel ``start_px`` to ``end_px``; returns the page end.

    Chromium reports whole CSS pixels (clientX is truncated), so the drag ends on a whole one.
    """
    start = to_page(page, index, *start_px)
    end = tuple(float(round(v)) for v in to_page(page, index, *end_px))
    page.mouse.move(*start)
    page.mouse.down()
    for fraction in np.linspace(1.0 / steps, 1.0, steps):
        page.mouse.move(start[0] + fraction * (end[0] - start[0]), start[1] + fraction * (end[1] - start[1]))
    page.mouse.up()
    return end


def wait_for_pending(page, expected, tolerance: float) -> dict:
    """Wait until Python's pending action is ``expected`` (2,) within ``tolerance``.

    A drag's intermediate moves reach the kernel first; this waits for the release's action.
    """
    return wait_for_status(page, f"s.pending !== null && Math.abs(s.pending[0] - {expected[0]}) < {tolerance}"
                                 f" && Math.abs(s.pending[1] - {expected[1]}) < {tolerance}")


def draw_arrow_pair_offset(theme) -> float:
    """The sideways offset ``draw_arrow_pair`` gives an optimal arrow aligned with the user's."""
    return side_offset(theme.user_arrow, theme.optimal_arrow)


def touch_context(browser, width: int, height: int):
    """(context, page) of a touch screen (a tablet or a phone) that may only reach 127.0.0.1."""
    from browser_support import LOCAL_PREFIXES
    context = browser.new_context(viewport={"width": width, "height": height}, has_touch=True, is_mobile=True)
    page = context.new_page()
    page.route("**/*", lambda route: route.continue_() if route.request.url.startswith(LOCAL_PREFIXES)
               else route.abort())
    return context, page


def touch_drag(page, start, end, steps: int = 6) -> None:
    """One finger from page point ``start`` to ``end`` (viewport CSS pixels), as a touch screen sends it."""
    cdp = page.context.new_cdp_session(page)
    try:
        cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": start[0], "y": start[1]}]})
        for fraction in np.linspace(1.0 / steps, 1.0, steps):
            point = {"x": start[0] + fraction * (end[0] - start[0]), "y": start[1] + fraction * (end[1] - start[1])}
            cdp.send("Input.dispatchTouchEvent", {"type": "touchMove", "touchPoints": [point]})
        cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    finally:
        cdp.detach()


def ax_names(page) -> list[str]:
    """Every name in Chromium's accessibility tree (what a screen reader can announce)."""
    cdp = page.context.new_cdp_session(page)
    try:
        nodes = cdp.send("Accessibility.getFullAXTree")["nodes"]
    finally:
        cdp.detach()
    return [node.get("name", {}).get("value", "") for node in nodes if not node.get("ignored")]


# -- the visitors' demo (tests/browser/test_impatient_clicks.py, test_payoff_in_view.py) ----------------

def reference(skill="sim-point", guidance=False, seed=0):
    """The demo's episode for these settings, built without a kernel (same defaults as the page)."""
    from mt_widgets.widgets import DemoPage
    page = DemoPage(skill=skill, guidance=True, seed=seed)
    if not guidance:
        page.guidance_switch.value = False
    return page.episode


@contextmanager
def demo_at(browser, voila_server, width: int, height: int):
    """``(page, episode)``: the demo page in a fresh local page of ``width`` x ``height``, its
    teaching canvas drawn (the reference episode's hand is yellow); the page is closed after."""
    from browser_support import local_page
    context, page = local_page(browser, width, height)
    try:
        page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
        page.wait_for_selector("canvas", timeout=60_000)
        episode = reference(guidance=True)
        wait_for_color(page, 0, *ee_pixel(episode), OKABE["yellow"])
        yield page, episode
    finally:
        context.close()


def teach_by_numbers(page, episode, guidance: bool, done: str = "Your teaching error") -> None:
    """Types each optimal arrow, sets and confirms it (and moves on after guidance), then waits for the
    text ``done`` (the demo's result; an ``EpisodeWidget``'s own says where the robot's hand ended)."""
    n = len(episode.query_states)
    for index, action in enumerate(episode.optimal):
        page.get_by_text(f"State {index + 1} of {n}").first.wait_for(timeout=10_000)
        fields = page.locator(".widget-text input[type=number]")
        fields.nth(0).fill(f"{action[0]:.6f}")
        fields.nth(1).fill(f"{action[1]:.6f}")
        fields.nth(1).press("Tab")  # the last value reaches the kernel before the click
        page.get_by_role("button", name="Set arrow").click()
        try:
            page.get_by_text(f"State {index + 1} of {n}: your arrow").first.wait_for(timeout=10_000)
        except Exception:
            page.screenshot(path="test-artifacts/impatient-debug.png")
            raise
        page.get_by_role("button", name="Confirm").click()
        if guidance:
            page.get_by_role("button", name="Finish and watch" if index == n - 1 else "Next state").click()
    page.get_by_text(done).first.wait_for(timeout=20_000)


def open_demo(page, voila_server, console):
    """Opens the demo page (notebooks/demo.ipynb) in Voila, its console kept in ``console``, and waits for
    its teaching canvas's hand."""
    page.on("console", lambda message: console.append(message.text))
    page.on("pageerror", lambda error: console.append(str(error)))
    page.goto(voila_server.url("/voila/render/demo.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee_pixel(reference(guidance=True)), OKABE["yellow"])


def set_guidance(page, on: bool) -> None:
    box = page.get_by_role("checkbox")
    if box.is_checked() != on:
        box.click()


def mark_canvases(page) -> None:
    """Marks the canvas elements on the page now, to tell when a new episode's have replaced them."""
    page.evaluate("() => document.querySelectorAll('canvas').forEach(c => { c.dataset.old = '1'; })")


def wait_for_new_canvases(page) -> None:
    page.wait_for_function("() => { const all = document.querySelectorAll('canvas');"
                           " return all.length === 2 && [...all].every(c => !c.dataset.old); }", timeout=10_000)


def watch_kernel_traffic(page, log: list) -> None:
    """Appends (time.monotonic(), "sent" or "received", payload bytes) for every frame of the
    page's websockets."""
    def on_socket(socket):
        def keep(direction):
            def record(payload):
                data = payload.encode() if isinstance(payload, str) else bytes(payload)
                log.append((time.monotonic(), direction, data))
            return record
        socket.on("framesent", keep("sent"))
        socket.on("framereceived", keep("received"))
    page.on("websocket", on_socket)


def model_errors(console) -> list[str]:
    """The console's messages about a command for a widget model the page no longer has."""
    return [text for text in console if "not found" in text.lower() or "could not find model" in text.lower()]
