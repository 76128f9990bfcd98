"""A six-axis industrial arm (Universal Robots UR5) on a table, taught through its tool's velocity in space.

The arm is the serial chain of its URDF (``ur5_description``, read from example-robot-data's
file), mounted on a table top at z = ``table_height`` in the base frame. The taught action is the
tool point's velocity (m/s, base frame); the arm's controller (``chain_rollout``) turns it into
joint torques at 1 kHz. A conveyor may run past the arm: then the state carries its phase s (how
far the belt has moved, m), so a part riding it is at ``origin + s * direction``.

State x = (q1..q6 rad, qd1..qd6 rad/s[, s m]). Query states are at rest, with the tool in the
teaching box above the table, reached from the home pose by position-only inverse kinematics
(so the wrist keeps the home pose's tool-down attitude as well as it can), inside the joint
limits, clear of the table and of the arm itself, and away from singular poses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from . import chain_dynamics as dyn
from . import chain_rollout, ur5_description
from .drawing import SPACE_VIEWS, PoseSketch, SpaceDrawing, ViewProjection
from .features import ConveyorFeatures, ToolFeatures
from .plants import ContinuousPlant, _check_rollout
from .serial_chain import SerialChain
from .trajectory import TrajectoryBatch
from .validation import as_count, as_finite, as_float_array, as_positive
from .workspace import Cuboid

#: The UR5's home pose (rad): upper arm up, forearm level, tool pointing down at about
#: (0.49, 0.11, 0.43) m.
UR5_HOME = (0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0)

#: Where the tool is taught, in the base frame (m): in front of the arm, above the table.
UR5_TEACHING_BOX = Cuboid((0.30, 0.65), (-0.25, 0.45), (0.05, 0.45))

#: What every view of the UR5 frames (m): the arm at home and all it does over the teaching box.
UR5_SCENE = Cuboid((-0.25, 0.90), (-0.50, 0.70), (0.0, 0.85))


@dataclass(frozen=True)
class Conveyor:
    """A belt running past the arm: a part on it is at ``origin + s * direction``, s growing at ``speed``.

    Attributes:
        origin: (3,) m, where a part is at s = 0 (its grasp point above the belt).
        direction: (3,) the belt's direction (normalised here).
        speed: m/s.
        phase_range: (low, high) m, the phases query states are drawn from.
    """

    origin: tuple[float, float, float]
    direction: tuple[float, float, float]
    speed: float
    phase_range: tuple[float, float]

    def __post_init__(self):
        origin = as_float_array("origin", self.origin, ndim=1, shape=(3,))
        direction = as_float_array("direction", self.direction, ndim=1, shape=(3,))
        norm = float(np.linalg.norm(direction))
        if norm == 0:
            raise ValueError("direction: expected a non-zero vector, got (0, 0, 0)")
        low, high = as_float_array("phase_range", self.phase_range, ndim=1, shape=(2,))
        if not low < high:
            raise ValueError(f"phase_range: expected (low, high) with low < high, got {(float(low), float(high))}")
        object.__setattr__(self, "origin", tuple(float(v) for v in origin))
        object.__setattr__(self, "direction", tuple(float(v) / norm for v in direction))
        object.__setattr__(self, "speed", as_positive("speed", self.speed, allow_zero=True))
        object.__setattr__(self, "phase_range", (float(low), float(high)))

    def part_position(self, phase) -> np.ndarray:
        """Where the part is at phases (...) -> (..., 3) m."""
        phase = np.asarray(phase, dtype=float)
        return np.asarray(self.origin) + phase[..., None] * np.asarray(self.direction)


def ur5_chain() -> SerialChain:
    """The UR5's serial chain from its URDF's numbers (``ur5_description``), tool point at ``tool0``."""
    return SerialChain(ur5_description.JOINTS, ur5_description.INERTIALS, ur5_description.TIP)


class UR5Plant(ContinuousPlant):
    """The UR5 on a table, its tool's velocity commanded through a resolved-rate controller.

    Args:
        conveyor: a ``Conveyor`` whose phase the state carries, or None.
        teaching_box: a ``Cuboid`` (m) the tool of a query state is in.
        table_height: the table top's z in the base frame (m); the base stands on it.
        link_radius: the capsule radius (m) of the links for the table and self-collision checks.
        velocity_gain: k_v of the controller's joint velocity loop (1/s).
        damping: mu of the damped least squares (m).
        min_singular_value: a query state's tool Jacobian must have all singular values above
            this (m/rad): away from the stretched and folded poses where teaching is ill-posed.
        speed_tolerance: a joint faster than its limit by more than this fraction stops a rollout.
    """

    robot = "ur5"
    units = "m"
    action_units = "m/s"
    action_dim = 3
    default_duration = 10.0
    control_rate = 1000.0

    def __init__(self, conveyor: Conveyor | None = None, teaching_box: Cuboid = UR5_TEACHING_BOX,
                 table_height: float = 0.0, link_radius: float = 0.045, velocity_gain: float = 20.0,
                 damping: float = 0.01, min_singular_value: float = 0.15, speed_tolerance: float = 0.1):
        if conveyor is not None and not isinstance(conveyor, Conveyor):
            raise TypeError(f"conveyor: expected a Conveyor or None, got {type(conveyor).__name__}")
        if not isinstance(teaching_box, Cuboid):
            raise TypeError(f"teaching_box: expected a Cuboid, got {type(teaching_box).__name__}")
        self.chain = ur5_chain()
        self.conveyor = conveyor
        self.teaching_box = teaching_box
        self.table_height = as_finite("table_height", table_height)
        self.link_radius = as_positive("link_radius", link_radius)
        self.velocity_gain = as_positive("velocity_gain", velocity_gain)
        self.damping = as_positive("damping", damping)
        self.min_singular_value = as_positive("min_singular_value", min_singular_value, allow_zero=True)
        self.speed_tolerance = as_positive("speed_tolerance", speed_tolerance, allow_zero=True)
        n = self.chain.n_joints
        names = tuple(f"q{i + 1}" for i in range(n)) + tuple(f"qd{i + 1}" for i in range(n))
        self.state_names = names + (("s",) if conveyor is not None else ())
        self.home = np.array(UR5_HOME)
        # Capsules: segments between consecutive chain points (base, joint origins, tool). The
        # first three points (base, shoulder pan, shoulder lift) stand on the table by design;
        # pairs of segments three or more apart may collide (nearer ones share a short link).
        self.first_table_point = 3
        segments = n + 1
        self.collision_pairs = np.array([(a, b) for a in range(segments) for b in range(a + 3, segments)],
                                        dtype=np.int64)

    def __repr__(self) -> str:
        return f"UR5Plant(conveyor={self.conveyor})"

    @property
    def n_joints(self) -> int:
        return self.chain.n_joints

    # -- input checks --------------------------------------------------------------------------
    def check_states(self, name: str, states) -> np.ndarray:
        """A state (state_dim,) or a batch (..., state_dim), finite, every joint inside its range.

        A state beyond a joint's range is refused (a ValueError naming the argument, the joint,
        its range and the value): no query state, start or feature is ever taken there.
        """
        states = as_float_array(name, states, shape=(self.state_dim,))
        q = states[..., :self.n_joints]
        outside = (q < self.chain.lower) | (q > self.chain.upper)
        if np.any(outside):
            joint = int(np.flatnonzero(outside.reshape(-1, self.n_joints).any(axis=0))[0])
            value = q.reshape(-1, self.n_joints)[:, joint][outside.reshape(-1, self.n_joints)[:, joint]][0]
            raise ValueError(f"{name}: expected joint {self.chain.joint_names[joint]} within "
                             f"[{self.chain.lower[joint]:.4g}, {self.chain.upper[joint]:.4g}] rad, got {value:.6g}")
        return states

    # -- readouts ------------------------------------------------------------------------------
    def end_effector(self, states):
        """(tool positions (..., 3) m, tool velocities (..., 3) m/s) in the base frame."""
        states = self.check_states("states", states)
        n = self.n_joints
        q, qd = states[..., :n], states[..., n:2 * n]
        return self.chain.forward_kinematics(q), self.chain.tool_velocity(q, qd)

    def drawing(self) -> SpaceDrawing:
        """Three views (top, side, perspective) of the scene: the table top, the conveyor's strip if any.

        Arrows of 0.5 m per m/s: the skills' 0.1-0.4 m/s tool velocities read as 5-20 cm arrows
        beside a 0.9 m arm; the tool's velocity likewise.
        """
        (x0, x1), (y0, y1) = UR5_SCENE.xlim, UR5_SCENE.ylim
        z = self.table_height
        surfaces = [np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z], [x0, y0, z]])]
        if self.conveyor is not None:
            # The strip the part's grasp point travels along over the phases taught and 0.5 m on.
            origin, direction = np.asarray(self.conveyor.origin), np.asarray(self.conveyor.direction)
            across = np.cross(direction, [0.0, 0.0, 1.0])
            across = 0.06 * across / (np.linalg.norm(across) or 1.0)
            low, high = self.conveyor.phase_range
            a, b = origin + (low - 0.1) * direction, origin + (high + 0.5) * direction
            surfaces.append(np.array([a - across, b - across, b + across, a + across, a - across]))
        centre = tuple(float(v) for v in (UR5_SCENE.low + UR5_SCENE.high) / 2.0)
        views = tuple(ViewProjection(name, centre=centre) for name in SPACE_VIEWS)
        return SpaceDrawing(bounds=UR5_SCENE, units=self.units, action_units=self.action_units, views=views,
                            base=(0.0, 0.0, self.table_height), surfaces=tuple(surfaces),
                            link_radius=self.link_radius, action_length=0.5, velocity_length=0.5)

    def sketch(self, states) -> PoseSketch:
        """The chain (..., 8, 3) m (base, joint origins, tool) and the tool's velocity (..., 3) m/s."""
        states = self.check_states("states", states)
        n = self.n_joints
        q, qd = states[..., :n], states[..., n:2 * n]
        return PoseSketch(self.chain.frame_origins(q), self.chain.tool_velocity(q, qd))

    def conveyor_phase(self, states) -> np.ndarray:
        """The conveyor's phase s (m) of states (..., state_dim) -> (...)."""
        if self.conveyor is None:
            raise ValueError("states: this plant has no conveyor, so its states carry no conveyor phase")
        return self.check_states("states", states)[..., -1]

    def chain_points(self, states) -> np.ndarray:
        """The arm's chain in the base frame: base, joint origins, tool. (..., state_dim) -> (..., 8, 3) m."""
        states = self.check_states("states", states)
        return self.chain.frame_origins(states[..., :self.n_joints])

    def safety(self, states) -> np.ndarray:
        """Per state, the reason it is unsafe (a ``chain_rollout.STOP_REASONS`` word) or "" when safe.

        Unlike the other readouts this takes any finite-shaped state, beyond a joint's range too
        (that is one of the reasons it reports).
        """
        states = as_float_array("states", states, shape=(self.state_dim,), finite=False)
        flat = states.reshape(-1, self.state_dim)
        q = np.nan_to_num(flat[:, :self.n_joints], nan=0.0, posinf=0.0, neginf=0.0)
        codes = _safety_batch(flat[:, :self.n_joints].copy(), flat[:, self.n_joints:2 * self.n_joints].copy(),
                              self.chain.frame_origins(q), self.chain.lower, self.chain.upper,
                              self.chain.velocity_limit, self.speed_tolerance, self.table_height,
                              self.first_table_point, self.collision_pairs, self.link_radius)
        words = np.array(chain_rollout.STOP_REASONS, dtype=object)[codes]
        return words.reshape(states.shape[:-1])

    # -- query states ----------------------------------------------------------------------------
    def state_at(self, position, phase: float | None = None) -> np.ndarray:
        """The state at rest whose tool is at ``position`` (3,) m, by IK from the home pose.

        Raises ValueError when the inverse kinematics does not reach the position to 1e-9 m.
        """
        position = as_float_array("position", position, ndim=1, shape=(3,))
        q, reached = self.inverse_kinematics(position[None, :])
        if not reached[0]:
            gap = np.linalg.norm(self.chain.forward_kinematics(q[0]) - position)
            raise ValueError(f"position: expected a point the tool can reach, got {position.tolist()} "
                             f"(the inverse kinematics stopped {gap:.3g} m away)")
        parts = [q[0], np.zeros(self.n_joints)]
        if self.conveyor is not None:
            parts.append([float(self.conveyor.phase_range[0] if phase is None else phase)])
        elif phase is not None:
            raise ValueError("phase: this plant has no conveyor; give no phase")
        return np.concatenate(parts)

    def inverse_kinematics(self, positions, iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles putting the tool at positions (N, 3) m, from the home pose by damped Newton steps.

        Returns (q (N, 6), reached (N,) bool: within 1e-9 m).
        """
        positions = as_float_array("positions", positions, ndim=2, shape=(None, 3))
        iterations = as_count("iterations", iterations)
        q = np.repeat(self.home[None, :], len(positions), axis=0)
        error = np.empty(len(positions))
        _position_ik(self.chain.placement_R, self.chain.placement_p, self.chain.axis, self.chain.tool_p,
                     np.ascontiguousarray(positions), q, iterations, error)
        return q, error < 1e-9

    def sample_states(self, rng, n):
        targets = self.teaching_box.sample(rng, n)
        q, _ = self.inverse_kinematics(targets)
        parts = [q, np.zeros_like(q)]
        if self.conveyor is not None:
            parts.append(rng.uniform(*self.conveyor.phase_range, size=(n, 1)))
        return np.concatenate(parts, axis=1)

    def is_valid_state(self, states):
        states = as_float_array("states", states, shape=(self.state_dim,))
        q = states[..., :self.n_joints]
        tool = self.chain.forward_kinematics(q)
        conditioned = np.linalg.svd(self.chain.jacobian(q), compute_uv=False)[..., -1] >= self.min_singular_value
        valid = (self.safety(states) == "") & self.teaching_box.contains(tool) & conditioned
        if self.conveyor is not None:
            low, high = self.conveyor.phase_range
            phase = states[..., -1]
            valid &= (phase >= low) & (phase <= high)
        return valid

    # -- the controller and the dynamics (for the generic rollout of a user's feature map) --------
    def hold(self, states, actions):
        """The joint torques (..., 6) the controller holds for tool velocities (..., 3) at states."""
        states = self.check_states("states", states)
        actions = as_float_array("actions", actions, shape=(3,))
        n = self.n_joints
        q, qd = states[..., :n], states[..., n:2 * n]
        shape = np.broadcast_shapes(q.shape[:-1], actions.shape[:-1])
        J = np.broadcast_to(self.chain.jacobian(q), shape + (3, n)).reshape(-1, 3, n)
        M = np.broadcast_to(self.chain.mass_matrix(q), shape + (n, n)).reshape(-1, n, n)
        g = np.broadcast_to(self.chain.gravity_torque(q), shape + (n,)).reshape(-1, n)
        qd = np.broadcast_to(qd, shape + (n,)).reshape(-1, n)
        u = np.broadcast_to(actions, shape + (3,)).reshape(-1, 3)
        tau = np.empty((len(u), n))
        for b in range(len(u)):
            chain_rollout.resolved_rate_torque(np.ascontiguousarray(J[b]), np.ascontiguousarray(u[b]),
                                               np.ascontiguousarray(qd[b]), np.ascontiguousarray(M[b]),
                                               np.ascontiguousarray(g[b]), self.chain.velocity_limit,
                                               self.chain.effort_limit, self.velocity_gain, self.damping, tau[b])
        return tau.reshape(shape + (n,))

    def derivative(self, states, held_input):
        n = self.n_joints
        q, qd = states[..., :n], states[..., n:2 * n]
        parts = [qd, self.chain.forward_dynamics(q, qd, held_input)]
        if self.conveyor is not None:
            parts.append(np.full(states.shape[:-1] + (1,), self.conveyor.speed))
        return np.concatenate(parts, axis=-1)

    def has_diverged(self, states):
        return self.safety(states) != ""

    def rollout(self, thetas, feature_map, start, duration, record_every=None):
        if self.conveyor is None:
            compiled = isinstance(feature_map, ToolFeatures)
        else:
            compiled = isinstance(feature_map, ConveyorFeatures)
        if not compiled:
            return super().rollout(thetas, feature_map, start, duration, record_every)
        thetas, start, n_steps = _check_rollout(self, thetas, feature_map, start, duration, self.control_rate)
        record_every = as_count("record_every", record_every if record_every is not None else 1)
        # Writable copies: numba compiles one version per array flag, and a skill's Theta and start
        # are read-only while a learnt Theta is not; one version serves both.
        thetas, start = np.array(thetas, order="C"), np.array(start, order="C")
        dt = 1.0 / self.control_rate
        batch, n_samples = thetas.shape[0], n_steps // record_every + 1
        states = np.empty((batch, n_samples, self.state_dim))
        positions, velocities, actions = (np.empty((batch, n_samples, 3)) for _ in range(3))
        lengths, stop_step, stop_code = (np.empty(batch, dtype=np.int64) for _ in range(3))
        chain = self.chain
        chain_rollout.rollout(chain.placement_R, chain.placement_p, chain.axis, chain.mass, chain.com, chain.inertia,
                              chain.tool_p, chain.gravity_vector, chain.lower, chain.upper, chain.velocity_limit,
                              chain.effort_limit, self.velocity_gain, self.damping, self.speed_tolerance,
                              self.table_height, self.first_table_point, self.collision_pairs, self.link_radius,
                              self.conveyor.speed if self.conveyor is not None else 0.0, self.conveyor is not None,
                              thetas, start, dt, n_steps, record_every,
                              states, positions, velocities, actions, lengths, stop_step, stop_code)
        stopped = stop_step >= 0
        diverged_at = np.where(stopped, stop_step * dt, np.nan)
        times = np.arange(n_samples) * record_every * dt
        reasons = tuple(chain_rollout.STOP_REASONS[code] for code in stop_code)
        return TrajectoryBatch(times, states, positions, velocities, actions, stopped, diverged_at, lengths,
                               self.units, reasons)


@njit(cache=True)
def _safety_batch(Q, QD, points, lower, upper, velocity_limit, speed_tolerance, table_height, first_table_point,
                  pairs, radius):
    codes = np.empty(Q.shape[0], dtype=np.int64)
    for b in range(Q.shape[0]):
        codes[b] = chain_rollout.safety_code(Q[b], QD[b], points[b], lower, upper, velocity_limit, speed_tolerance,
                                             table_height, first_table_point, pairs, radius)
    return codes


@njit(cache=True)
def _position_ik(placement_R, placement_p, axis, tool_p, targets, Q, iterations, out_error):
    """Damped Newton steps dq = J^T (J J^T + mu^2 I)^-1 (target - tool) from each row of Q (in place)."""
    n = Q.shape[1]
    local_R, world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, 3))
    tool, J, step = np.empty(3), np.empty((3, n)), np.empty(n)
    zeros = np.zeros(n)
    limits = np.full(n, np.inf)
    effort = np.full(n, np.inf)
    gravity_free = np.zeros(n)
    identity = np.eye(n)
    for b in range(Q.shape[0]):
        error = np.inf
        for _ in range(iterations):
            dyn.local_rotations(placement_R, axis, Q[b], local_R)
            dyn.world_frames(local_R, placement_p, world_R, world_p)
            dyn.tool_point(world_R, world_p, tool_p, tool)
            e = targets[b] - tool
            error = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            if error < 1e-12:
                break
            dyn.tool_jacobian(world_R, world_p, axis, tool, J)
            # The controller's own resolved-rate map with gain 1 and M = I: a step dq towards the target.
            chain_rollout.resolved_rate_torque(J, e, zeros, identity, gravity_free, limits, effort, 1.0, 1e-3, step)
            for i in range(n):
                Q[b, i] += step[i]
        out_error[b] = error
