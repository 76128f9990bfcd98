"""Query states, the seed schedule, and the paper's skills."""

import json
from pathlib import Path

import numpy as np
import pytest

from mt_widgets import SKILLS, SeedSchedule
from mt_widgets.core import FunctionFeatures, Skill, condition_number, sample_query_states

PAPER = json.loads((Path(__file__).parents[2] / "tests" / "data" / "paper_skills.json").read_text())


@pytest.mark.parametrize("key", list(PAPER))
def test_skills_carry_the_papers_theta(key):
    # The paper gives vec(Theta), stacking columns.
    np.testing.assert_array_equal(SKILLS[key].theta.flatten(order="F"), PAPER[key]["vec_theta"])


@pytest.mark.parametrize("key", list(SKILLS))
def test_every_accepted_query_set_is_under_the_threshold_and_valid(key):
    skill = SKILLS[key]
    for seed in range(40):
        states = skill.query_states(seed=seed)
        assert states.shape == (skill.n_features, skill.state_dim)
        Phi = skill.features(states)
        for k in range(2, len(states) + 1):  # every partial set too, as accepted one by one
            assert condition_number(Phi[:k]) <= skill.max_condition
        assert np.all(skill.plant.is_valid_state(states))


def test_the_threshold_actually_rejects_states():
    skill = SKILLS["sim-point"]
    rng = np.random.default_rng(0)
    unfiltered = [condition_number(skill.features(skill.plant.sample_states(rng, 5))) for _ in range(300)]
    assert np.mean(np.array(unfiltered) > skill.max_condition) > 0.2


def test_the_same_seed_gives_the_same_states_and_other_seeds_others():
    skill = SKILLS["sim-point"]
    np.testing.assert_array_equal(skill.query_states(seed=7), skill.query_states(seed=7))
    assert not np.allclose(skill.query_states(seed=7), skill.query_states(seed=8))


def test_the_seed_schedule_gives_every_phase_and_episode_its_own_states():
    schedule = SeedSchedule(2025)
    skill = SKILLS["uarm-point"]
    sets = {(p, e): skill.query_states(seed=schedule.seed(p, e)) for p in range(5) for e in range(3)}
    keys = list(sets)
    for i, a in enumerate(keys):
        for b in keys[i + 1:]:
            assert not np.allclose(sets[a], sets[b]), (a, b)
    again = SeedSchedule(2025)
    np.testing.assert_array_equal(skill.query_states(seed=again.seed(3, 1)), sets[(3, 1)])
    assert not np.allclose(skill.query_states(seed=SeedSchedule(2026).seed(3, 1)), sets[(3, 1)])
    assert not np.allclose(skill.query_states(seed=schedule.seed(3, 1, participant=4)), sets[(3, 1)])


def test_an_impossible_threshold_fails_with_a_clear_message():
    skill = SKILLS["sim-point"]
    with pytest.raises(ValueError, match="max_condition"):
        sample_query_states(skill.plant, skill.feature_map, 5, seed=0, max_condition=1.0001, max_candidates=200)
    with pytest.raises(ValueError, match="seed"):
        skill.query_states(seed="abc")
    with pytest.raises(ValueError, match="n: expected a whole number"):
        skill.query_states(seed=0, n=0)


def test_features_and_target_actions_have_the_documented_shapes():
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=1)
    Phi = skill.features(states)
    assert Phi.shape == (5, 5) and np.all(Phi[:, 4] == 1)
    positions, velocities = skill.end_effector(states)
    np.testing.assert_array_equal(Phi[:, :2], positions)
    np.testing.assert_array_equal(Phi[:, 2:4], velocities)
    np.testing.assert_allclose(skill.target_actions(states), -(positions - [0.8, 1.2]) - velocities)
    with pytest.raises(ValueError, match="states"):
        skill.features(np.zeros((3, 2)))


def test_a_user_defines_a_new_skill_in_a_few_lines():
    base = SKILLS["sim-point"]
    features = FunctionFeatures(base.plant, lambda x: np.c_[base.end_effector(x)[0], np.ones(len(x))],
                                names=("r1", "r2", "1"))
    skill = Skill("sim-spring", "A stiff spring to (0, 1.5)", base.plant, features,
                  [[-2.0, 0.0, 0.0], [0.0, -2.0, 3.0]], base.start, max_condition=50)
    states = skill.query_states(seed=0)
    assert states.shape == (3, 4)
    trajectory = skill.reproduce(skill.theta, duration=1.0)
    assert trajectory.positions.shape == (1001, 2) and not trajectory.diverged
    with pytest.raises(ValueError, match="theta"):
        Skill("bad", "bad", base.plant, features, np.zeros((2, 5)), base.start)


@pytest.mark.slow
@pytest.mark.parametrize("key", ["sim-point", "uarm-point"])
def test_no_seed_dead_ends(key):
    # Before backtracking, about 1 uArm seed in 750 found no well-conditioned third state.
    skill = SKILLS[key]
    for seed in range(1500):
        assert skill.query_states(seed=seed).shape == (skill.n_features, skill.state_dim)


def test_backtracking_still_returns_well_conditioned_sets():
    skill = SKILLS["uarm-point"]
    for seed in range(50):
        # patience=1 backtracks after every rejected candidate: the hardest path through the code.
        states = sample_query_states(skill.plant, skill.feature_map, 3, seed=seed, max_condition=skill.max_condition,
                                     patience=1)
        Phi = skill.features(states)
        assert all(condition_number(Phi[:k]) <= skill.max_condition for k in range(2, 4))
