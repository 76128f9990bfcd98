"""Skills beyond linear features: only a nonlinear learner represents their targets."""

import numpy as np
import pytest

from mt_widgets.core import SKILLS, Skill
from mt_widgets.core.episode import target_reproduction
from mt_widgets.core.learner_teaching import evaluation_states, make_learner, policy_risk, teach
from mt_widgets.core.nonlinear_skills import NONLINEAR_SKILLS, ArcReach, best_linear_theta
from mt_widgets.core.skills import PAPER_SKILL_KEYS

KEYS = ["sim-curve", "sim-obstacle", "uarm-curve", "uarm-obstacle"]


def test_the_nonlinear_skills_are_a_registry_of_their_own_and_skills_keeps_its_four():
    assert list(NONLINEAR_SKILLS) == KEYS
    # SKILLS keeps the paper's four (and the UR5's), and holds none of these
    assert set(PAPER_SKILL_KEYS) <= set(SKILLS) and not set(KEYS) & set(SKILLS)
    with pytest.raises(TypeError, match="read-only"):
        NONLINEAR_SKILLS.add(SKILLS["sim-point"])
    assert all(not NONLINEAR_SKILLS[k].linear for k in KEYS) and all(SKILLS[k].linear for k in SKILLS)


@pytest.mark.parametrize("key", KEYS)
def test_theta_is_the_best_linear_policy_and_it_misses_the_target(key):
    skill = NONLINEAR_SKILLS[key]
    states = skill.plant.sample_states(np.random.default_rng(0), 2048)
    states = states[skill.plant.is_valid_state(states)]
    Phi = skill.features(states)
    # The normal equations of least squares: the residual is orthogonal to every feature.
    residual = skill.target_actions(states) - Phi @ skill.theta.T
    assert np.abs(Phi.T @ residual).max() < 1e-8 * np.abs(Phi).sum()
    evaluation = evaluation_states(skill)
    target = skill.target_actions(evaluation)
    floor = policy_risk(skill.features(evaluation) @ skill.theta.T, target)
    assert floor > 0.1 * policy_risk(np.zeros_like(target), target)   # not linear in the features


@pytest.mark.parametrize("key", KEYS)
@pytest.mark.parametrize("name", ["kernel-ridge", "gaussian-process"])
def test_with_enough_states_a_kernel_learner_is_taught_beyond_what_ridge_can_learn(key, name):
    skill = NONLINEAR_SKILLS[key]
    query = skill.query_states(seed=1, n=40)
    evaluation = evaluation_states(skill)
    floor = policy_risk(skill.features(evaluation) @ skill.theta.T, skill.target_actions(evaluation))
    ridge = teach(make_learner("ridge"), skill, query)
    kernel = teach(make_learner(name, skill), skill, query)
    assert ridge.risk > 0.98 * floor    # no demonstration teaches ridge below its best linear policy
    assert kernel.risk < 0.9 * floor


@pytest.mark.parametrize("key", ["uarm-curve", "uarm-obstacle"])
def test_the_uarm_targets_reach_their_point_along_a_curve_the_best_linear_policy_does_not_draw(key):
    skill = NONLINEAR_SKILLS[key]
    path = skill.reproduce_policy(skill.policy).positions
    assert skill.target.distance(path[-1]) < 0.3
    linear = skill.reproduce(skill.theta).positions
    if key == "uarm-obstacle":   # around the obstacle at (20, 0.5) cm; the linear policy grazes its centre
        assert np.linalg.norm(path - [20.0, 0.5], axis=1).min() > 3.0
        assert np.linalg.norm(linear - [20.0, 0.5], axis=1).min() < 1.0
    else:                        # along the arc: the distance from the base stays between start and goal
        radius = np.linalg.norm(path, axis=1)
        assert radius.min() > np.hypot(18, -10) - 0.2 and radius.max() < np.hypot(23, 11) + 0.2
        assert np.linalg.norm(linear, axis=1).max() > np.hypot(23, 11) + 0.3   # overshoots, off the arc


@pytest.mark.slow
def test_the_simulated_arm_goes_around_its_obstacle():
    skill = NONLINEAR_SKILLS["sim-obstacle"]
    path = skill.reproduce_policy(skill.policy, record_every=10).positions
    assert skill.target.distance(path[-1]) < 0.1
    assert np.linalg.norm(path - [0.3, 1.3], axis=1).min() > 0.3


def test_a_policy_must_be_callable_and_give_actions_of_the_plants_shape():
    base = SKILLS["uarm-point"]
    with pytest.raises(TypeError, match="policy: expected a function"):
        Skill("x", "x", base.plant, base.feature_map, base.theta, base.start, policy=3)
    wrong = Skill("x", "x", base.plant, base.feature_map, base.theta, base.start, policy=lambda s: s[:, :1])
    with pytest.raises(ValueError, match="actions returned by policy: expected shape"):
        wrong.target_actions(base.query_states(seed=0))
    arc = ArcReach(base.plant, (23.0, 11.0), 0.25, 0.25)
    assert best_linear_theta(base.plant, base.feature_map, arc).shape == (2, 3)


def test_an_episodes_target_rollout_is_the_target_policys_not_its_best_linear_theta():
    skill = NONLINEAR_SKILLS["uarm-obstacle"]
    drawn = target_reproduction(skill).positions
    np.testing.assert_allclose(drawn, skill.reproduce_policy(skill.policy).positions)
    assert np.abs(drawn - skill.reproduce(skill.theta).positions).max() > 1.0
