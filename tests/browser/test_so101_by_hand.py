"""A scripted hand teaches the simulated SO-101 a whole episode in Chromium (pages/episode_so101_hand.ipynb
in Voila): at each query state the person presses "Teach by hand", the arm lets go, the hand drags
the gripper in the simulated hand's view (its canvas, top panel then side panel, with real mouse
events), the page shows the demonstration arrow, the hand confirms, MT's guidance answers, and the
arm plays the learnt skill's reproduction within its envelope.

Pixel targets come from the view's own mapping (``so101_hand.to_view``) of the wanted tool point, so
the gripper moves by the wanted displacement (within a pixel, 1/350 m, per axis).
"""

import json

import numpy as np
import pytest

from mt_widgets.apps.so101_hand import PANEL_PX, to_view

from .helpers import drag, status, wait_for_status

pytestmark = pytest.mark.browser

# One pixel of the hand's view is 1/350 m: a drag ends on a whole CSS pixel, and the arm's inverse
# kinematics put the tool nearest the point it can reach.
TOLERANCE_M = 0.008


def reference():
    """The page's episode, built here without a kernel: its query states and MT's optimal actions."""
    from mt_widgets.widgets import EpisodeWidget
    return EpisodeWidget("so101-reach", seed=0, guidance=True)


def hand_canvas(page) -> int:
    index = page.evaluate("() => [...document.querySelectorAll('canvas')]"
                          ".findIndex(c => c.closest('.mt-simulated-hand') !== null)")
    assert index >= 0, "no canvas of the simulated hand's view on the page"
    return index


def inside_panel(pixel, panel: int) -> tuple[float, float]:
    low, high = (4.0, PANEL_PX - 4.0) if panel == 0 else (PANEL_PX + 4.0, 2 * PANEL_PX - 4.0)
    x, y = float(pixel[0]), float(pixel[1])
    assert low <= x <= high and 4.0 <= y <= PANEL_PX - 4.0, f"pixel {pixel} outside panel {panel}"
    return x, y


@pytest.mark.slow
def test_a_scripted_hand_teaches_the_simulated_so101_a_whole_episode(browser, voila_server, page, artifacts):
    episode = reference()
    length = episode.skill.plant.drawing().action_length
    n = len(episode.query_states)
    page.set_viewport_size({"width": 1280, "height": 1400})
    page.goto(voila_server.url("/voila/render/episode_so101_hand.ipynb"), timeout=60_000)
    page.wait_for_selector(".mt-simulated-hand", timeout=60_000)
    index = hand_canvas(page)
    view = page.locator("canvas").nth(index)
    for k in range(n):
        wait_for_status(page, f"s.index === {k} && s.phase === 'teaching'", timeout=30_000)
        page.get_by_role("button", name="Teach by hand").click(timeout=30_000)   # the page's arm lets go
        wait_for_status(page, f"s.released && s.index === {k}", timeout=30_000)
        wanted = np.asarray(episode.optimal[k]) * length   # MT's arrow (what guidance shows), m
        start = np.array(status(page)["tool"])
        view.scroll_into_view_if_needed()
        # The top panel moves the gripper across the table (x, y), the side panel forward and up (x, z).
        goal = start + wanted
        drag(page, index, inside_panel(to_view(start)[0], 0), inside_panel(to_view(goal)[0], 0))
        across = np.array(wait_for_status(page, f"Math.abs(s.tool[1] - {float(goal[1])}) < {TOLERANCE_M}")["tool"])
        drag(page, index, inside_panel(to_view(across)[1], 1), inside_panel(to_view(goal)[1], 1))
        # The arrow follows the hand a reading (20 ms) behind: wait for the one where the drag ended.
        s = wait_for_status(page, f"s.pending !== null && [0, 1, 2].every(i => Math.abs(s.tool[i] - "
                                  f"{json.dumps(goal.tolist())}[i]) < {TOLERANCE_M} && Math.abs(s.pending[i] * {length}"
                                  f" - {json.dumps(wanted.tolist())}[i]) < {TOLERANCE_M})", timeout=20_000)
        # The arrow is the hand's displacement, and the canvas says so to a screen reader.
        assert np.allclose(np.array(s["pending"]) * length, wanted, atol=TOLERANCE_M), (s, wanted)
        label = page.locator("canvas").first.get_attribute("aria-label")
        assert "Your arrow: x " in label and f"State {k + 1} of {n}" in label, label
        if k == 0:
            page.screenshot(path=artifacts("hand-arrow"), full_page=True)
        page.get_by_role("button", name="Confirm").click()
        wait_for_status(page, f"s.phase === 'guidance' && s.records.length === {k + 1}", timeout=20_000)
        if k == 0:
            page.screenshot(path=artifacts("guidance"), full_page=True)
        page.get_by_role("button", name="Finish and watch" if k == n - 1 else "Next state").click()
    # The reproduction is played on the arm through the envelope, whole: the skill's goal is 4 cm above the
    # table's clearance, so what was learnt from these pixel-rounded demonstrations of MT's arrows stays above it.
    s = wait_for_status(page, "s.phase === 'finished' && s.report !== null", timeout=60_000)
    recorded = np.array(s["records"]) * length
    wanted = np.array(episode.optimal[:n]) * length
    assert np.allclose(recorded, wanted, atol=TOLERANCE_M), (recorded, wanted)
    reached, total, stopped, error = s["report"]
    assert s["reproduced"] and reached == total and not stopped and error == "", s["report"]
    page.get_by_text("The robot has finished its reproduction.").last.wait_for(timeout=10_000)
    # The arm ended at the learnt skill's end, near the part, and the hand's view shows it there.
    assert np.linalg.norm(np.array(s["tool"]) - np.array(episode.skill.target.point)) < 0.02, s["tool"]
    assert s["tool"][2] >= 0.02 - 0.001, s["tool"]                # above the table's clearance (to a servo step)
    assert np.allclose(s["drawn"], s["tool"], atol=0.002), (s["drawn"], s["tool"])
    page.screenshot(path=artifacts("reproduced"), full_page=True)
