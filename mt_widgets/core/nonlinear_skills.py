"""Skills beyond linear features: targets only a nonlinear learner represents.

Each is the paper's plant and feature map with a target *policy* (a function of the state) that
no Theta on those features reproduces: reaching a point along an arc around the robot's base
(linear in polar coordinates, curved in the plane), and reaching a point around an obstacle
(a smooth repulsion and swirl near it). Their ``theta`` is the best linear policy on the
features (least squares over the skill's states): what the paper's ridge learner can at best
learn, so every ridge view still works, and ``target_actions`` are the policy's.

``NONLINEAR_SKILLS`` holds them, read-only, apart from ``SKILLS`` (the paper's four, whose keys
are documented and fixed): "sim-curve", "sim-obstacle", "uarm-curve", "uarm-obstacle".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm_plant import ArmPlant
from .features import EndEffectorFeatures, FeatureMap, PositionFeatures
from .skills import Skill, SkillRegistry
from .targets import PointTarget
from .uarm_plant import UArmPlant


@dataclass(frozen=True)
class ArcReach:
    """Reach ``goal`` along an arc about the origin (the base): the action is linear in polar
    coordinates, ``-k_radius (rho - rho*) e_rho - k_angle rho* (phi - phi*) e_phi``, minus
    ``damping`` times the end-effector velocity (for a plant driven by forces)."""

    plant: object
    goal: tuple[float, float]
    k_radius: float
    k_angle: float
    damping: float = 0.0

    def __call__(self, states):
        positions, velocities = self.plant.end_effector(states)
        rho = np.linalg.norm(positions, axis=-1, keepdims=True)
        radial = positions / np.maximum(rho, 1e-12)
        tangent = np.concatenate([-radial[..., 1:], radial[..., :1]], axis=-1)
        goal = np.asarray(self.goal)
        rho_goal, phi_goal = np.linalg.norm(goal), np.arctan2(goal[1], goal[0])
        angle = np.angle(np.exp(1j * (np.arctan2(positions[..., 1], positions[..., 0]) - phi_goal)))[..., None]
        return (-self.k_radius * (rho - rho_goal) * radial - self.k_angle * rho_goal * angle * tangent
                - self.damping * velocities)


@dataclass(frozen=True)
class ObstacleReach:
    """Reach ``goal`` (a pull ``-gain (r - goal)``) around a round obstacle at ``obstacle``:
    near it (a Gaussian of width ``width``) a push away from its centre and a swirl around it,
    minus ``damping`` times the end-effector velocity."""

    plant: object
    goal: tuple[float, float]
    obstacle: tuple[float, float]
    width: float
    gain: float
    push: float
    swirl: float
    damping: float = 0.0

    def __call__(self, states):
        positions, velocities = self.plant.end_effector(states)
        away = positions - np.asarray(self.obstacle)
        nearness = np.exp(-np.sum(away**2, axis=-1, keepdims=True) / (2.0 * self.width**2))
        around = np.concatenate([away[..., 1:], -away[..., :1]], axis=-1)   # clockwise about the obstacle
        return (-self.gain * (positions - np.asarray(self.goal))
                + nearness * (self.push * away + self.swirl * around) / self.width - self.damping * velocities)


def best_linear_theta(plant, feature_map: FeatureMap, policy, n: int = 2048, seed: int = 0) -> np.ndarray:
    """The least-squares Theta (R, S) of ``policy`` on the features over n valid sampled states."""
    states = plant.sample_states(np.random.default_rng(seed), n)
    states = states[plant.is_valid_state(states)]
    solution, *_ = np.linalg.lstsq(feature_map(states), policy(states), rcond=None)
    return solution.T


def _skill(key, title, plant, feature_map, policy, start, target, description, max_condition) -> Skill:
    return Skill(key, title, plant, feature_map, best_linear_theta(plant, feature_map, policy), start, target,
                 description, max_condition=max_condition, policy=policy)


def _nonlinear_skills() -> list[Skill]:
    sim, uarm = ArmPlant(), UArmPlant()
    sim_features, uarm_features = EndEffectorFeatures(sim), PositionFeatures(uarm)
    sim_start = np.array([0.3, 0.5, 0.0, 0.0])     # the paper's start: the tip at about (1.65, 1.01) m
    # The obstacle sits just off the straight line from the start to the goal, so going around it
    # (the swirl's side) is a curve no linear policy on the features draws.
    return [
        _skill("sim-curve", "Reach (0.8, 1.2) m along an arc", sim, sim_features,
               ArcReach(sim, (0.8, 1.2), k_radius=2.0, k_angle=1.5, damping=1.0), sim_start, PointTarget((0.8, 1.2)),
               "Pull the tip to (0.8, 1.2) m by swinging it around the base: along the circle first, then in.", 20.0),
        _skill("sim-obstacle", "Reach (-1, 1) m around an obstacle", sim, sim_features,
               ObstacleReach(sim, (-1.0, 1.0), (0.3, 1.3), width=0.35, gain=1.0, push=3.0, swirl=3.0, damping=1.0),
               sim_start, PointTarget((-1.0, 1.0)),
               "Pull the tip across to (-1, 1) m while steering below a round obstacle at (0.3, 1.3) m.", 20.0),
        _skill("uarm-curve", "Reach (23, 11) cm along an arc", uarm, uarm_features,
               ArcReach(uarm, (23.0, 11.0), k_radius=0.25, k_angle=0.25), np.array([18.0, -10.0]),
               PointTarget((23.0, 11.0)),
               "Each step, move a quarter of the way to (23, 11) cm in distance from the base and in angle: "
               "an arc around the base.", 200.0),
        _skill("uarm-obstacle", "Reach (23, 11) cm around an obstacle", uarm, uarm_features,
               ObstacleReach(uarm, (23.0, 11.0), (20.0, 0.5), width=3.0, gain=0.2, push=3.0, swirl=4.0),
               np.array([18.0, -10.0]), PointTarget((23.0, 11.0)),
               "Each step, move a fifth of the way to (23, 11) cm, steering around an obstacle at (20, 0.5) cm.",
               200.0),
    ]


#: Skills only a nonlinear learner represents, by key (read-only): "sim-curve", "sim-obstacle",
#: "uarm-curve", "uarm-obstacle".
NONLINEAR_SKILLS: SkillRegistry = SkillRegistry(_nonlinear_skills(), read_only=True)
