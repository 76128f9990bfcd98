"""A participant of industrial-sim (the paper's phases on the UR5) in Chromium, on the online study page
(notebooks/study_online.ipynb, the protocol with the online pilot's [online] tables): the page builds
the 3-D canvas, the participant draws each 3-D demonstration of P1 by dragging in the top view (x, y)
and the side view (x, height), with a mouse on a laptop and with a finger on a phone, watches the
reproduction and moves on to the next part. The log holds the drawn 3-D actions."""

from __future__ import annotations

import shutil
from urllib.parse import urlencode

import numpy as np
import pytest

from browser_support import REPO, local_page, voila
from mt_widgets.widgets import SpaceTeachingCanvas
from protocols import industrial_online_toml

from .support import button, wait_for_log

pytestmark = pytest.mark.browser

ONLINE = "/voila/render/study_online.ipynb"
YELLOW = (240, 228, 66)   # the tool's marker (Okabe-Ito yellow)
#: Drags from the tool, in canvas pixels: in the top view (x right, y up the screen), in the side view.
TOP_DRAG, SIDE_DRAG = np.array([36.0, -28.0]), np.array([-22.0, -30.0])


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    root = tmp_path_factory.mktemp("voila-industrial")
    (root / "notebooks").mkdir()
    shutil.copy(REPO / "notebooks" / "study_online.ipynb", root / "notebooks")
    protocol = root / "notebooks" / "industrial_online.toml"
    protocol.write_text(industrial_online_toml(practice_s=2))
    logs = root / "logs"
    served = voila(root, env={"MT_WIDGETS_STUDY_LOGS": str(logs), "MT_WIDGETS_STUDY_PROTOCOL": str(protocol)})
    served.logs = logs
    yield served
    served.stop()


def to_page(page, x, y):
    element = page.locator("canvas").first
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")
    return box["x"] + x * box["width"] / width, box["y"] + y * box["height"] / height


def wait_for_tool(page, pixel, timeout=60_000):
    page.wait_for_function(
        """([x, y, rgb]) => {
            const c = document.querySelector('canvas');
            if (!c) return false;
            const d = c.getContext('2d').getImageData(Math.round(x) - 2, Math.round(y) - 2, 5, 5).data;
            for (let i = 0; i < d.length; i += 4) {
                if (Math.abs(d[i] - rgb[0]) < 40 && Math.abs(d[i + 1] - rgb[1]) < 40
                    && Math.abs(d[i + 2] - rgb[2]) < 40 && d[i + 3] > 200) return true;
            }
            return false;
        }""", arg=[float(pixel[0]), float(pixel[1]), list(YELLOW)], timeout=timeout)


def mouse_drag(page, start_px, end_px):
    start, end = to_page(page, *start_px), to_page(page, *end_px)
    end = tuple(float(round(v)) for v in end)   # Chromium reports whole CSS pixels
    page.mouse.move(*start)
    page.mouse.down()
    for fraction in np.linspace(0.2, 1.0, 5):
        page.mouse.move(start[0] + fraction * (end[0] - start[0]), start[1] + fraction * (end[1] - start[1]))
    page.mouse.up()


def finger_drag(page, start_px, end_px):
    start, end = to_page(page, *start_px), to_page(page, *end_px)
    cdp = page.context.new_cdp_session(page)
    try:
        cdp.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [{"x": start[0], "y": start[1]}]})
        for fraction in np.linspace(1 / 6, 1.0, 6):
            point = {"x": start[0] + fraction * (end[0] - start[0]), "y": start[1] + fraction * (end[1] - start[1])}
            cdp.send("Input.dispatchTouchEvent", {"type": "touchMove", "touchPoints": [point]})
        cdp.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
    finally:
        cdp.detach()


def take_part_until_p1(page, server, pid, shot, name):
    query = urlencode({"PROLIFIC_PID": pid, "STUDY_ID": "ST1", "SESSION_ID": "SE1"})
    page.goto(f"{server.url(ONLINE)}?{query}", wait_until="commit", timeout=180_000)
    button(page, "Continue").wait_for(timeout=300_000)
    # Each screen's words are waited for before its button: a click on the previous screen's
    # Continue, about to be replaced, would be lost.
    button(page, "Continue").click()                # welcome
    page.get_by_text("Information sheet").wait_for(timeout=30_000)
    button(page, "Continue").click()
    button(page, "I agree").click()
    page.get_by_text("Have you studied robotics").wait_for(timeout=30_000)
    page.get_by_role("radio", name="no").check()
    button(page, "Continue").click()
    page.get_by_text("Your age, in years").wait_for(timeout=30_000)
    page.get_by_placeholder("a number (years)").fill("27")
    page.get_by_role("radio", name="female").check()
    button(page, "Continue").click()
    page.get_by_text("six-joint arm standing on a table").wait_for(timeout=30_000)
    button(page, "Start the practice").click()
    page.locator("canvas").first.wait_for(timeout=60_000)
    page.screenshot(path=shot(f"{name}-practice"))
    done = button(page, "Continue to the study")
    page.wait_for_function("b => !b.disabled", arg=done.element_handle(timeout=30_000), timeout=30_000)
    done.click()
    button(page, "Start").click()                   # Part 1 of 5


def teach_p1(page, server, pid, draw, shot, name):
    """Draws every demonstration of P1 (top view, then side view), confirms it, checks the log."""
    started = wait_for_log(server, pid, lambda events: any(e["type"] == "episode_started" for e in events), 60)
    states = np.asarray([e for e in started if e["type"] == "episode_started"][0]["query_states"])
    reference = SpaceTeachingCanvas("ur5-reach", states, guidance=False, play=False)
    top, side = reference.panel("top"), reference.panel("side")
    confirm = button(page, "Confirm")
    for index in range(len(states)):
        top_tool, side_tool = reference.tool_pixel("top"), reference.tool_pixel("side")
        wait_for_tool(page, top_tool)
        wait_for_tool(page, side_tool)
        page.wait_for_function("b => b.disabled", arg=confirm.element_handle(timeout=30_000), timeout=30_000)
        draw(page, top_tool, top_tool + TOP_DRAG)
        page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(), timeout=30_000)
        draw(page, side_tool, side_tool + SIDE_DRAG)
        if index == 0:
            page.screenshot(path=shot(f"{name}-drawn"))
        confirm.click()
        events = wait_for_log(server, pid, lambda events, i=index: any(
            e["type"] == "demonstration" and e["phase"] == "P1" and e["index"] == i for e in events), 60)
        action = np.asarray([e for e in events if e["type"] == "demonstration"][-1]["action"])
        length = reference.action_length
        # x in both views: the side drag moves it on from the top drag's x.
        expected = np.array([TOP_DRAG[0] / top.scale + SIDE_DRAG[0] / side.scale, -TOP_DRAG[1] / top.scale,
                             -SIDE_DRAG[1] / side.scale]) / length
        # A CSS pixel of the scaled canvas (a phone's is 1.5 canvas pixels) is the tolerance.
        assert action == pytest.approx(expected, abs=3.0 / top.scale / length), (index, action, expected)
        reference.set_action(action)
        reference.confirm()   # the reference moves on to the next state, as the page did


@pytest.mark.parametrize("device", ["laptop-mouse", "phone-touch"])
def test_a_participant_draws_3d_demonstrations_on_the_study_page_and_moves_on(browser, server, artifacts, device):
    pid = {"laptop-mouse": "5f0a1b2c3d4e5f6a7b8c9d71", "phone-touch": "5f0a1b2c3d4e5f6a7b8c9d72"}[device]
    if device == "laptop-mouse":
        context, page = local_page(browser, 1280, 1100)
        draw = mouse_drag
    else:
        from browser_support import LOCAL_PREFIXES
        context = browser.new_context(viewport={"width": 390, "height": 844}, has_touch=True, is_mobile=True)
        page = context.new_page()
        page.route("**/*", lambda route: route.continue_() if route.request.url.startswith(LOCAL_PREFIXES)
                   else route.abort())
        draw = finger_drag
    try:
        try:
            take_part_until_p1(page, server, pid, artifacts, device)
        except Exception:
            page.screenshot(path=artifacts(f"{device}-stuck"))
            raise
        teach_p1(page, server, pid, draw, artifacts, device)
        # The reproduction plays in the three views; Continue comes once it has played.
        page.get_by_text("This is what the robot learnt from your demonstrations").wait_for(timeout=60_000)
        go_on = button(page, "Continue")
        page.wait_for_function("b => !b.disabled", arg=go_on.element_handle(timeout=60_000), timeout=60_000)
        go_on.scroll_into_view_if_needed()
        page.screenshot(path=artifacts(f"{device}-reproduction"))
        go_on.click()
        page.get_by_text("Part 2 of 5").wait_for(timeout=30_000)
        page.get_by_text("a part rides a conveyor across the table").wait_for(timeout=30_000)
        page.screenshot(path=artifacts(f"{device}-next-part"))
        events = wait_for_log(server, pid, lambda events: any(e["type"] == "episode_finished" for e in events), 30)
        finished = [e for e in events if e["type"] == "episode_finished"]
        assert [(e["phase"], e["skill"]) for e in finished] == [("P1", "ur5-reach")]
        assert all(e["input"]["method"] == "pointer" for e in events if e["type"] == "demonstration")
    finally:
        context.close()
