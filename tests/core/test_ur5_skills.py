"""The UR5 on its production line: MT exact on every ur5- skill, reproductions as pinocchio steps them,
safety stops that leave no NaN, and bad input refused by name."""

import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, TeachingEpisode, optimal_actions, teaching_risk
from mt_widgets.arms import UR5Plant
from mt_widgets.core import FunctionFeatures
from mt_widgets.core.features import ToolFeatures
from mt_widgets.core.query_states import condition_number

UR5_KEYS = ["ur5-reach", "ur5-place", "ur5-conveyor"]


@pytest.mark.parametrize("key", UR5_KEYS)
def test_mt_teaches_every_ur5_skill_exactly(key):
    skill = SKILLS[key]
    assert skill.theta.shape == (3, skill.n_features) and skill.plant.action_dim == 3
    for seed in range(10):
        states = skill.query_states(seed=seed)
        Phi = skill.features(states)
        for lam in (0.0, 1e-3, 0.1):
            U = optimal_actions(Phi, skill.theta, lam)
            assert teaching_risk(RidgeLearner(lam=lam).fit(Phi, U).theta, skill.theta) < 1e-12
        # and a teacher who shows the skill's own actions teaches it only up to ridge's shrinkage
        shrunk = teaching_risk(RidgeLearner(lam=0.1).fit(Phi, skill.target_actions(states)).theta, skill.theta)
        assert shrunk > 1e-6


@pytest.mark.parametrize("key", UR5_KEYS)
def test_a_teaching_episode_runs_on_the_arm(key):
    skill = SKILLS[key]
    episode = TeachingEpisode(skill, seed=4)
    for action in episode.optimal_actions:
        demonstration = episode.demonstrate(action)
        assert demonstration.action_difference is None   # arrows in space: no planar angle
    assert episode.theta_error < 1e-12
    trajectory = episode.reproduction
    assert not trajectory.diverged and trajectory.positions.shape[1] == 3


@pytest.mark.parametrize("key", UR5_KEYS)
def test_query_states_are_at_rest_above_the_table_reachable_safe_and_well_conditioned(key):
    skill = SKILLS[key]
    plant = skill.plant
    for seed in range(20):
        states = skill.query_states(seed=seed)
        assert np.all(states[:, 6:12] == 0)
        assert np.all(plant.safety(states) == "") and np.all(plant.is_valid_state(states))
        tool = plant.end_effector(states)[0]
        assert np.all(plant.teaching_box.contains(tool)) and np.all(tool[:, 2] >= 0.05)
        assert np.all(plant.chain_points(states)[:, 3:, 2] > plant.table_height + plant.link_radius)
        assert condition_number(skill.features(states)) <= skill.max_condition
        singular = np.linalg.svd(plant.chain.jacobian(states[:, :6]), compute_uv=False)
        assert np.all(singular[:, -1] >= plant.min_singular_value)


def test_the_thresholds_are_about_the_median_condition_number():
    rng = np.random.default_rng(0)
    for key in UR5_KEYS:
        skill = SKILLS[key]
        candidates = skill.plant.sample_states(rng, 600)
        candidates = candidates[skill.plant.is_valid_state(candidates)]
        conditions = [condition_number(skill.features(candidates[rng.choice(len(candidates), skill.n_features,
                                                                             replace=False)])) for _ in range(300)]
        assert 0.3 < np.mean(np.array(conditions) > skill.max_condition) < 0.7


@pytest.mark.parametrize("key, goal", [("ur5-reach", (0.55, -0.10, 0.10)), ("ur5-place", (0.40, 0.35, 0.12))])
def test_reproductions_of_the_true_skills_reach_their_goal(key, goal):
    trajectory = SKILLS[key].reproduce(SKILLS[key].theta)
    assert not trajectory.diverged and trajectory.stop_reason == ""
    assert np.linalg.norm(trajectory.final_position - goal) < 2e-3
    limits = SKILLS[key].plant.chain.velocity_limit
    assert np.all(np.abs(trajectory.states[:, 6:12]) <= limits)


def test_the_place_skill_starts_with_the_tool_above_the_part_as_the_inverse_kinematics_puts_it():
    skill = SKILLS["ur5-place"]
    above = np.array([0.55, -0.10, 0.25])
    assert np.linalg.norm(skill.end_effector(skill.start)[0] - above) < 1e-4
    np.testing.assert_allclose(skill.start, skill.plant.state_at(above), atol=5e-5)


def test_the_conveyor_skill_rides_with_the_part():
    skill = SKILLS["ur5-conveyor"]
    trajectory = skill.reproduce(skill.theta)
    part = skill.plant.conveyor.part_position(trajectory.states[:, -1])
    gap = np.linalg.norm(trajectory.positions - part, axis=1)
    assert gap[0] > 0.3 and np.all(gap[-3000:] < 5e-3)       # caught up and stays with it
    assert trajectory.states[-1, -1] == pytest.approx(0.5)    # the belt moved 0.5 m in 10 s
    np.testing.assert_allclose(trajectory.velocities[-1], [0.0, 0.05, 0.0], atol=2e-3)


@pytest.mark.parametrize("size", [2, 6])   # 6: over chain_rollout.PARALLEL_FROM, spread over the cores
def test_a_batch_rolls_out_each_theta_as_alone(size):
    skill = SKILLS["ur5-reach"]
    thetas = np.stack([skill.theta * (1 + 0.2 * k) for k in range(size - 1)] + [_constant([0.0, 0.0, -0.3])])
    batch = skill.reproduce(thetas, duration=2.0)
    for k in (1, size - 1):
        alone = skill.reproduce(thetas[k], duration=2.0)
        np.testing.assert_array_equal(batch[k].states, alone.states)
        assert batch[k].stop_reason == alone.stop_reason
    assert batch.stop_reasons[-1] == "table" and not batch.diverged[:-1].any()


# -- safety stops --------------------------------------------------------------------------------

def _constant(velocity, features=4):
    theta = np.zeros((3, features))
    theta[:, -1] = velocity
    return theta


def test_driving_the_tool_into_the_table_stops_at_the_table_without_nan():
    skill = SKILLS["ur5-reach"]
    trajectory = skill.reproduce(_constant([0.0, 0.0, -0.3]))
    assert trajectory.diverged and trajectory.stop_reason == "table"
    assert np.all(np.isfinite(trajectory.states)) and np.all(np.isfinite(trajectory.positions))
    assert trajectory.positions[-1, 2] >= skill.plant.link_radius - 1e-9
    assert trajectory.positions[-1, 2] < skill.plant.link_radius + 1e-3   # stopped at the table, not before


def test_pushing_a_folded_arm_back_stops_at_a_self_collision():
    plant = UR5Plant()
    # The elbow folded (2.2 rad), the wrist tipped up: the tool at (0.23, 0.11, 0.37) m, in front
    # of the upper arm; moving the tool back towards the base drives the wrist into the upper arm.
    folded = plant.home.copy()
    folded[2], folded[3] = 2.2, 1.0
    start = np.concatenate([folded, np.zeros(6)])
    assert plant.safety(start) == ""
    batch = plant.rollout(_constant([-0.3, 0.0, 0.0])[None], ToolFeatures(plant), start, 5.0)
    assert batch.diverged[0] and batch.stop_reasons[0] == "self-collision"
    assert np.all(np.isfinite(batch.states)) and plant.safety(batch[0].states[-1]) == ""


def test_a_joint_at_the_end_of_its_range_stops_the_rollout():
    plant = UR5Plant()
    plant.chain.lower = plant.chain.lower.copy()
    plant.chain.lower[0] = -0.3   # the shoulder pan may turn only 0.3 rad to the right
    start = np.concatenate([plant.home, np.zeros(6)])
    batch = plant.rollout(_constant([0.0, -0.3, 0.0])[None], ToolFeatures(plant), start, 5.0)
    assert batch.diverged[0] and batch.stop_reasons[0] == "joint limit"
    last = batch[0].states[-1]
    assert -0.3 <= last[0] < -0.29


def test_a_fast_command_is_held_to_the_joint_speed_limits():
    skill = SKILLS["ur5-reach"]
    trajectory = skill.reproduce(_constant([0.0, -5.0, 0.0]), duration=2.0)
    limits = skill.plant.chain.velocity_limit
    assert np.abs(trajectory.states[:, 6:12]).max(axis=0).max() > 0.5 * limits.min()
    assert np.all(np.abs(trajectory.states[:, 6:12]) <= limits * (1 + skill.plant.speed_tolerance))


def test_an_overflowing_policy_stops_as_diverged_with_finite_arrays():
    skill = SKILLS["ur5-reach"]
    trajectory = skill.reproduce(_constant([1e308, 0.0, 0.0]))
    assert trajectory.diverged and trajectory.stop_reason == "diverged" and trajectory.diverged_at == 0.001
    assert np.all(np.isfinite(trajectory.states)) and len(trajectory) == 1


def test_safety_names_each_kind_of_unsafe_state():
    plant = SKILLS["ur5-reach"].plant
    home = np.concatenate([plant.home, np.zeros(6)])
    beyond = home.copy()
    beyond[2] = 3.2                       # the elbow's range is +-pi
    fast = home.copy()
    fast[6] = 4.0                         # the pan's speed limit is 3.15 rad/s
    down = home.copy()
    down[1] = 0.3                         # the upper arm tipped below the table top
    nan = home.copy()
    nan[7] = np.nan
    assert plant.safety(np.stack([home, beyond, fast, down, nan])).tolist() == [
        "", "joint limit", "joint speed limit", "table", "diverged"]


# -- bad input -------------------------------------------------------------------------------------

def test_bad_input_is_refused_with_the_argument_the_expectation_and_what_came():
    skill = SKILLS["ur5-reach"]
    with pytest.raises(ValueError, match=r"states: expected shape \(any, 12\).*got \(2, 11\)"):
        skill.features(np.zeros((2, 11)))
    beyond = np.concatenate([skill.plant.home, np.zeros(6)])
    beyond[2] = 4.0
    with pytest.raises(ValueError, match=r"states: expected joint elbow_joint within \[-3.142, 3.142\] rad, got 4"):
        skill.features(beyond[None, :])
    with pytest.raises(ValueError, match=r"start: expected joint elbow_joint within"):
        skill.plant.rollout(skill.theta[None], skill.feature_map, beyond, 1.0)
    episode = TeachingEpisode(skill, seed=0)
    with pytest.raises(ValueError, match=r"action: expected shape \(3\)"):
        episode.check_action([0.1, 0.2])
    with pytest.raises(ValueError, match="action: expected finite numbers"):
        episode.check_action([0.1, np.nan, 0.2])
    with pytest.raises(TypeError, match="action: expected an array of numbers"):
        episode.check_action(["up", "left", "down"])
    with pytest.raises(KeyError, match=r"skill: expected one of the known skills .*ur5-reach.*got 'ur5-weld'"):
        SKILLS["ur5-weld"]
    with pytest.raises(ValueError, match="phase: this plant has no conveyor"):
        skill.plant.state_at((0.5, 0.0, 0.2), phase=0.1)
    with pytest.raises(ValueError, match="position: expected a point the tool can reach"):
        skill.plant.state_at((3.0, 0.0, 0.2))


def test_the_compiled_rollout_equals_the_generic_rollout_of_a_users_feature_map():
    skill = SKILLS["ur5-conveyor"]
    plant = skill.plant
    # The same features, as a user would write them: the generic RK4 loop of ContinuousPlant runs.
    mine = FunctionFeatures(plant, lambda x: np.concatenate([plant.end_effector(x)[0], x[:, -1:], np.ones((len(x), 1))],
                                                            axis=1), names=("r1", "r2", "r3", "s", "1"))
    thetas = np.stack([skill.theta, skill.theta + 0.2])
    compiled = plant.rollout(thetas, skill.feature_map, skill.start, 0.3)
    generic = plant.rollout(thetas, mine, skill.start, 0.3)
    np.testing.assert_allclose(generic.states, compiled.states, rtol=0, atol=1e-12)
    np.testing.assert_allclose(generic.actions, compiled.actions, rtol=0, atol=1e-12)
    # and the generic loop stops at the table too, through the plant's safety check
    down = np.zeros((1, 3, 5))
    down[0, 2, 4] = -0.3
    stopped = plant.rollout(down, mine, plant.state_at((0.5, 0.1, 0.07), phase=0.0), 0.3)
    assert stopped.diverged[0] and np.all(np.isfinite(stopped.states))
    assert np.all(plant.safety(stopped[0].states) == "")
