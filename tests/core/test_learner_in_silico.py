"""In silico: per learner, MT's demonstration leaves less risk than the target's own actions and
than random actions, over random query sets of every skill (the paper's four and the nonlinear four)."""

import numpy as np
import pytest

from mt_widgets.core import SKILLS
from mt_widgets.core.learner_teaching import compare_with_baselines, make_learner
from mt_widgets.core.network_learner import NeuralNetworkLearner
from mt_widgets.core.nonlinear_skills import NONLINEAR_SKILLS

ALL_SKILLS = {**SKILLS, **NONLINEAR_SKILLS}


def _check(comparison):
    assert np.all(comparison.mt < comparison.target) and np.all(comparison.mt < comparison.random)
    assert comparison.target_factor > 1.0 and comparison.random_factor > 1.0


@pytest.mark.parametrize("key", ["uarm-point", "uarm-obstacle"])
def test_approximate_mt_beats_the_target_and_random_actions_on_a_few_sets(key):
    _check(compare_with_baselines(NeuralNetworkLearner(steps=100), ALL_SKILLS[key], n_sets=3, iterations=2))


@pytest.mark.slow
@pytest.mark.parametrize("key", list(ALL_SKILLS))
def test_approximate_mt_beats_the_target_and_random_actions_over_100_query_sets(key):
    comparison = compare_with_baselines(NeuralNetworkLearner(), ALL_SKILLS[key], n_sets=100, iterations=3)
    _check(comparison)
    print(f"{key}: neural network, target/MT {comparison.target_factor:.2f}, random/MT {comparison.random_factor:.2f}")


@pytest.mark.parametrize("key", list(ALL_SKILLS))
@pytest.mark.parametrize("name", ["ridge", "kernel-ridge", "gaussian-process"])
def test_exact_mt_beats_the_target_and_random_actions_over_100_query_sets(name, key):
    skill = ALL_SKILLS[key]
    comparison = compare_with_baselines(make_learner(name, skill), skill, n_sets=100)
    # Least squares: never above the target's actions (equal only when the ridge shrinkage is nil).
    assert np.all(comparison.mt <= comparison.target * (1 + 1e-12)) and np.all(comparison.mt < comparison.random)
    assert comparison.target_factor > 1.0
