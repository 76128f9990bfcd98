"""The episode widget draws an episode of any learner: guidance arrows, the reproduction, the error."""

import numpy as np
import pytest

from mt_widgets.core import SKILLS, TeachingEpisode
from mt_widgets.core.learner_teaching import make_learner
from mt_widgets.core.network_learner import NeuralNetworkLearner
from mt_widgets.core.nonlinear_skills import NONLINEAR_SKILLS
from mt_widgets.widgets.episode import EpisodeWidget


@pytest.mark.parametrize("key, name, n", [("uarm-curve", "kernel-ridge", 6), ("uarm-obstacle", "gaussian-process", 6),
                                          ("uarm-point", "reward", 8), ("uarm-point", "neural-network", 3)])
def test_an_episode_of_any_learner_runs_in_the_widget_with_its_guidance(key, name, n):
    skill = {**SKILLS, **NONLINEAR_SKILLS}[key]
    learner = NeuralNetworkLearner(steps=60) if name == "neural-network" else make_learner(name, skill)
    episode = TeachingEpisode(skill, skill.query_states(seed=3, n=n), learner=learner)
    finished = []
    widget = EpisodeWidget(episode, guidance_modality="arrows+words", on_finished=finished.append)
    for index in range(n):
        given = widget.demonstrate(episode.optimal_actions[index] + [0.3, -0.2])
        np.testing.assert_array_equal(given.optimal_action, episode.optimal_actions[index])
        assert widget.phase == "guidance" and given.contribution_norm > 0
        widget.next()
    assert widget.phase == "finished" and finished and finished[0].episode is episode
    assert widget.theta_error is None and widget.policy_risk == pytest.approx(episode.policy_risk)
    assert episode.policy_risk > 0
    # The number shown is the measure the episode has, by its own name and in the skill's units.
    shown = widget.player.error_label.value
    assert "policy risk" in shown and f"{episode.policy_risk:.3f} {episode.skill.action_units}" in shown
    assert "&Theta;" not in shown
    assert episode.reproduced and len(episode.reproduction.positions) > 1
