"""The simulated two-link arm as a plant: query-state region, end-effector readout, fast rollouts.

Its rollouts run on the chain engine (``chain_rollout``), the arm as a two-joint chain
(``TwoLinkArm.chain_description``) force-controlled in its plane; the closed forms of
``TwoLinkArm`` give the readouts and are the engine's test oracle.
"""

from __future__ import annotations

import numpy as np

from . import chain_rollout
from .arm import TwoLinkArm
from .drawing import PlantDrawing, PoseSketch
from .features import EndEffectorFeatures
from .plants import ContinuousPlant, _check_rollout
from .serial_chain import SerialChain
from .trajectory import TrajectoryBatch
from .validation import as_count, as_float_array, as_positive
from .workspace import Box

#: The arm's plane in its chain's base frame: x and z (gravity along -z, as for every chain).
_PLANE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
_PLANE.flags.writeable = False
# Writable like a ChainPlant's pairs: numba compiles one version per array flag, and one serves both.
_NO_PAIRS = np.empty((0, 2), dtype=np.int64)


class ArmPlant(ContinuousPlant):
    """The paper's simulated arm: state x = (q1, q2, qd1, qd2), action = end-effector force (N).

    Args:
        arm: the ``TwoLinkArm`` (default: the paper's arm, uniform rods, gravity compensated).
        joint_speed_range: query states have joint speeds uniform in [-v, v] rad/s.
        max_joint_speed: a rollout whose joint speed exceeds this (rad/s) is stopped and
            flagged diverged. 100 rad/s (16 turns a second) is far beyond any motion a sensible
            skill produces and well before the numbers overflow.

    ``chain`` is the arm as a two-joint ``SerialChain`` (its plane (x, y) the chain's (x, z)),
    which the chain engine rolls out with ``scene()`` and ``control()``.
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
        # The arm's plane (x, y) is its chain's (x, z); a joint speed beyond max_joint_speed stops a rollout.
        self.chain = SerialChain.from_description(self.arm.chain_description(), gravity=self.arm.gravity)
        self.chain.velocity_limit = np.full(2, self.max_joint_speed)

    def scene(self) -> chain_rollout.ChainScene:
        """Nothing around the arm: no table, no collision pair (the engine checks joints only)."""
        return chain_rollout.ChainScene(-np.inf, self.chain.n_joints + 2, _NO_PAIRS, 0.0, 0.0, False)

    def control(self) -> chain_rollout.ChainControl:
        """The paper's controller: the end-effector force in the plane, held as J^T u (+ g(q) when compensated)."""
        return chain_rollout.ChainControl(0.0, 0.0, 0.0, 0.0, np.zeros(2), False, _PLANE, True,
                                          self.arm.gravity_compensation, True)

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
        # Writable copies: numba compiles one version per array flag (a skill's Theta is read-only).
        thetas, start = np.array(thetas, order="C"), np.array(start, order="C")
        dt = 1.0 / self.control_rate
        batch, n_samples = thetas.shape[0], n_steps // record_every + 1
        states = np.empty((batch, n_samples, 4))
        positions, velocities, actions = (np.empty((batch, n_samples, 2)) for _ in range(3))
        lengths, stop_step, stop_code = (np.empty(batch, dtype=np.int64) for _ in range(3))
        chain_rollout.rollout(self.chain.model, self.scene(), self.control(), thetas, start, dt, n_steps, record_every,
                              (states, positions, velocities, actions, lengths, stop_step, stop_code))
        # Every stop of this arm (a joint speed beyond max_joint_speed, a state not finite) is a divergence.
        diverged_at = np.where(stop_step >= 0, stop_step * dt, np.nan)
        times = np.arange(n_samples) * record_every * dt
        return TrajectoryBatch(times, states, positions, velocities, actions, stop_step >= 0, diverged_at,
                               lengths, self.units)
