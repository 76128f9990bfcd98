"""A protocol whose learner cannot represent a skill it teaches is refused at load, by name."""

import pytest

from mt_widgets.analysis import protocol_with_learner
from mt_widgets.core import NONLINEAR_SKILLS, SKILLS, KernelRidgeLearner, RewardLearner, RidgeLearner
from mt_widgets.in_silico.plan import resolve_protocol
from mt_widgets.study.protocol_model import ProtocolError


def test_the_reward_learner_on_the_simulated_arm_is_refused_naming_learner_skill_and_why():
    with pytest.raises(ProtocolError, match=r"learner 'reward' cannot represent skill 'sim-point': it learns rewards "
                                            r"over planar positions of a kinematic plant.*ArmPlant"):
        protocol_with_learner("paper-sim", "reward")


def test_the_reward_learner_on_the_uarm_is_accepted():
    protocol = protocol_with_learner("paper-uarm", "reward")
    assert protocol.learner == "reward" and resolve_protocol("reward-sim").learner == "reward"


def test_a_linear_learner_cannot_represent_a_nonlinear_skill_a_kernel_learner_can():
    curve = NONLINEAR_SKILLS["uarm-curve"]
    assert "nonlinear target policy" in RidgeLearner.cannot_represent(curve)
    assert "nonlinear target policy" in RewardLearner.cannot_represent(curve)
    assert KernelRidgeLearner.cannot_represent(curve) is None
    assert RidgeLearner.cannot_represent(SKILLS["uarm-point"]) is None
    assert RewardLearner.cannot_represent(SKILLS["uarm-line"]) is None
