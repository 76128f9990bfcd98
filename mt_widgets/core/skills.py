"""Skills: what a teacher teaches. A skill is a target policy Theta on a plant's features.

``SKILLS`` holds the paper's four. A user defines their own with ``Skill(...)``: a plant,
a feature map, Theta (R x S), and the start state its reproduction runs from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .arm_plant import ArmPlant
from .features import EndEffectorFeatures, FeatureMap, PositionFeatures
from .query_states import sample_query_states
from .uarm_plant import UArmPlant
from .validation import as_count, as_float_array, as_positive


@dataclass(frozen=True)
class PointTarget:
    """The skill drives the end-effector to ``point``."""

    point: tuple[float, float]

    def distance(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(2,))
        return np.linalg.norm(positions - np.asarray(self.point), axis=-1)


@dataclass(frozen=True)
class LineTarget:
    """The skill drives the end-effector onto the line through ``point`` along ``direction``."""

    point: tuple[float, float]
    direction: tuple[float, float]

    def __post_init__(self):
        norm = float(np.hypot(*self.direction))
        if norm == 0:
            raise ValueError("direction: expected a non-zero vector, got (0, 0)")
        object.__setattr__(self, "direction", (self.direction[0] / norm, self.direction[1] / norm))

    def distance(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(2,))
        offset = positions - np.asarray(self.point)
        d = np.asarray(self.direction)
        return np.abs(offset[..., 0] * d[1] - offset[..., 1] * d[0])


@dataclass(frozen=True, eq=False)
class Skill:
    """A motor skill to teach.

    Args:
        key: a short identifier ("sim-point").
        title: a human title ("Reach the point (0.8, 1.2) m").
        plant: the plant it runs on.
        feature_map: phi for that plant.
        theta: (R, S) the target policy u = theta @ phi(x).
        start: the state every reproduction starts from.
        target: a ``PointTarget`` or ``LineTarget`` (for drawing and for checks), or None.
        description: one or two sentences for a student.
        max_condition: the query-state sampler's condition-number threshold for this skill.
    """

    key: str
    title: str
    plant: object
    feature_map: FeatureMap
    theta: np.ndarray
    start: np.ndarray
    target: PointTarget | LineTarget | None = None
    description: str = ""
    max_condition: float = 20.0

    def __post_init__(self):
        theta = as_float_array("theta", self.theta, ndim=2, shape=(self.plant.action_dim, self.feature_map.dim))
        theta = theta.copy()
        theta.setflags(write=False)
        object.__setattr__(self, "theta", theta)
        start = self.plant.check_states("start", self.start).copy()
        if start.ndim != 1:
            raise ValueError(f"start: expected one state of shape ({self.plant.state_dim},), got {start.shape}")
        start.setflags(write=False)
        object.__setattr__(self, "start", start)
        as_positive("max_condition", self.max_condition)

    def __repr__(self) -> str:
        return f"Skill({self.key!r}: {self.title})"

    # -- what a view needs to know -------------------------------------------------------------
    @property
    def robot(self) -> str:
        return self.plant.robot

    @property
    def units(self) -> str:
        return self.plant.units

    @property
    def action_units(self) -> str:
        return self.plant.action_units

    @property
    def state_dim(self) -> int:
        return self.plant.state_dim

    @property
    def n_features(self) -> int:
        return self.feature_map.dim

    @property
    def workspace(self):
        """The view extent (a ``Box`` with ``xlim``, ``ylim`` in ``units``)."""
        return self.plant.view

    @property
    def default_duration(self) -> float:
        return self.plant.default_duration

    def end_effector(self, states):
        """(positions (..., 2), velocities (..., 2)) in ``units``."""
        return self.plant.end_effector(states)

    # -- the science -----------------------------------------------------------------------------
    def features(self, states) -> np.ndarray:
        """phi for states (N, state_dim) -> (N, S)."""
        states = as_float_array("states", states, ndim=2, shape=(None, self.state_dim))
        return self.feature_map(states)

    def target_actions(self, states) -> np.ndarray:
        """The skill's own actions theta @ phi(x) at states (N, state_dim) -> (N, R)."""
        return self.features(states) @ self.theta.T

    def query_states(self, seed=None, n: int | None = None) -> np.ndarray:
        """n (default S, the teaching dimension) well-conditioned query states, seeded."""
        n = self.n_features if n is None else as_count("n", n)
        return sample_query_states(self.plant, self.feature_map, n, seed=seed, max_condition=self.max_condition)

    def reproduce(self, theta, duration: float | None = None, record_every: int | None = None):
        """Rolls out the policy ``theta`` from the skill's start.

        Args:
            theta: (R, S), or (B, R, S) for B rollouts stepped together.
            duration: seconds (default: the plant's, 10 s).
            record_every: control steps between recorded samples (default every step).

        Returns:
            A ``Trajectory`` for one theta, a ``TrajectoryBatch`` for a batch. A policy that
            drives the plant out of bounds comes back with ``diverged`` set, never as NaN.
        """
        theta = as_float_array("theta", theta, ndim=(2, 3), shape=(self.plant.action_dim, self.n_features))
        duration = self.default_duration if duration is None else duration
        batch = self.plant.rollout(theta.reshape((-1,) + self.theta.shape), self.feature_map, self.start,
                                   duration, record_every)
        return batch[0] if theta.ndim == 2 else batch


def _paper_skills() -> dict[str, Skill]:
    sim = ArmPlant()
    uarm = UArmPlant()
    sim_features = EndEffectorFeatures(sim)
    uarm_features = PositionFeatures(uarm)
    # Reproductions start at rest at q = (0.3, 0.5): the end-effector at about (1.65, 1.01) m,
    # away from both targets, so a student sees the whole approach.
    sim_start = np.array([0.3, 0.5, 0.0, 0.0])
    # The uArm point skill starts at (18, -10) cm, the line skill at (26, -4) cm: inside the
    # workspace, off their targets, and placed so the true skill's path stays inside the
    # workspace all the way (the line skill moves along (-1, 2) onto r1 = 2 r2 at (19.2, 9.6)).
    uarm_point_start = np.array([18.0, -10.0])
    uarm_line_start = np.array([26.0, -4.0])
    # Thresholds: about the median condition number of random sets of S states for each plant
    # (sim 5 x 5: about 16; uArm 3 x 3 in cm: about 200, the bias column being small next to
    # positions of 14-30 cm), so accepted sets are ordinary rather than contrived while the worst
    # half, which would amplify a teacher's small slips the most, is never shown.
    skills = [
        Skill("sim-point", "Reach the point (0.8, 1.2) m", sim, sim_features,
              [[-1, 0, -1, 0, 0.8], [0, -1, 0, -1, 1.2]], sim_start, PointTarget((0.8, 1.2)),
              "A spring-damper pulling the arm's tip to the point (0.8, 1.2) m: force = -(r - r*) - rdot.",
              max_condition=20.0),
        Skill("sim-line", "Reach the line r1 = 0.8 m", sim, sim_features,
              [[-1, 0, -1, 0, 0.8], [0, 0, 0, -1, 0]], sim_start, LineTarget((0.8, 0.0), (0.0, 1.0)),
              "Pull the tip onto the vertical line r1 = 0.8 m, damping its motion along the line.",
              max_condition=20.0),
        Skill("uarm-point", "Reach the point (23, 11) cm", uarm, uarm_features,
              [[-0.2, 0, 4.6], [0, -0.2, 2.2]], uarm_point_start, PointTarget((23.0, 11.0)),
              "Each step, move a fifth of the way to the point (23, 11) cm.", max_condition=200.0),
        Skill("uarm-line", "Reach the line r1 = 2 r2", uarm, uarm_features,
              [[-0.04, 0.08, 0], [0.08, -0.16, 0]], uarm_line_start, LineTarget((0.0, 0.0), (2.0, 1.0)),
              "Each step, move towards the line r1 = 2 r2 along the direction (-1, 2).", max_condition=200.0),
    ]
    return {skill.key: skill for skill in skills}


#: The paper's four skills, by key: "sim-point", "sim-line", "uarm-point", "uarm-line".
SKILLS: dict[str, Skill] = _paper_skills()
