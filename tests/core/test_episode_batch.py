"""The batched teaching episode gives, teacher by teacher, what the single episode's analysis gives."""

import numpy as np
import pytest

from mt_widgets.core import (
    SKILLS,
    KernelRidgeLearner,
    RidgeLearner,
    analyse_demonstrations,
    optimal_actions,
    ridge_operator,
)
from mt_widgets.core.episode import TeachingEpisode
from mt_widgets.core.episode_batch import EpisodeBatch


@pytest.fixture(scope="module")
def skill():
    return SKILLS["sim-point"]


def _states(skill, k):
    return np.stack([skill.query_states(seed=seed) for seed in range(k)])


def test_each_teacher_is_fitted_and_scored_as_a_single_episode_would_be(skill):
    batch = EpisodeBatch.of(skill, _states(skill, 3), RidgeLearner(0.01))
    rng = np.random.default_rng(0)
    which = np.array([0, 1, 2, 2, 0])
    actions = batch.optimal_for(which, 5) + rng.normal(0, 0.3, (5,) + batch.optimal_actions.shape[1:])
    outcome = batch.complete(actions, which)
    for b, k in enumerate(which):
        single = analyse_demonstrations(batch.features[k], actions[b], skill.theta, 0.01)
        assert outcome.theta_hat[b] == pytest.approx(single.theta_hat, abs=1e-10)
        assert outcome.theta_error[b] == pytest.approx(single.risk, abs=1e-10)
        episode = TeachingEpisode.from_actions(skill, batch.query_states[k], actions[b], learner=RidgeLearner(0.01))
        assert outcome.policy_risk[b] == pytest.approx(episode.policy_risk, rel=1e-12)
        assert outcome.rho1[b] == pytest.approx(single.rho1, abs=1e-12)
        assert outcome.rho2[b] == pytest.approx(single.rho2, abs=1e-10)
        assert outcome.bound[b] == pytest.approx(single.bound, abs=1e-10)
    assert batch.exact.all()


def test_a_batch_is_many_teaching_episodes_with_the_same_names_and_values(skill):
    states = _states(skill, 2)
    batch = EpisodeBatch.of(skill, states, RidgeLearner(0.05), duration=0.3)
    rng = np.random.default_rng(1)
    actions = batch.optimal_actions + rng.normal(0, 0.5, batch.optimal_actions.shape)
    outcome = batch.complete(actions)
    trajectories = batch.reproduce(outcome.theta_hat)
    for b in range(2):
        episode = TeachingEpisode.from_actions(skill, states[b], actions[b], lam=0.05, duration=0.3)
        assert batch.optimal_actions[b] == pytest.approx(episode.optimal_actions, abs=1e-10)
        assert batch.exact[b] == episode.exact and batch.rank[b] == episode.rank
        assert batch.residual_norm[b] == pytest.approx(episode.residual_norm, abs=1e-10)
        for name in ("theta_hat", "theta_error", "policy_risk", "rho1", "rho2", "bound"):
            assert getattr(outcome, name)[b] == pytest.approx(getattr(episode, name), abs=1e-10), name
        assert np.asarray(trajectories[b].states)[-1] == pytest.approx(
            np.asarray(episode.reproduction.states)[-1], abs=1e-9)


def test_the_optimal_demonstration_teaches_the_skill_exactly(skill):
    batch = EpisodeBatch.of(skill, _states(skill, 2), RidgeLearner(0.01))
    outcome = batch.complete(batch.optimal_actions)
    assert outcome.theta_error == pytest.approx([0, 0], abs=1e-9)
    assert outcome.rho2 == pytest.approx([0, 0], abs=1e-12)


def test_below_the_teaching_dimension_the_rank_rule_is_the_single_learners(skill):
    # Repeated states: Phi has rank 1, so only the least-error demonstration exists.
    one = skill.query_states(seed=0)[:1]
    states = np.repeat(one, skill.n_features, axis=0)[None]
    batch = EpisodeBatch.of(skill, states, RidgeLearner(0.0))
    assert batch.rank[0] == ridge_operator(batch.features[0], 0.0).rank == 1
    assert not batch.exact[0]
    with pytest.warns(UserWarning):
        single = optimal_actions(batch.features[0], skill.theta, 0.0)
    assert batch.optimal_actions[0] == pytest.approx(single, abs=1e-9)
    outcome = batch.complete(batch.optimal_actions)
    assert outcome.bound[0] > 0 and np.isfinite(outcome.theta_hat).all()


def test_learnt_skills_are_rolled_out_as_one_batch(skill):
    batch = EpisodeBatch.of(skill, _states(skill, 1), RidgeLearner(0.01), duration=0.5)
    thetas = np.stack([skill.theta, skill.theta])
    rolled = batch.reproduce(thetas, record_every=50)
    single = skill.reproduce(skill.theta, duration=0.5, record_every=50)
    assert np.asarray(rolled[1].states) == pytest.approx(np.asarray(single.states))


def test_bad_input_is_refused_naming_the_argument(skill):
    with pytest.raises(TypeError, match="skill"):
        EpisodeBatch.of("sim-point", _states(skill, 1), RidgeLearner(0.01))
    with pytest.raises(ValueError, match="query_states"):
        EpisodeBatch.of(skill, skill.query_states(seed=0), RidgeLearner(0.01))
    with pytest.raises(ValueError, match="lam"):
        EpisodeBatch.of(skill, _states(skill, 1), RidgeLearner(-1.0))
    with pytest.raises(TypeError, match="learner: expected a parametric smoother"):
        EpisodeBatch.of(skill, _states(skill, 1), KernelRidgeLearner(1.0))
    batch = EpisodeBatch.of(skill, _states(skill, 2), RidgeLearner(0.01))
    with pytest.raises(ValueError, match="episode_of"):
        batch.complete(batch.optimal_actions[:1].repeat(3, axis=0))
    with pytest.raises(ValueError, match="episode_of"):
        batch.complete(batch.optimal_actions, np.array([0, 5]))
    with pytest.raises(ValueError, match="actions"):
        batch.complete(np.zeros((2, 1, 1)), np.array([0, 1]))
