"""The simulated two-link arm as a plant: query-state region, end-effector readout, fast rollouts."""

from __future__ import annotations

import numpy as np

from . import arm_rollout
from .arm import TwoLinkArm
from .drawing import PlantDrawing, PoseSketch
from .features import EndEffectorFeatures
from .plants import ContinuousPlant, _check_rollout
from .trajectory import TrajectoryBatch
from .validation import as_count, as_float_array, as_positive
from .workspace import Box


class ArmPlant(ContinuousPlant):
    """The paper's simulated arm: state x = (q1, q2, qd1, qd2), action = end-effector force (N).

    Args:
        arm: the ``TwoLinkArm`` (default: the paper's arm, uniform rods, gravity compensated).
        joint_speed_range: query states have joint speeds uniform in [-v, v] rad/s.
        max_joint_speed: a rollout whose joint speed exceeds this (rad/s) is stopped and
            flagged diverged. 100 rad/s (16 turns a second) is far beyond any motion a sensible
            skill produces and well before the numbers overflow.
    """

    robot = "sim"
    state_names = ("q1", "q2", "qd1", "qd2")
    units = "m"
    action_units = "N"
    default_duration = 10.0

    def __init__(self, arm: TwoLinkArm | None = None, joint_speed_range: float = 2.0, max_joint_speed: float = 100.0):
        self.arm = arm if arm is not None else TwoLinkArm()
        if not isinstance(self.arm, TwoLinkArm):
            raise ValueError(f"arm: expected a TwoLinkArm, got {type(arm).__name__}")
        self.joint_speed_range = as_positive("joint_speed_range", joint_speed_range, allow_zero=True)
        self.max_joint_speed = as_positive("max_joint_speed", max_joint_speed)
        reach = 1.1 * self.arm.reach
        self.view = Box((-reach, reach), (-reach, reach))

    def __repr__(self) -> str:
        return f"ArmPlant({self.arm!r})"

    def end_effector(self, states):
        states = self.check_states("states", states)
        q, qd = states[..., :2], states[..., 2:]
        return self.arm.forward_kinematics(q), self.arm.end_effector_velocity(q, qd)

    def drawing(self):
        # Arrows of 0.35 m per newton: a typical action of the paper's skills (1-3 N) is a
        # clearly visible arrow of 0.35-1 m; the velocity arrow shows 0.3 s of motion.
        return PlantDrawing(view=self.view, units=self.units, action_units=self.action_units, links="rigid",
                            marker="hand", base=(0.0, 0.0), action_length=0.35, velocity_length=0.3)

    def sketch(self, states):
        states = self.check_states("states", states)
        q, qd = states[..., :2], states[..., 2:]
        return PoseSketch(self.arm.joint_positions(q), self.arm.end_effector_velocity(q, qd))

    def sample_states(self, rng, n):
        q = rng.uniform(-np.pi, np.pi, size=(n, 2))
        qd = rng.uniform(-self.joint_speed_range, self.joint_speed_range, size=(n, 2))
        return np.concatenate([q, qd], axis=1)

    def state_at(self, position, velocity=(0.0, 0.0), elbow_up: bool = True) -> np.ndarray:
        """The state whose end-effector is at ``position`` (m) moving at ``velocity`` (m/s)."""
        q = self.arm.inverse_kinematics(position, elbow_up=elbow_up)
        velocity = as_float_array("velocity", velocity, ndim=1, shape=(2,))
        jacobian = self.arm.jacobian(q)
        if abs(np.linalg.det(jacobian)) < 1e-9:
            if np.any(velocity):
                raise ValueError(f"position: {np.asarray(position).tolist()} is where the arm is stretched or folded "
                                 f"(a singular pose): the tip cannot move at velocity {velocity.tolist()} there")
            return np.concatenate([q, np.zeros(2)])
        return np.concatenate([q, np.linalg.solve(jacobian, velocity)])

    # -- dynamics for the generic rollout (user feature maps) ----------------------------------
    def hold(self, states, actions):
        return self.arm.applied_torque(states[..., :2], actions)

    def derivative(self, states, held_input):
        q, qd = states[..., :2], states[..., 2:]
        return np.concatenate([qd, self.arm.joint_acceleration(q, qd, held_input)], axis=-1)

    def has_diverged(self, states):
        return ~np.all(np.isfinite(states), axis=-1) | np.any(np.abs(states[..., 2:]) > self.max_joint_speed, axis=-1)

    def rollout(self, thetas, feature_map, start, duration, record_every=None):
        if not isinstance(feature_map, EndEffectorFeatures):
            return super().rollout(thetas, feature_map, start, duration, record_every)
        thetas, start, n_steps = _check_rollout(self, thetas, feature_map, start, duration, self.control_rate)
        record_every = as_count("record_every", record_every if record_every is not None else 1)
        dt = 1.0 / self.control_rate
        states, positions, velocities, actions, lengths, diverged_step = arm_rollout.rollout(
            np.ascontiguousarray(thetas), start, self.arm.parameters.as_array(), self.arm.gravity_compensation,
            dt, n_steps, record_every, self.max_joint_speed)
        diverged_at = np.where(diverged_step >= 0, diverged_step * dt, np.nan)
        times = np.arange(states.shape[1]) * record_every * dt
        return TrajectoryBatch(times, states, positions, velocities, actions, diverged_step >= 0, diverged_at,
                               lengths, self.units)
