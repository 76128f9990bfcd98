"""Tutorial 13 in a browser (Voila, real Chromium): a learner draws a demonstration for the UR5 in the 3-D
episode, machine teaching's arrow answers, and the arm they brought from a URDF is drawn in its own episode.

Expected pixels come from the same widgets built here without a kernel.
"""

import json
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from browser.helpers import OKABE, to_page, wait_for_color
from browser_support import voila

pytestmark = pytest.mark.browser

NAME = "13_teaching_an_industrial_arm.ipynb"
TUTORIAL = Path(__file__).resolve().parents[2] / "tutorials" / NAME


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    root = tmp_path_factory.mktemp("tutorial-13")
    (root / "notebooks").mkdir()
    shutil.copy(TUTORIAL, root / "notebooks" / NAME)
    running = voila(root)
    yield running
    running.stop()


def references():
    """The learner's UR5 episode and the own-arm episode, as the tutorial builds them."""
    from mt_widgets.arms import arm_skills
    from mt_widgets.robot_models import read_urdf
    from mt_widgets.widgets import EpisodeWidget

    cells = ["".join(c["source"]) for c in json.loads(TUTORIAL.read_text())["cells"]]
    urdf = re.search(r"MY_ARM = '''(.*?)'''", next(c for c in cells if "MY_ARM = " in c), re.S).group(1)
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "my_arm.urdf").write_text(urdf, encoding="utf-8")
        description = read_urdf(Path(folder) / "my_arm.urdf", tool="flange")
    mine = arm_skills(description, "mine", home=[0.0, 0.3, 1.2], teaching_box=[[0.25, 0.40], [-0.15, 0.15],
                                                                               [0.05, 0.25]],
                      part=(0.32, -0.08, 0.08), fixture=(0.30, 0.10, 0.10), lift=0.12, label="My arm")
    return EpisodeWidget("ur5-reach", seed=1, guidance=True), EpisodeWidget(mine["mine-reach"], seed=0, guidance=True)


def test_a_learner_draws_a_3d_demonstration_and_sees_their_own_arm(browser, server, artifacts):
    ur5, mine = references()
    context = browser.new_context(viewport={"width": 1280, "height": 1100})
    page = context.new_page()
    try:
        # Voila runs the whole tutorial before the page loads: generous limits for a loaded machine.
        page.goto(server.url(f"/voila/render/{NAME}"), timeout=300_000)
        # Three 3-D episodes: the learner's, the one taught by code, the learner's own arm.
        page.wait_for_function("() => document.querySelectorAll('canvas').length === 3", timeout=120_000)
        page.locator("canvas").first.scroll_into_view_if_needed()
        for view in ("top", "side", "perspective"):
            wait_for_color(page, 0, *ur5.teaching.tool_pixel(view), OKABE["yellow"], timeout=60_000)
        page.screenshot(path=artifacts("ur5-opened"))

        # A drag from the hand in the top view: the arrow's horizontal part, drawn in the learner's colour.
        start = ur5.teaching.tool_pixel("top")
        end = start + np.array([45.0, -35.0])
        first, last = to_page(page, 0, *start), tuple(float(round(v)) for v in to_page(page, 0, *end))
        page.mouse.move(*first)
        page.mouse.down()
        for fraction in np.linspace(0.2, 1.0, 5):
            page.mouse.move(first[0] + fraction * (last[0] - first[0]), first[1] + fraction * (last[1] - first[1]))
        page.mouse.up()
        wait_for_color(page, 0, *(start + 0.8 * (end - start)), OKABE["blue"], radius=3, timeout=20_000)
        page.screenshot(path=artifacts("ur5-drawn"))
        confirm = page.get_by_role("button", name="Confirm").first
        page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(timeout=10_000), timeout=20_000)
        confirm.click()
        page.get_by_text("Teaching effort: 1 of 4 demonstrations").first.wait_for(timeout=20_000)
        page.get_by_text("The optimal arrow (dashed)").first.wait_for(timeout=20_000)
        # Machine teaching's arrow, drawn dashed in orange from the hand: its head, in the top view.
        tool = ur5.skill.end_effector(ur5.query_states[:1])[0][0]
        head = ur5.teaching.panel("top").pixels(tool + ur5.skill.drawing().action_length * ur5.optimal[0])
        wait_for_color(page, 0, *(start + 0.97 * (head - start)), OKABE["orange"], radius=3, timeout=20_000)
        page.locator("canvas").first.scroll_into_view_if_needed()
        page.screenshot(path=artifacts("ur5-guidance"))

        # The arm the learner brought: its own chain, read from the URDF, in its own episode.
        page.locator("canvas").nth(2).scroll_into_view_if_needed()
        for view in ("top", "side"):
            wait_for_color(page, 2, *mine.teaching.tool_pixel(view), OKABE["yellow"], timeout=30_000)
        page.screenshot(path=artifacts("own-arm"))
    finally:
        context.close()
