"""A JupyterLab cell run again, impatiently, closes the episode it made and draws the new one
(``mt_widgets/widgets/cells.py``): the kernel keeps one episode open, not one per run, the page never
meets a command for a closed canvas, and the new episode teaches."""

import json
import re
import time

import pytest

from browser_support import local_page

from .helpers import OKABE, ee_pixel, model_errors, teach_by_numbers, wait_for_color, watch_kernel_traffic

pytestmark = pytest.mark.browser

NOTEBOOK = "cell_rerun.ipynb"
EPISODE_CELL = ('from mt_widgets.widgets import EpisodeWidget\n'
                'episode = EpisodeWidget("sim-point", seed=0, guidance=True)\n'
                'episode')
# Numbered runs: the test reads the answer of the run it asked for, not an output area JupyterLab has
# just cleared for it (which read "open episodes: None" on a loaded CI machine).
PROBE_CELL = ('from ipywidgets.widgets.widget import _instances\n'
              'import gc; gc.collect()\n'
              '_probe_run = globals().get("_probe_run", 0) + 1\n'
              'print(f"probe {_probe_run}: open episodes:", '
              'sum(isinstance(w, EpisodeWidget) for w in list(_instances.values())))')
#: Seconds within which the replaced episodes are closed once the page has drawn them: far below the
#: 60 s a close takes when no page answers (``animation.CLOSE_FALLBACK_S``).
CLOSED_WITHIN_S = 20.0


def _notebook() -> dict:
    cells = [{"cell_type": "code", "id": cell_id, "metadata": {}, "execution_count": None, "outputs": [],
              "source": source} for cell_id, source in (("episode-cell", EPISODE_CELL), ("probe-cell", PROBE_CELL))]
    return {"cells": cells, "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3",
                                                        "language": "python"}},
            "nbformat": 4, "nbformat_minor": 5}


def test_a_cell_run_again_and_again_keeps_one_episode_open_and_the_page_drawing(browser, lab_server, artifacts):
    from mt_widgets.widgets import EpisodeWidget

    context, page = local_page(browser, 1280, 1100)
    console, traffic = [], []
    page.on("console", lambda message: console.append(message.text))
    page.on("pageerror", lambda error: console.append(str(error)))
    watch_kernel_traffic(page, traffic)
    api = page.context.request
    headers = {"Authorization": f"token {lab_server.token}"}
    expected = EpisodeWidget("sim-point", seed=0, guidance=True)
    try:
        put = api.put(lab_server.url(f"/api/contents/{NOTEBOOK}"), headers=headers,
                      data=json.dumps({"type": "notebook", "format": "json", "content": _notebook()}))
        assert put.ok, put.text()
        page.goto(lab_server.url(f"/lab/tree/{NOTEBOOK}?reset&token={lab_server.token}"), timeout=60_000)
        page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)
        cells = page.locator(".jp-Notebook .jp-Cell")
        cells.nth(0).locator(".jp-InputArea-editor").click()
        page.keyboard.press("Control+Enter")
        page.wait_for_selector(".jp-OutputArea canvas", timeout=60_000)
        wait_for_color(page, 0, *ee_pixel(expected), OKABE["yellow"], timeout=60_000)

        # Impatient: the same cell run four times more, each before the last one's episode is drawn.
        started = time.monotonic()
        for _ in range(4):
            page.keyboard.press("Control+Enter")
            page.wait_for_timeout(150)
        page.wait_for_function("() => document.body.innerText.includes('Idle')", timeout=60_000)
        page.wait_for_selector(".jp-OutputArea canvas", timeout=60_000)
        wait_for_color(page, 0, *ee_pixel(expected), OKABE["yellow"], timeout=60_000)

        # The kernel closes the replaced episodes once the page has drawn what they held.
        deadline, open_episodes, run = time.monotonic() + CLOSED_WITHIN_S, None, 0
        while time.monotonic() < deadline:
            run += 1
            cells.nth(1).locator(".jp-InputArea-editor").click()
            page.keyboard.press("Control+Enter")
            answer = cells.nth(1).locator(".jp-OutputArea").get_by_text(f"probe {run}: open episodes:")
            answer.wait_for(timeout=60_000)
            open_episodes = int(re.search(r"open episodes: (\d+)", answer.inner_text()).group(1))
            if open_episodes == 1:
                break
            page.wait_for_timeout(500)
        page.screenshot(path=artifacts("after-reruns"))
        closes = [at - started for at, direction, data in traffic
                  if direction == "received" and b'"comm_close"' in data and at >= started]
        assert open_episodes == 1, f"the kernel keeps {open_episodes} episodes open after five runs of one cell"
        assert closes, "no widget was closed"
        assert not model_errors(console), model_errors(console)

        # The episode on the page now is the live one: it teaches.
        teach_by_numbers(page, expected, guidance=True, done="the robot's hand is at")
        # The reproduction played: its Replay button comes on once the animation was sent.
        page.wait_for_function("() => [...document.querySelectorAll('button')].some("
                               "b => b.textContent.includes('Replay') && !b.disabled)", timeout=30_000)
        page.get_by_role("button", name="Replay").scroll_into_view_if_needed()
        page.wait_for_timeout(1500)
        page.screenshot(path=artifacts("taught"))
        assert not model_errors(console), model_errors(console)
    finally:
        for session in api.get(lab_server.url("/api/sessions"), headers=headers).json():
            api.delete(lab_server.url(f"/api/sessions/{session['id']}"), headers=headers)
        api.delete(lab_server.url(f"/api/contents/{NOTEBOOK}"), headers=headers)
        context.close()
