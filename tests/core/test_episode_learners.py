"""A teaching episode for every learner: the record the widgets draw, beyond ridge."""

import numpy as np
import pytest

from mt_widgets.core import SKILLS, EpisodeStateError, RidgeLearner, TeachingEpisode
from mt_widgets.core.learner_teaching import evaluation_states, make_learner, risk_of_actions, teach
from mt_widgets.core.network_learner import NeuralNetworkLearner
from mt_widgets.core.nonlinear_skills import NONLINEAR_SKILLS


def test_ridge_given_as_a_learner_is_the_papers_episode():
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=4)
    plain, given = TeachingEpisode(skill, states, lam=0.05), TeachingEpisode(skill, states, learner=RidgeLearner(0.05))
    np.testing.assert_array_equal(plain.optimal_actions, given.optimal_actions)
    assert given.lam == 0.05 and given.has_theta and plain.rho1 == given.rho1
    with pytest.raises(ValueError, match="lam: expected none \\(or the learner's own lam 0.05\\)"):
        TeachingEpisode(skill, states, lam=0.2, learner=RidgeLearner(0.05))
    # The default's value given explicitly is a second source too: refused, not overridden.
    with pytest.raises(ValueError, match="got 0.01: the learner's lam is the one source"):
        TeachingEpisode(skill, states, lam=0.01, learner=RidgeLearner(0.5))
    assert TeachingEpisode(skill, states, lam=0.05, learner=RidgeLearner(0.05)).lam == 0.05
    with pytest.raises(TypeError, match="learner: expected a mt_widgets.core Learner"):
        TeachingEpisode(skill, states, learner="ridge")


@pytest.mark.parametrize("name", ["kernel-ridge", "gaussian-process"])
def test_a_kernel_learners_episode_guides_with_its_mt_and_scores_the_policy_risk(name):
    skill = NONLINEAR_SKILLS["uarm-curve"]
    learner = make_learner(name, skill)
    states = skill.query_states(seed=2, n=12)
    episode = TeachingEpisode(skill, states, learner=learner)
    teaching = teach(learner, skill, states)
    np.testing.assert_allclose(episode.optimal_actions, teaching.optimal)
    assert not episode.has_theta and not episode.exact and episode.rho1 > 0
    first = episode.demonstrate(episode.optimal_actions[0] + [1.0, 0.0])
    # The gain bounds how much this gap can move the risk (a linear smoother: exactly linear).
    moved = risk_of_actions(learner, skill, states, np.vstack([first.action, episode.optimal_actions[1:]]))
    assert abs(moved - teaching.risk) <= first.contribution_norm * (1 + 1e-9)
    episode.restore(episode.optimal_actions[1:])
    assert episode.policy_risk == pytest.approx(risk_of_actions(learner, skill, states, episode.actions), rel=1e-12)
    for ridge_only in ("theta_hat", "analysis", "contributions", "bound", "residual"):
        with pytest.raises(EpisodeStateError, match="only a learner with a Theta on the skill.s features"):
            getattr(episode, ridge_only)
    path = episode.reproduction.positions
    assert np.linalg.norm(path[-1] - [23.0, 11.0]) < 3.0 and episode.reproduced


def test_the_reward_learners_episode_of_8_reaches_the_goal():
    skill = SKILLS["uarm-point"]
    episode = TeachingEpisode(skill, skill.query_states(seed=0, n=8), learner=make_learner("reward"))
    episode.restore(episode.optimal_actions)
    assert episode.policy_risk < 1e-9 and episode.exact is False   # approximate MT: never claimed exact
    # Taught exactly, the robot's reproduction is the target's own.
    np.testing.assert_allclose(episode.reproduction.positions, episode.target_reproduction.positions, atol=1e-6)


def test_a_network_episode_has_linearised_gains_and_its_error_falls_with_mt():
    skill = SKILLS["uarm-point"]
    learner = NeuralNetworkLearner(steps=80)
    states = skill.query_states(seed=1)
    episode = TeachingEpisode(skill, states, learner=learner)
    given = [episode.demonstrate(u + [0.5, 0.0]) for u in episode.optimal_actions]
    gains = np.array([d.contribution_norm for d in given]) / 0.5
    assert np.all(gains > 0) and episode.rho1 >= gains.max() * (1 - 1e-9)
    episode = TeachingEpisode(skill, states, learner=learner)
    episode.restore(episode.optimal_actions)
    own = risk_of_actions(learner, skill, states, skill.target_actions(states), evaluation_states(skill))
    assert episode.policy_risk < own


def test_the_episode_reports_theta_error_where_a_theta_exists_and_policy_risk_always():
    skill = SKILLS["uarm-point"]
    states = skill.query_states(seed=2)
    actions = skill.target_actions(states) + 0.3
    ridge = TeachingEpisode.from_actions(skill, states, actions)
    assert ridge.theta_error == ridge.analysis.risk > 0
    assert ridge.policy_risk == pytest.approx(risk_of_actions(RidgeLearner(), skill, states, actions), rel=1e-12)
    kernel = TeachingEpisode.from_actions(skill, states, actions, learner=make_learner("kernel-ridge", skill))
    assert kernel.theta_error is None and kernel.policy_risk > 0
