"""Rollouts: energy conservation, the compiled path against the generic one, divergence, batches."""

import numpy as np
import pytest

from mt_widgets import SKILLS, TwoLinkArm
from mt_widgets.core import ArmPlant, EndEffectorFeatures, FunctionFeatures, UArmPlant
from mt_widgets.core.uarm_plant import UARM_WORKSPACE_CM


def energy_drift(gravity: float) -> float:
    arm = TwoLinkArm(gravity=gravity, gravity_compensation=False)
    plant = ArmPlant(arm)
    start = np.array([0.4, 1.1, 1.5, -2.0])
    trajectory = plant.rollout(np.zeros((1, 2, 5)), EndEffectorFeatures(plant), start, 10.0)[0]
    q, qd = trajectory.states[:, :2], trajectory.states[:, 2:]
    energy = arm.kinetic_energy(q, qd) + arm.potential_energy(q)
    assert np.ptp(q[:, 1]) > 1.0, "the test motion should swing the arm, not sit still"
    scale = np.max(arm.kinetic_energy(q, qd))  # the energy that moves around the system
    return float(np.max(np.abs(energy - energy[0])) / scale)


@pytest.mark.slow
def test_energy_is_conserved_without_gravity():
    assert energy_drift(0.0) < 1e-9


def test_energy_is_conserved_with_gravity():
    assert energy_drift(9.81) < 1e-6


@pytest.mark.slow
def test_the_compiled_rollout_equals_the_generic_numpy_rollout():
    # The same features given as a user function take the generic RK4 path written in numpy.
    skill = SKILLS["sim-point"]
    plant = skill.plant
    generic = FunctionFeatures(plant, EndEffectorFeatures(plant), names=EndEffectorFeatures.names)
    theta = skill.theta + np.random.default_rng(0).normal(scale=0.3, size=skill.theta.shape)
    fast = plant.rollout(theta[None], skill.feature_map, skill.start, 2.0)[0]
    slow = plant.rollout(theta[None], generic, skill.start, 2.0)[0]
    np.testing.assert_allclose(fast.states, slow.states, rtol=0, atol=1e-11)
    np.testing.assert_allclose(fast.actions, slow.actions, rtol=0, atol=1e-10)


def test_sim_point_reaches_its_target_within_5_cm_in_10_s():
    skill = SKILLS["sim-point"]
    trajectory = skill.reproduce(skill.theta, duration=10.0)
    assert not trajectory.diverged
    assert trajectory.times[-1] == pytest.approx(10.0)
    assert np.linalg.norm(trajectory.positions[-1] - [0.8, 1.2]) < 0.05
    assert np.linalg.norm(trajectory.positions[0] - [0.8, 1.2]) > 0.5


def test_sim_line_ends_on_its_line():
    skill = SKILLS["sim-line"]
    trajectory = skill.reproduce(skill.theta)
    assert abs(trajectory.positions[-1, 0] - 0.8) < 0.05
    assert abs(trajectory.positions[0, 0] - 0.8) > 0.5


def test_without_gravity_compensation_the_paper_skill_lets_the_arm_hang():
    raw = ArmPlant(TwoLinkArm(gravity_compensation=False))
    skill = SKILLS["sim-point"]
    trajectory = raw.rollout(skill.theta[None], EndEffectorFeatures(raw), skill.start, 10.0)[0]
    np.testing.assert_allclose(trajectory.positions[-1], [0.31, -1.96], atol=0.02)


def test_a_wild_theta_is_flagged_diverged_and_stays_finite():
    skill = SKILLS["sim-point"]
    trajectory = skill.reproduce(-3 * skill.theta)
    assert trajectory.diverged and 0 < trajectory.diverged_at < 10
    assert len(trajectory) < 10001
    for array in (trajectory.states, trajectory.positions, trajectory.velocities, trajectory.actions):
        assert np.all(np.isfinite(array))


def test_a_batch_equals_the_same_rollouts_one_by_one():
    skill = SKILLS["sim-point"]
    thetas = skill.theta + np.random.default_rng(1).normal(scale=0.5, size=(4, 2, 5))
    thetas[2] = -3 * skill.theta  # one diverges inside the batch
    batch = skill.reproduce(thetas, duration=3.0)
    assert batch.diverged.tolist() == [False, False, True, False]
    for i in range(4):
        single = skill.reproduce(thetas[i], duration=3.0)
        np.testing.assert_array_equal(batch[i].states, single.states)
        np.testing.assert_array_equal(batch[i].actions, single.actions)
        assert batch[i].diverged == single.diverged
    assert np.all(np.isfinite(batch.states))


def test_recording_every_nth_step_keeps_the_same_samples():
    skill = SKILLS["sim-line"]
    dense = skill.reproduce(skill.theta, duration=1.0)
    sparse = skill.reproduce(skill.theta, duration=1.0, record_every=10)
    np.testing.assert_array_equal(sparse.states, dense.states[::10])
    np.testing.assert_allclose(sparse.times, dense.times[::10])


@pytest.mark.parametrize("key", ["uarm-point", "uarm-line"])
def test_uarm_skills_reach_their_target_and_stay_in_the_workspace(key):
    skill = SKILLS[key]
    trajectory = skill.reproduce(skill.theta)
    assert skill.target.distance(trajectory.positions[-1]) < 0.5  # cm, after 20 steps at 0.8 per step
    assert np.all(UARM_WORKSPACE_CM.contains(trajectory.positions))


def test_uarm_steps_are_limited_and_the_workspace_is_never_left():
    plant = UArmPlant()
    skill = SKILLS["uarm-point"]
    wild = np.array([[3.0, 0.0, 10.0], [0.0, -2.0, 40.0]])
    trajectory = skill.reproduce(wild)
    steps = np.linalg.norm(np.diff(trajectory.positions, axis=0), axis=1)
    assert np.all(steps <= plant.max_step_cm + 1e-9)
    assert np.all(UARM_WORKSPACE_CM.contains(trajectory.positions))
    assert not trajectory.diverged


def test_bad_rollout_input_is_refused_by_name():
    skill = SKILLS["sim-point"]
    with pytest.raises(ValueError, match="theta"):
        skill.reproduce(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="theta: expected finite"):
        skill.reproduce(np.full((2, 5), np.nan))
    with pytest.raises(ValueError, match="duration"):
        skill.reproduce(skill.theta, duration=-1)


def test_batches_rolled_out_from_several_threads_at_once_are_right():
    from concurrent.futures import ThreadPoolExecutor

    skill = SKILLS["sim-point"]
    thetas = skill.theta + np.random.default_rng(3).normal(scale=0.3, size=(4, 16, 2, 5))
    with ThreadPoolExecutor(4) as pool:
        batches = list(pool.map(lambda t: skill.reproduce(t, duration=0.5), thetas))
    for t, batch in zip(thetas, batches):
        np.testing.assert_array_equal(batch.states, skill.reproduce(t, duration=0.5).states)
