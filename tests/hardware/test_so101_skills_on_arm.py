"""The SO-101's skills on the arm: every query state is one its envelope lets it go to, and the
reproduction of a nearly right learnt skill stays above the table's clearance (so it is played
whole on the arm, not stopped by the envelope)."""

import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, optimal_actions
from mt_widgets.arms import SO101_QUERY_MARGIN
from mt_widgets.core.learner import DEFAULT_LAMBDA
from mt_widgets.hardware.feetech import ARM_JOINTS
from mt_widgets.hardware.feetech.calibration import calibration_from_dict
from mt_widgets.hardware.feetech.envelope import SO101Envelope
from mt_widgets.hardware.feetech.kinematics import ArmKinematics

from .so101_support import CALIBRATION

KEYS = ("so101-reach", "so101-place")


def envelope(skill) -> SO101Envelope:
    return SO101Envelope(calibration_from_dict(CALIBRATION), ArmKinematics(skill.plant.chain))


@pytest.mark.parametrize("key", KEYS)
def test_every_query_state_of_200_seeds_is_inside_the_simulated_arms_envelope(key):
    skill = SKILLS[key]
    arm = envelope(skill)
    low = np.array([arm.ranges[j][0] for j in ARM_JOINTS])
    high = np.array([arm.ranges[j][1] for j in ARM_JOINTS])
    chain = skill.plant.chain
    closest = np.inf
    for seed in range(200):
        q = skill.query_states(seed=seed)[:, :len(ARM_JOINTS)]
        assert np.all((q >= low) & (q <= high)), (seed, q, low, high)
        # the margin itself: every joint this far inside the URDF's range
        assert np.all((q >= chain.lower + SO101_QUERY_MARGIN) & (q <= chain.upper - SO101_QUERY_MARGIN)), (seed, q)
        assert np.all(arm.kinematics.points(q)[..., 2] >= arm.table_height + arm.clearance), (seed, q)
        closest = min(closest, float(np.min(np.minimum(q - low, high - q))))
    assert closest > 0.0


def test_a_state_the_urdf_allows_but_the_arm_refuses_is_no_query_state():
    # the seed that was stuck before the margin: wrist_flex 1.627 rad, inside the URDF's 1.658 but not the arm's
    skill = SKILLS["so101-reach"]
    arm = envelope(skill)
    assert skill.plant.chain.upper[3] > 1.627 > arm.ranges["wrist_flex"][1]
    state = skill.plant.home.copy()
    state[3] = 1.627
    assert not skill.plant.is_valid_state(state)


@pytest.mark.parametrize("key", KEYS)
def test_reproductions_of_the_target_and_of_a_nearly_right_learnt_skill_stay_above_the_clearance(key):
    skill = SKILLS[key]
    arm = envelope(skill)
    floor = arm.table_height + arm.clearance
    length = skill.plant.drawing().action_length

    def lowest(theta):
        trajectory = skill.reproduce(theta)
        assert trajectory.stop_reason == "", trajectory.stop_reason
        return float(arm.kinematics.points(trajectory.states[:, :len(ARM_JOINTS)])[..., 2].min())

    assert lowest(skill.theta) >= floor + 0.035
    for seed in range(9):   # the first nine episodes' query states, taught as a page teaches them
        features = skill.features(skill.query_states(seed=seed))
        actions = optimal_actions(features, skill.theta, DEFAULT_LAMBDA)   # MT's arrows
        # shown by a hand up to 2 pixels of the simulated hand's view (1/350 m) off on each axis
        shown = actions + np.random.default_rng(seed).uniform(-2 / 350, 2 / 350, actions.shape) / length
        learnt = RidgeLearner(lam=DEFAULT_LAMBDA).fit(features, shown).theta
        assert np.linalg.norm(learnt - skill.theta) > 1e-3          # not the target: a nearly right skill
        # a margin above the clearance (the goals of 4 and 6 cm above the table left it 1 cm on reach)
        assert lowest(learnt) >= floor + 0.02, seed
