"""The Panda and the SO-101 on the chain engine: MT exact on every skill, query states, reproductions
that reach their goals, the Panda's null space, the SO-101's kinematic plant, and safety stops."""

import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, TeachingEpisode, optimal_actions, teaching_risk
from mt_widgets.arms import SO101_JOINT_SPEED, panda_plant, so101_plant
from mt_widgets.core.chain_plant import ChainPlant
from mt_widgets.core.features import ToolFeatures
from mt_widgets.core.query_states import condition_number, sample_query_states
from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.core.workspace import Cuboid
from mt_widgets.robot_models.urdf import load_shipped

KEYS = ["panda-reach", "panda-place", "panda-conveyor", "so101-reach", "so101-place"]


def _rest(plant, q):
    return np.concatenate([q] + ([] if plant.kinematic else [np.zeros(plant.n_joints)]))


@pytest.mark.parametrize("key", KEYS)
def test_mt_teaches_every_skill_of_the_panda_and_the_so101_exactly(key):
    skill = SKILLS[key]
    assert skill.theta.shape == (3, skill.n_features) and skill.plant.action_dim == 3
    for seed in range(5):
        states = skill.query_states(seed=seed)
        Phi = skill.features(states)
        for lam in (0.0, 1e-3, 0.1):
            U = optimal_actions(Phi, skill.theta, lam)
            assert teaching_risk(RidgeLearner(lam=lam).fit(Phi, U).theta, skill.theta) < 1e-12
    episode = TeachingEpisode(skill, seed=4)
    for action in episode.optimal_actions:
        episode.demonstrate(action)
    assert episode.theta_error < 1e-12 and not episode.reproduction.diverged


@pytest.mark.parametrize("key", KEYS)
def test_query_states_are_at_rest_above_the_table_reachable_safe_and_well_conditioned(key):
    skill = SKILLS[key]
    plant = skill.plant
    n = plant.n_joints
    for seed in range(5):
        states = skill.query_states(seed=seed)
        if not plant.kinematic:
            assert np.all(states[:, n:2 * n] == 0)
        assert np.all(plant.safety(states) == "") and np.all(plant.is_valid_state(states))
        tool = plant.end_effector(states)[0]
        assert np.all(plant.teaching_box.contains(tool))
        assert condition_number(skill.features(states)) <= skill.max_condition
        singular = np.linalg.svd(plant.chain.jacobian(states[:, :n]), compute_uv=False)
        assert np.all(singular[:, -1] >= plant.min_singular_value)


@pytest.mark.parametrize("key, above", [("panda-place", (0.50, -0.15, 0.27)), ("so101-place", (0.22, -0.08, 0.12))])
def test_the_place_skill_starts_above_the_part_as_the_inverse_kinematics_puts_it(key, above):
    skill = SKILLS[key]
    assert np.linalg.norm(skill.end_effector(skill.start)[0] - np.array(above)) < 1e-4
    np.testing.assert_allclose(skill.start, skill.plant.state_at(above), atol=5e-5)


@pytest.mark.parametrize("key, goal", [("panda-reach", (0.50, -0.15, 0.12)), ("panda-place", (0.40, 0.22, 0.15)),
                                       ("so101-reach", (0.22, -0.08, 0.06)), ("so101-place", (0.18, 0.09, 0.08))])
def test_reproductions_of_the_true_skills_reach_their_goal_within_the_joint_speed_limits(key, goal):
    skill = SKILLS[key]
    trajectory = skill.reproduce(skill.theta)
    assert not trajectory.diverged and trajectory.stop_reason == ""
    assert np.linalg.norm(trajectory.final_position - goal) < 2e-3
    plant = skill.plant
    n = plant.n_joints
    speeds = np.abs(np.diff(trajectory.states[:, :n], axis=0)) / np.diff(trajectory.times)[:, None]
    assert np.all(speeds <= plant.chain.velocity_limit * (1 + plant.speed_tolerance))


def test_the_panda_follows_the_conveyor():
    skill = SKILLS["panda-conveyor"]
    trajectory = skill.reproduce(skill.theta)
    part = skill.plant.conveyor.part_position(trajectory.states[:, -1])
    gap = np.linalg.norm(trajectory.positions - part, axis=1)
    assert gap[0] > 0.2 and np.all(gap[-3000:] < 5e-3)


def test_the_panda_null_space_holds_the_elbow_near_home_without_moving_the_tool():
    # The same tool path with and without the null-space pull: the tool's motion is the same (the
    # damped least squares' own error aside), the joints end nearer home with it.
    skill = SKILLS["panda-reach"]
    held, free = skill.plant, panda_plant()
    free.null_gain = 0.0
    with_pull = held.rollout(skill.theta[None], ToolFeatures(held), skill.start, 10.0)[0]
    without = free.rollout(skill.theta[None], ToolFeatures(free), skill.start, 10.0)[0]
    assert np.linalg.norm(with_pull.final_position - without.final_position) < 2e-3
    home = held.home
    assert np.linalg.norm(with_pull.states[-1, :7] - home) < np.linalg.norm(without.states[-1, :7] - home)
    # the pull alone (no tool velocity) leaves the tool where it is: the projector is exact
    q = np.array(home) + np.array([0.3, 0.2, -0.3, 0.2, 0.3, -0.2, 0.1])
    reference = held.joint_velocity_reference(q, np.zeros(3))
    assert np.linalg.norm(reference) > 0.1
    assert np.linalg.norm(held.chain.jacobian(q) @ reference) < 1e-12 * np.linalg.norm(reference)


def test_the_so101_is_a_kinematic_plant_whose_joints_follow_the_resolved_rate():
    plant = SKILLS["so101-reach"].plant
    assert plant.kinematic and plant.state_dim == 5 and plant.state_names == ("q1", "q2", "q3", "q4", "q5")
    assert plant.chain.tip == "gripper_frame_link" and np.all(plant.chain.velocity_limit == SO101_JOINT_SPEED)
    q = plant.home
    velocity = np.array([0.02, -0.01, 0.01])
    # the joints' speeds move the tool at the commanded velocity (to the damping's order)
    reference = plant.joint_velocity_reference(q, velocity)
    np.testing.assert_allclose(plant.chain.jacobian(q) @ reference, velocity, atol=2e-4)
    # the compiled rollout equals the generic RK4 loop of the same derivative
    theta = SKILLS["so101-reach"].theta[None]
    compiled = plant.rollout(theta, ToolFeatures(plant), q, 0.2)
    generic = ChainPlant.__mro__[1].rollout(plant, theta, ToolFeatures(plant), q, 0.2)
    np.testing.assert_allclose(compiled.states, generic.states, rtol=0, atol=1e-12)


def test_driving_the_so101_into_the_table_stops_at_the_table_without_nan():
    skill = SKILLS["so101-reach"]
    down = np.zeros((3, 4))
    down[2, 3] = -0.1
    trajectory = skill.reproduce(down)
    assert trajectory.diverged and trajectory.stop_reason == "table"
    assert np.all(np.isfinite(trajectory.states))
    assert trajectory.positions[-1, 2] >= skill.plant.link_radius - 1e-9


def test_a_so101_joint_at_the_end_of_its_range_stops_the_rollout():
    plant = so101_plant()
    plant.chain.lower = plant.chain.lower.copy()
    plant.chain.lower[0] = -0.2   # the shoulder may pan only 0.2 rad to the left (its axis points down)
    theta = np.zeros((3, 4))
    theta[1, 3] = 0.05
    batch = plant.rollout(theta[None], ToolFeatures(plant), plant.home, 5.0)
    assert batch.diverged[0] and batch.stop_reasons[0] == "joint limit"
    assert -0.2 <= batch[0].states[-1, 0] < -0.19


def test_bad_input_is_refused_by_name():
    skill = SKILLS["so101-reach"]
    with pytest.raises(ValueError, match=r"states: expected shape \(any, 5\)"):
        skill.features(np.zeros((2, 6)))
    beyond = skill.plant.home.copy()
    beyond[2] = 2.0
    with pytest.raises(ValueError, match=r"states: expected joint elbow_flex within \[-1.69, 1.69\] rad, got 2"):
        skill.features(beyond[None, :])
    with pytest.raises(ValueError, match="position: expected a point the tool can reach"):
        skill.plant.state_at((0.8, 0.0, 0.1))
    with pytest.raises(ValueError, match=r"home: expected joint shoulder_pan within"):
        ChainPlant(skill.plant.chain, [3.0, 0, 0, 0, 0], skill.plant.teaching_box, skill.plant.scene_box)
    with pytest.raises(ValueError, match="query_margin: expected a non-negative finite number, got -0.1"):
        ChainPlant(skill.plant.chain, skill.plant.home, skill.plant.teaching_box, skill.plant.scene_box,
                   query_margin=-0.1)
    with pytest.raises(ValueError, match="query_margin: expected less than half of every joint's range, got 2.0"):
        ChainPlant(skill.plant.chain, skill.plant.home, skill.plant.teaching_box, skill.plant.scene_box,
                   query_margin=2.0)
    with pytest.raises(TypeError, match="kinematic: expected"):
        ChainPlant(skill.plant.chain, skill.plant.home, skill.plant.teaching_box, skill.plant.scene_box, kinematic=1)
    description = load_shipped("so101")
    description["inertials"] = [inertial | {"mass": 0.0} for inertial in description["inertials"]]
    massless = SerialChain.from_description(description, dynamics=False)
    with pytest.raises(ValueError, match=r"so101.urdf: kinematic=False needs the chain's dynamics"):
        ChainPlant(massless, skill.plant.home, skill.plant.teaching_box, skill.plant.scene_box)


def test_an_arm_asked_to_teach_out_of_its_reach_is_told_so():
    reach = SKILLS["so101-reach"]
    plant = reach.plant
    far = ChainPlant(plant.chain, plant.home, Cuboid((0.8, 0.9), (-0.1, 0.1), (0.05, 0.1)), plant.scene_box,
                     robot="so101", kinematic=True, link_radius=0.015)
    with pytest.raises(ValueError, match=r"plant: expected valid candidate states \(is_valid_state\), got none of "
                                         r"400 sampled: is the workspace within the robot's reach"):
        sample_query_states(far, ToolFeatures(far), 4, seed=0, max_condition=50.0, max_candidates=400, block=200)
