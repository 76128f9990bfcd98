"""The headless teaching episode against computations made independently of it (numpy only)."""

import dataclasses
import gc

import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, analyse_demonstrations, optimal_actions, teaching_risk
from mt_widgets.core import DEFAULT_LAMBDA, EpisodeStateError, Skill, TeachingEpisode, UnderdeterminedTeachingWarning
from mt_widgets.core import episode as episode_module


def _ridge_map(Phi, lam):
    """A = (Phi^T Phi + lam I)^-1 Phi^T, by the normal equations (not by the SVD the episode uses)."""
    return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[1]), Phi.T)


@pytest.mark.parametrize("key", ["sim-point", "sim-line", "uarm-point", "uarm-line"])
@pytest.mark.parametrize("lam", [0.0, DEFAULT_LAMBDA, 0.5])
def test_learning_from_the_optimal_actions_gives_back_theta(key, lam):
    skill = SKILLS[key]
    episode = TeachingEpisode(skill, seed=3, lam=lam)
    assert episode.exact and episode.rank == skill.n_features == episode.n_states
    # U_bar agrees with the public optimal_actions and with Phi Theta^T + lam Phi (Phi^T Phi)^-1 Theta^T.
    Phi = skill.features(episode.query_states)
    np.testing.assert_allclose(episode.optimal_actions, optimal_actions(Phi, skill.theta, lam), atol=1e-10)
    closed_form = Phi @ skill.theta.T + lam * Phi @ np.linalg.solve(Phi.T @ Phi, skill.theta.T)
    np.testing.assert_allclose(episode.optimal_actions, closed_form, rtol=1e-8, atol=1e-8)
    for action in episode.optimal_actions:
        analysis = episode.demonstrate(action)
        assert analysis.contribution_norm < 1e-10 and np.allclose(analysis.gap, 0)
    assert episode.complete
    np.testing.assert_allclose(episode.theta_hat, skill.theta, atol=1e-10)
    assert episode.theta_error < 1e-10 and episode.rho2 < 1e-10


def test_the_result_matches_the_learner_the_risk_and_the_bound():
    skill = SKILLS["sim-point"]
    rng = np.random.default_rng(11)
    episode = TeachingEpisode(skill, seed=5)
    U = episode.optimal_actions + rng.normal(scale=1.5, size=episode.optimal_actions.shape)
    for action in U:
        episode.demonstrate(action)
    Phi = skill.features(episode.query_states)
    theta_hat = RidgeLearner(DEFAULT_LAMBDA).fit(Phi, U).theta
    np.testing.assert_allclose(episode.theta_hat, theta_hat, atol=1e-10)
    np.testing.assert_allclose(episode.theta_hat, (_ridge_map(Phi, DEFAULT_LAMBDA) @ U).T, atol=1e-9)
    assert episode.theta_error == pytest.approx(teaching_risk(theta_hat, skill.theta), rel=1e-10)
    singular = np.linalg.svd(Phi, compute_uv=False)
    assert episode.rho1 == pytest.approx(np.max(singular / (singular**2 + DEFAULT_LAMBDA)), rel=1e-10)
    assert episode.rho2 == pytest.approx(np.linalg.norm(U - episode.optimal_actions), rel=1e-12)
    assert episode.theta_error <= episode.rho1 * episode.rho2
    assert episode.bound == pytest.approx(episode.rho1 * episode.rho2)
    assert episode.theta_error > 0.1, "a test of the bound needs a real error"


@pytest.mark.parametrize("n_states", [3, 5, 8])
def test_contributions_sum_to_theta_hat_minus_theta(n_states):
    skill = SKILLS["sim-line"]
    rng = np.random.default_rng(n_states)
    states = skill.query_states(seed=2, n=n_states)
    episode = TeachingEpisode(skill, states, lam=0.05)
    assert episode.exact == (n_states >= skill.n_features)
    actions = rng.normal(size=(n_states, 2)) * 3
    analyses = [episode.demonstrate(a) for a in actions]
    Phi = skill.features(states)
    A = _ridge_map(Phi, 0.05)
    optimal = episode.optimal_actions
    terms = np.array([np.outer(u - ub, a) for u, ub, a in zip(actions, optimal, A.T)])    # (N, R, S)
    np.testing.assert_allclose(episode.contributions, terms, atol=1e-9)
    residual = (A @ optimal).T - skill.theta
    np.testing.assert_allclose(episode.residual, residual, atol=1e-9)
    np.testing.assert_allclose(episode.contributions.sum(axis=0) + episode.residual, episode.theta_hat - skill.theta,
                               atol=1e-9)
    if episode.exact:
        assert episode.residual_norm < 1e-9
    norms = np.linalg.norm(terms.reshape(n_states, -1), axis=1)
    np.testing.assert_allclose(episode.contribution_norms, norms, rtol=1e-9)
    np.testing.assert_allclose([a.contribution_norm for a in analyses], norms, rtol=1e-9)
    # The norms are sizes of terms that partly cancel: their sum bounds E but is not E.
    assert episode.theta_error <= episode.contribution_norms.sum() + episode.residual_norm + 1e-12
    assert episode.theta_error < episode.contribution_norms.sum()
    assert episode.theta_error <= episode.bound + 1e-12


def test_below_the_teaching_dimension_the_episode_is_not_exact_and_its_optimum_is_the_least_error_one():
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=0)[:3]
    episode = TeachingEpisode(skill, states)
    assert not episode.exact and episode.rank == 3
    with pytest.warns(UnderdeterminedTeachingWarning):
        reference = optimal_actions(skill.features(states), skill.theta, DEFAULT_LAMBDA)
    np.testing.assert_allclose(episode.optimal_actions, reference, atol=1e-10)
    for action in episode.optimal_actions:
        episode.demonstrate(action)
    assert episode.theta_error == pytest.approx(episode.residual_norm, rel=1e-9) and episode.theta_error > 0.1


def test_each_demonstration_is_analysed_as_it_comes():
    skill = SKILLS["uarm-point"]
    episode = TeachingEpisode(skill, seed=1)
    optimal = episode.optimal_actions[0]
    # The optimal arrow turned 90 degrees anticlockwise and halved.
    action = 0.5 * np.array([-optimal[1], optimal[0]])
    analysis = episode.demonstrate(action)
    assert analysis.index == 0 and episode.next_index == 1 and not episode.complete
    np.testing.assert_array_equal(analysis.state, episode.query_states[0])
    np.testing.assert_allclose(analysis.optimal_action, optimal)
    assert analysis.action_difference.angle_deg == pytest.approx(90.0)
    assert analysis.action_difference.magnitude_ratio == pytest.approx(0.5)
    assert analysis.action_difference.error == pytest.approx(np.linalg.norm(action - optimal))
    np.testing.assert_allclose(episode.actions, [action])
    with pytest.raises(EpisodeStateError, match="theta_hat: expected a complete episode"):
        episode.theta_hat
    with pytest.raises(EpisodeStateError, match="reproduction"):
        episode.reproduction
    with pytest.raises(ValueError, match=r"action: expected shape \(2\)"):
        episode.demonstrate([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="action: expected finite numbers"):
        episode.demonstrate([np.nan, 0.0])
    assert len(episode.demonstrations) == 1, "a refused action is not recorded"


def test_the_reproduction_is_rolled_out_once_and_is_the_learnt_skills(monkeypatch):
    skill = SKILLS["uarm-line"]
    calls = []
    original = Skill.reproduce
    monkeypatch.setattr(Skill, "reproduce",
                        lambda self, theta, **kw: calls.append(theta) or original(self, theta, **kw))
    episode = TeachingEpisode(skill, seed=4, duration=3.0)
    episode.restore(episode.optimal_actions + 0.2)
    assert not episode.reproduced and calls == []
    first = episode.reproduction
    assert episode.reproduction is first and episode.reproduction is first
    assert len(calls) == 1 and episode.reproduced
    np.testing.assert_allclose(calls[0], episode.theta_hat)
    reference = original(skill, episode.theta_hat, duration=3.0)
    np.testing.assert_allclose(first.positions, reference.positions)
    assert first.times[-1] == pytest.approx(3.0, abs=0.6)


def test_resuming_from_actions_gives_the_same_episode():
    skill = SKILLS["sim-point"]
    rng = np.random.default_rng(0)
    live = TeachingEpisode(skill, seed=9, lam=0.02)
    actions = rng.normal(size=(5, 2))
    for action in actions:
        live.demonstrate(action)
    resumed = TeachingEpisode.from_actions(skill, live.query_states, actions[:2], lam=0.02)
    assert len(resumed.demonstrations) == 2 and not resumed.complete
    resumed.restore(actions[2:])
    np.testing.assert_allclose(resumed.theta_hat, live.theta_hat, atol=1e-12)
    assert resumed.theta_error == pytest.approx(live.theta_error)
    resumed.restore([])
    with pytest.raises(ValueError, match="actions: expected at most 0 more"):
        resumed.restore(actions[:1])
    with pytest.raises(EpisodeStateError, match="demonstrate"):
        resumed.demonstrate(actions[0])
    with pytest.raises(ValueError, match=r"actions: expected shape \(k, 2\)"):
        TeachingEpisode.from_actions(skill, live.query_states, [1.0, 2.0])


def test_an_episode_of_a_users_own_skill():
    base = SKILLS["sim-point"]
    skill = dataclasses.replace(base, key="mine", theta=base.theta * 0.5)
    episode = TeachingEpisode(skill, seed=2)
    episode.restore(episode.optimal_actions)
    np.testing.assert_allclose(episode.theta_hat, skill.theta, atol=1e-10)


def test_bad_arguments_name_themselves():
    skill = SKILLS["sim-point"]
    with pytest.raises(TypeError, match="skill: expected a mt_widgets.core.Skill, got str"):
        TeachingEpisode("sim-point")
    with pytest.raises(ValueError, match="lam: expected a non-negative"):
        TeachingEpisode(skill, lam=-1)
    with pytest.raises(TypeError, match="lam: expected a real number"):
        TeachingEpisode(skill, lam="0.1")
    with pytest.raises(ValueError, match="duration: expected a positive"):
        TeachingEpisode(skill, duration=0)
    with pytest.raises(ValueError, match=r"query_states: expected shape \(any, 4\)"):
        TeachingEpisode(skill, np.zeros((5, 2)))
    with pytest.raises(ValueError, match="query_states: expected at least one state"):
        TeachingEpisode(skill, np.zeros((0, 4)))
    with pytest.raises(ValueError, match="seed: expected None when query_states are given"):
        TeachingEpisode(skill, skill.query_states(seed=0), seed=1)
    with pytest.raises(ValueError, match="seed"):
        TeachingEpisode(skill, seed=-3)
    episode = TeachingEpisode(skill, seed=0)
    with pytest.raises(ValueError, match="read-only"):  # the states the optimal actions were computed for
        episode.query_states[0, 0] = 1.0


def test_the_ghost_is_the_skills_own_motion_even_when_an_id_is_reused_and_dies_with_the_skill(monkeypatch):
    base = SKILLS["sim-point"]
    slow, fast = (dataclasses.replace(base, theta=base.theta * k) for k in (0.5, 2.0))
    # CPython reuses the id of a freed object: make every skill share one, as a reused id would.
    monkeypatch.setattr(episode_module, "id", lambda obj: 7, raising=False)
    for skill in (slow, fast):
        ghost = episode_module.target_reproduction(skill, 1.0)
        np.testing.assert_allclose(ghost.positions, skill.reproduce(skill.theta, duration=1.0).positions)
    before = len(episode_module._TARGET_ROLLOUTS)
    del slow, fast, skill
    gc.collect()
    assert len(episode_module._TARGET_ROLLOUTS) == before - 2, "the cache keeps ghosts of skills that are gone"


@pytest.mark.parametrize("n_states", [3, 5])
def test_the_episode_and_analyse_demonstrations_compute_through_one_path(n_states):
    # The same numbers to the last bit: one formula for U_bar and the result, not two that agree.
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=2)[:n_states]
    episode = TeachingEpisode(skill, states)
    U = episode.optimal_actions + np.random.default_rng(n_states).normal(size=episode.optimal_actions.shape)
    episode.restore(U)
    reference = analyse_demonstrations(skill.features(states), U, skill.theta, episode.lam)
    assert np.array_equal(episode.optimal_actions, reference.optimal)
    for field in dataclasses.fields(reference):
        assert np.array_equal(getattr(episode.analysis, field.name), getattr(reference, field.name)), field.name
    assert episode.theta_hat is episode.analysis.theta_hat and episode.theta_error == reference.risk
    assert episode.exact == reference.exact and episode.rho1 == reference.rho1
