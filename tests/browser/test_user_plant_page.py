"""Tutorial 09's own plant (a puck) taught on the demo page in Chromium, with real mouse drags.

The page (pages/demo_user_plant.ipynb) gives ``DemoPage`` the caller's skills, the puck first.
Nothing in the views knows the puck: it is drawn from its end-effector alone (a dot with its
velocity), taught by dragging arrows, learnt, and its reproduction played to the last frame.
"""

import numpy as np
import pytest

from mt_widgets import RidgeLearner, teaching_risk
from user_plant import park

from .helpers import (
    OKABE,
    drag,
    draw_arrow_pair_offset,
    ee_pixel,
    to_canvas,
    wait_for_color,
    wait_for_pending,
    wait_for_status,
)

pytestmark = pytest.mark.browser

PAGE = "demo_user_plant.ipynb"


def reference_page():
    """The page's first episode, built here without a kernel (same skills and defaults as the page)."""
    from mt_widgets.widgets import DemoPage
    return DemoPage(skills=[("Puck: park it", park), ("Arm: reach a point", "sim-point")], duration=3.0).episode


def test_the_your_own_skill_tutorials_puck_is_taught_with_real_drags_on_the_demo_page(page, voila_server, artifacts):
    reference = reference_page()
    view = reference.teaching.view
    page.goto(voila_server.url(f"/voila/render/{PAGE}"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    assert page.get_by_role("button", name="Puck: park it", exact=True).count() == 1
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["black"], tolerance=20)        # the puck: a dot
    wait_for_color(page, 0, *view.transform.to_pixel(park.target.point), OKABE["vermillion"])
    s = wait_for_status(page, "s.skill === 'puck-park' && s.index === 0")
    assert s["phase"] == "teaching"
    page.screenshot(path=artifacts("opened"))

    one_pixel = 1.0 / view.transform.pixels_per_action
    dragged = []
    for index in range(len(reference.query_states)):
        origin = park.end_effector(reference.query_states[index:index + 1])[0][0]
        ee = ee_pixel(reference, index)
        wait_for_color(page, 0, *ee, OKABE["black"], tolerance=20)
        # The visitor aims at the optimal arrow's tip (as a careful teacher would, after guidance).
        end = drag(page, 0, ee, view.transform.action_tip(origin, reference.optimal[index]))
        expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
        s = wait_for_pending(page, expected, one_pixel)
        dragged.append(s["pending"])
        if index == 0:
            page.screenshot(path=artifacts("dragged"))
        page.get_by_role("button", name="Confirm").click()
        wait_for_status(page, f"s.phase === 'guidance' && s.demos.length === {index + 1}")
        if index == 0:
            # Guidance on: the optimal arrow's solid head, in the optimal arrow's colour.
            # Aimed at its tip, the user's arrow is aligned with it: the optimal one is drawn beside.
            tip = view.transform.action_tip(origin, reference.optimal[0])
            along = (tip - ee) / np.hypot(*(tip - ee))
            side = np.array([along[1], -along[0]]) * draw_arrow_pair_offset(view.theme)
            page.screenshot(path=artifacts("guidance"))
            wait_for_color(page, 0, *(tip + side - 5 * along), OKABE["orange"], radius=2, tolerance=40)
        last = index == len(reference.query_states) - 1
        page.get_by_role("button", name="Finish and watch" if last else "Next state").click()
        if not last:
            wait_for_status(page, f"s.phase === 'teaching' && s.index === {index + 1}")

    s = wait_for_status(page, "s.phase === 'finished' && s.error !== null", timeout=20_000)
    demos = np.array(s["demos"])
    np.testing.assert_allclose(demos, dragged, atol=1e-12)
    # Each drag ended within a pixel of the optimal tip, so each action is within about a pixel's
    # worth of the optimal one ...
    assert np.all(np.abs(demos - reference.optimal) <= 1.5 * one_pixel)
    # ... and the error the page shows is the one the learner gives for these very actions.
    theta_hat = RidgeLearner(lam=reference.lam).fit(reference.features, demos).theta
    error = teaching_risk(theta_hat, park.theta)
    assert s["error"] == pytest.approx(error, rel=1e-9, abs=1e-12)
    assert error < 0.2, "aimed at the optimal arrows, the puck learns its skill closely"
    page.get_by_text(f"Your teaching error: {error:.3f}").wait_for(timeout=10_000)

    # The reproduction plays to its last frame: the puck's dot where the learnt skill leaves it.
    for action in demos:
        reference.demonstrate(action)
        reference.next()
    player = reference.player.view
    final = player.transform.to_pixel(reference.result.trajectory.positions[-1])
    wait_for_color(page, 1, *final, OKABE["black"], tolerance=20, timeout=20_000)
    page.screenshot(path=artifacts("reproduced"))
