"""The science of mt-widgets, with numpy and numba only (no Jupyter, no widgets, no serial).

Arm dynamics, plants, feature maps, skills, the ridge learner, exact machine teaching,
query-state selection, rollouts, and the teaching episode that ties them together. It reads no
file and imports nothing else of the package: a robot's URDF reaches it as data, read and built
into the shipped arms by ``mt_widgets.arms`` (which promises their skills to ``SKILLS``).
"""

from .arm import ArmParameters, TwoLinkArm
from .arm_plant import ArmPlant
from .chain_plant import ChainPlant, Conveyor
from .drawing import PlantDrawing, PoseSketch, SpaceDrawing, TargetShape, ViewProjection
from .episode import Demonstration, DemonstrationAnalysis, EpisodeResult, EpisodeStateError, TeachingEpisode
from .features import (
    ConveyorFeatures,
    EndEffectorFeatures,
    FeatureMap,
    FunctionFeatures,
    PositionFeatures,
    ToolFeatures,
)
from .kernel_learners import GaussianProcessLearner, KernelPolicy, KernelRidgeLearner, SingularFitError
from .learner import DEFAULT_LAMBDA, FittedPolicy, Learner, LinearPolicy, RidgeLearner
from .learner_teaching import LEARNERS, LearnerTeaching, make_learner, policy_risk, teach
from .machine_teaching import (
    ActionDifference,
    TeachingAnalysis,
    UnderdeterminedTeachingWarning,
    action_difference,
    analyse_demonstrations,
    optimal_actions,
    ridge_operator,
    teaching_risk,
)
from .network_learner import NetworkPolicy, NeuralNetworkLearner
from .nonlinear_skills import NONLINEAR_SKILLS
from .plants import ContinuousPlant, KinematicPlant, Plant
from .query_states import SeedSchedule, condition_number, sample_query_states
from .reward_learner import RewardLearner, RewardPolicy
from .serial_chain import SerialChain
from .skills import SKILLS, Skill, SkillRegistry
from .targets import ConveyorTarget, LineTarget, PointTarget, SpacePointTarget, Target
from .trajectory import Trajectory, TrajectoryBatch
from .uarm_plant import UARM_WORKSPACE_CM, UArmPlant
from .workspace import AnnulusSector, Box, Cuboid

__all__ = [
    "ActionDifference", "AnnulusSector", "ArmParameters", "ArmPlant", "Box", "ContinuousPlant", "DEFAULT_LAMBDA",
    "Demonstration", "DemonstrationAnalysis", "EndEffectorFeatures", "EpisodeResult", "EpisodeStateError",
    "FeatureMap", "FunctionFeatures",
    "KinematicPlant", "LineTarget", "Plant", "PlantDrawing", "PointTarget", "PoseSketch", "PositionFeatures",
    "RidgeLearner", "SKILLS", "SeedSchedule", "Skill", "SkillRegistry", "Target", "TargetShape", "TeachingAnalysis",
    "TeachingEpisode",
    "Trajectory", "TrajectoryBatch", "TwoLinkArm", "UARM_WORKSPACE_CM", "UArmPlant",
    "UnderdeterminedTeachingWarning", "action_difference", "analyse_demonstrations", "condition_number",
    "optimal_actions", "ridge_operator", "sample_query_states", "teaching_risk",
    "ChainPlant", "Conveyor", "ConveyorFeatures", "ConveyorTarget", "Cuboid", "SerialChain",
    "SpaceDrawing", "SpacePointTarget", "ToolFeatures", "ViewProjection",
]
__all__ += ["GaussianProcessLearner", "KernelRidgeLearner", "LEARNERS", "Learner", "LearnerTeaching",
            "NeuralNetworkLearner", "SingularFitError", "make_learner", "policy_risk", "teach"]
__all__ += ["NONLINEAR_SKILLS", "RewardLearner"]
__all__ += ["FittedPolicy", "KernelPolicy", "LinearPolicy", "NetworkPolicy", "RewardPolicy"]
