"""A learner other than ridge in Chromium: a kernel-ridge episode of a curved uArm skill, taught with a
real drag, its MT's guidance arrow drawn, then learnt and reproduced (pages/episode_learner.ipynb)."""

import numpy as np
import pytest

from mt_widgets.core import NONLINEAR_SKILLS, TeachingEpisode, make_learner
from mt_widgets.core.learner_teaching import risk_of_actions

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


def reference_episode():
    """The page's episode, built here without a kernel (the same skill, states and learner)."""
    from mt_widgets.widgets import EpisodeWidget
    skill = NONLINEAR_SKILLS["uarm-curve"]
    learner = make_learner("kernel-ridge", skill)
    teaching = TeachingEpisode(skill, skill.query_states(seed=0, n=6), learner=learner)
    return EpisodeWidget(teaching, guidance=True, css_width="260px"), learner


def test_a_kernel_ridge_episode_is_taught_guided_and_reproduced_in_chromium(page, voila_server, artifacts):
    reference, learner = reference_episode()
    view = reference.teaching.view
    page.goto(voila_server.url("/voila/render/episode_learner.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    ee = ee_pixel(reference)
    wait_for_color(page, 0, *ee, OKABE["black"], tolerance=20)
    origin = reference.query_states[0]
    optimal = reference.optimal[0]
    # A drag short of the kernel MT's arrow: the guidance then draws the optimal arrow's head at its tip.
    end = drag(page, 0, ee, view.transform.action_tip(origin, 0.5 * optimal))
    expected = view.transform.action_from_drag(origin, to_canvas(page, 0, *end))
    wait_for_pending(page, expected, 1.0 / view.transform.pixels_per_action)
    page.get_by_role("button", name="Confirm").click()
    wait_for_status(page, "s.phase === 'guidance' && s.demos.length === 1")
    # The user's arrow is aligned with the optimal one: the optimal one is drawn beside it.
    tip = view.transform.action_tip(origin, optimal)
    along = (tip - ee) / np.hypot(*(tip - ee))
    side = np.array([along[1], -along[0]]) * draw_arrow_pair_offset(view.theme)
    wait_for_color(page, 0, *(tip + side - 5 * along), OKABE["orange"], radius=2, tolerance=40)
    page.screenshot(path=artifacts("guidance"))
    page.get_by_role("button", name="test: finish with optimal").click()
    s = wait_for_status(page, "s.phase === 'finished' && s.error !== null", timeout=30_000)
    demos = np.array(s["demos"])
    np.testing.assert_allclose(demos[1:], reference.optimal[1:], atol=1e-9)
    # The error shown is the policy risk of what kernel ridge learnt from these six actions.
    assert s["error"] == pytest.approx(risk_of_actions(learner, reference.episode.skill, reference.query_states, demos),
                                       rel=1e-9)
    page.screenshot(path=artifacts("reproduced"))
