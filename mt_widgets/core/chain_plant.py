"""Any serial arm on a table, taught through its tool's velocity in space: the chain plant.

The arm is a ``SerialChain`` (read from its URDF outside ``core``: ``mt_widgets.robot_models``),
mounted on a table top at z = ``table_height`` in the base frame. The taught action is the tool
point's velocity (m/s, base frame); the controller of ``chain_rollout`` turns it into joint
motion at 1 kHz. A conveyor may run past the arm: then the state carries its phase s (how far
the belt has moved, m), so a part riding it is at ``origin + s * direction``.

Two kinds of arm:

- dynamic (``kinematic=False``, the UR5, the Panda): torque-controlled drives; state
  x = (q, qd[, s]); the velocity loop with gravity compensation drives the chain's rigid-body
  dynamics, which need every moving link's inertia;
- kinematic (``kinematic=True``, the SO-101): position-controlled servos whose own loops track a
  smooth setpoint far faster than the taught motion; state x = (q[, s]) and the joints follow
  the resolved rate exactly. No inertia is needed.

Query states are at rest, with the tool in the teaching box above the table, reached from the
home pose by position-only inverse kinematics, inside the joint limits (``query_margin`` inside
them), clear of the table and of the arm itself, and away from singular poses. A redundant arm
(more than three joints the tool's position depends on: every six- or seven-joint arm here) gets
the minimum-norm joint motion, plus with ``null_gain`` > 0 a pull towards its home pose in the
null space (``chain_rollout``'s docstring).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from . import chain_dynamics as dyn
from . import chain_rollout
from .drawing import SPACE_VIEWS, PoseSketch, SpaceDrawing, ViewProjection
from .features import ConveyorFeatures, ToolFeatures
from .plants import ContinuousPlant, _check_rollout
from .serial_chain import SerialChain
from .trajectory import TrajectoryBatch
from .validation import as_bool, as_count, as_finite, as_float_array, as_positive
from .workspace import Cuboid, belt_line

#: The task space of an arm taught in space: the base frame's three axes.
_SPACE = np.eye(3)
_SPACE.flags.writeable = False


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
        origin, direction, phase_range = belt_line(self.origin, self.direction, self.phase_range)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "direction", direction)
        object.__setattr__(self, "speed", as_positive("speed", self.speed, allow_zero=True))
        object.__setattr__(self, "phase_range", phase_range)

    def part_position(self, phase) -> np.ndarray:
        """Where the part is at phases (...) -> (..., 3) m."""
        phase = np.asarray(phase, dtype=float)
        return np.asarray(self.origin) + phase[..., None] * np.asarray(self.direction)


class ChainPlant(ContinuousPlant):
    """A serial arm on a table, its tool's velocity commanded through a resolved-rate controller.

    Args:
        chain: the arm's ``SerialChain``.
        home: (n,) rad (or m) the home pose: where inverse kinematics starts and the null space pulls.
        teaching_box: a ``Cuboid`` (m) the tool of a query state is in.
        scene_box: a ``Cuboid`` (m) every view frames.
        robot: a short name for the logs ("ur5", "panda", or a user's own).
        conveyor: a ``Conveyor`` whose phase the state carries, or None.
        kinematic: position-controlled servos (state q) rather than torque-controlled drives (q, qd).
        table_height: the table top's z in the base frame (m); the base stands on it.
        link_radius: the capsule radius (m) of the links for the table and self-collision checks.
        first_table_point: the first chain point (0 the base, i the origin of joint i, n + 1 the
            tool) checked against the table; those before stand on it by design.
        collision_gap: segments this many or more apart along the chain may collide (nearer
            ones share a short link).
        velocity_gain: k_v of a dynamic arm's joint velocity loop (1/s).
        damping: mu of the damped least squares (m).
        null_gain: k_n (1/s) of the pull towards ``home`` in the null space (0: none).
        min_singular_value: a query state's tool Jacobian must have all singular values above
            this (m/rad): away from the stretched and folded poses where teaching is ill-posed.
        speed_tolerance: a joint faster than its limit by more than this fraction stops a rollout.
        arrow_scale: the drawing's arrow length in m per m/s.
        query_margin: how far (rad, or m for a sliding joint) inside each joint's range a query
            state's joints stay. A query state near the end of a URDF range may lie beyond what a
            real arm's controller allows (a calibrated range, a safety margin of its own): the
            margin keeps every query state one the arm will go to (0: the URDF's range itself).
    """

    units = "m"
    action_units = "m/s"
    action_dim = 3
    default_duration = 10.0
    control_rate = 1000.0

    def __init__(self, chain: SerialChain, home, teaching_box: Cuboid, scene_box: Cuboid, robot: str = "arm",
                 conveyor: Conveyor | None = None, kinematic: bool = False, table_height: float = 0.0,
                 link_radius: float = 0.045, first_table_point: int = 3, collision_gap: int = 3,
                 velocity_gain: float = 20.0, damping: float = 0.01, null_gain: float = 0.0,
                 min_singular_value: float = 0.15, speed_tolerance: float = 0.1, arrow_scale: float = 0.5,
                 query_margin: float = 0.0):
        if not isinstance(chain, SerialChain):
            raise TypeError(f"chain: expected a SerialChain, got {type(chain).__name__}")
        if conveyor is not None and not isinstance(conveyor, Conveyor):
            raise TypeError(f"conveyor: expected a Conveyor or None, got {type(conveyor).__name__}")
        for name, box in (("teaching_box", teaching_box), ("scene_box", scene_box)):
            if not isinstance(box, Cuboid):
                raise TypeError(f"{name}: expected a Cuboid, got {type(box).__name__}")
        if not isinstance(robot, str) or not robot:
            raise TypeError(f"robot: expected a non-empty str, got {robot!r}")
        self.robot = robot
        self.chain = chain
        self.kinematic = as_bool("kinematic", kinematic)
        if not self.kinematic and not chain.has_dynamics:
            raise ValueError(f"{chain.source}: kinematic=False needs the chain's dynamics: expected a positive mass "
                             f"on every moving body (build the chain with dynamics=True), got {chain.mass.tolist()} kg")
        self.home = as_float_array("home", home, ndim=1, shape=(chain.n_joints,)).copy()
        self.conveyor = conveyor
        self.teaching_box = teaching_box
        self.scene_box = scene_box
        self.table_height = as_finite("table_height", table_height)
        self.link_radius = as_positive("link_radius", link_radius)
        self.velocity_gain = as_positive("velocity_gain", velocity_gain)
        self.damping = as_positive("damping", damping)
        self.null_gain = as_positive("null_gain", null_gain, allow_zero=True)
        self.min_singular_value = as_positive("min_singular_value", min_singular_value, allow_zero=True)
        self.speed_tolerance = as_positive("speed_tolerance", speed_tolerance, allow_zero=True)
        self.arrow_scale = as_positive("arrow_scale", arrow_scale)
        self.query_margin = as_positive("query_margin", query_margin, allow_zero=True)
        if np.any(chain.upper - chain.lower <= 2 * self.query_margin):
            raise ValueError(f"query_margin: expected less than half of every joint's range, got {query_margin!r}")
        n = self.chain.n_joints
        self.first_table_point = as_count("first_table_point", first_table_point, minimum=0)
        if self.first_table_point > n + 1:
            raise ValueError(f"first_table_point: expected at most {n + 1} (the tool), got {first_table_point}")
        gap = as_count("collision_gap", collision_gap)
        names = tuple(f"q{i + 1}" for i in range(n)) + (() if self.kinematic else tuple(f"qd{i + 1}" for i in range(n)))
        self.state_names = names + (("s",) if conveyor is not None else ())
        # Capsules: segments between consecutive chain points (base, joint origins, tool).
        segments = n + 1
        self.collision_pairs = np.array([(a, b) for a in range(segments) for b in range(a + gap, segments)],
                                        dtype=np.int64).reshape(-1, 2)
        outside = (self.home < chain.lower) | (self.home > chain.upper)
        if np.any(outside):
            joint = int(np.flatnonzero(outside)[0])
            raise ValueError(f"home: expected joint {chain.joint_names[joint]} within [{chain.lower[joint]:.4g}, "
                             f"{chain.upper[joint]:.4g}], got {self.home[joint]:.6g}")

    def __repr__(self) -> str:
        kind = "kinematic" if self.kinematic else "dynamic"
        return f"ChainPlant({self.robot!r}, {self.n_joints} joints, {kind}, conveyor={self.conveyor})"

    def scene(self) -> chain_rollout.ChainScene:
        """The scene as the compiled engine takes it (built from the attributes on each call)."""
        return chain_rollout.ChainScene(float(self.table_height), int(self.first_table_point), self.collision_pairs,
                                        float(self.link_radius),
                                        float(self.conveyor.speed) if self.conveyor is not None else 0.0,
                                        self.conveyor is not None)

    def control(self) -> chain_rollout.ChainControl:
        """The controller's settings as the compiled engine takes them."""
        return chain_rollout.ChainControl(float(self.velocity_gain), float(self.damping), float(self.speed_tolerance),
                                          float(self.null_gain), self.home, self.kinematic, _SPACE, False, True,
                                          False)

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
        """(tool positions (..., 3) m, tool velocities (..., 3) m/s) in the base frame.

        A kinematic arm's state carries no joint speeds: its tool is at rest between commands.
        """
        states = self.check_states("states", states)
        q, qd = states[..., :self.n_joints], self.joint_speeds(states)
        return self.chain.forward_kinematics(q), self.chain.tool_velocity(q, qd)

    def joint_speeds(self, states) -> np.ndarray:
        """qd of states (..., state_dim) -> (..., n): zeros for a kinematic arm (its state has none)."""
        n = self.n_joints
        if self.kinematic:
            return np.zeros(states.shape[:-1] + (n,))
        return states[..., n:2 * n]

    def drawing(self) -> SpaceDrawing:
        """Three views (top, side, perspective) of the scene: the table top, the conveyor's strip if any.

        Arrows of ``arrow_scale`` m per m/s (the UR5's 0.5: its skills' 0.1-0.4 m/s tool velocities
        read as 5-20 cm arrows beside a 0.9 m arm); the tool's velocity likewise.
        """
        (x0, x1), (y0, y1) = self.scene_box.xlim, self.scene_box.ylim
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
        centre = tuple(float(v) for v in (self.scene_box.low + self.scene_box.high) / 2.0)
        views = tuple(ViewProjection(name, centre=centre) for name in SPACE_VIEWS)
        return SpaceDrawing(bounds=self.scene_box, units=self.units, action_units=self.action_units, views=views,
                            base=(0.0, 0.0, self.table_height), surfaces=tuple(surfaces),
                            link_radius=self.link_radius, action_length=self.arrow_scale,
                            velocity_length=self.arrow_scale)

    def sketch(self, states) -> PoseSketch:
        """The chain (..., n + 2, 3) m (base, joint origins, tool) and the tool's velocity (..., 3) m/s."""
        states = self.check_states("states", states)
        q, qd = states[..., :self.n_joints], self.joint_speeds(states)
        return PoseSketch(self.chain.frame_origins(q), self.chain.tool_velocity(q, qd))

    def conveyor_phase(self, states) -> np.ndarray:
        """The conveyor's phase s (m) of states (..., state_dim) -> (...)."""
        if self.conveyor is None:
            raise ValueError("states: this plant has no conveyor, so its states carry no conveyor phase")
        return self.check_states("states", states)[..., -1]

    def chain_points(self, states) -> np.ndarray:
        """The arm's chain in the base frame: base, joint origins, tool. (..., state_dim) -> (..., n + 2, 3) m."""
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
        qd = np.ascontiguousarray(self.joint_speeds(flat), dtype=float)
        codes = _safety_batch(self.chain.model, self.scene(), self.speed_tolerance, flat[:, :self.n_joints].copy(),
                              qd, self.chain.frame_origins(q))
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
        parts = [q[0]] + ([] if self.kinematic else [np.zeros(self.n_joints)])
        if self.conveyor is not None:
            parts.append([float(self.conveyor.phase_range[0] if phase is None else phase)])
        elif phase is not None:
            raise ValueError("phase: this plant has no conveyor; give no phase")
        return np.concatenate(parts)

    def inverse_kinematics(self, positions, iterations: int = 100) -> tuple[np.ndarray, np.ndarray]:
        """Joint angles putting the tool at positions (N, 3) m, from the home pose by damped Newton steps.

        Returns (q (N, n), reached (N,) bool: within 1e-9 m).
        """
        positions = as_float_array("positions", positions, ndim=2, shape=(None, 3))
        iterations = as_count("iterations", iterations)
        q = np.repeat(self.home[None, :], len(positions), axis=0)
        error = np.empty(len(positions))
        _position_ik(self.chain.model, np.ascontiguousarray(positions), q, iterations, error)
        return q, error < 1e-9

    def sample_states(self, rng, n):
        targets = self.teaching_box.sample(rng, n)
        q, _ = self.inverse_kinematics(targets)
        parts = [q] + ([] if self.kinematic else [np.zeros_like(q)])
        if self.conveyor is not None:
            parts.append(rng.uniform(*self.conveyor.phase_range, size=(n, 1)))
        return np.concatenate(parts, axis=1)

    def is_valid_state(self, states):
        states = as_float_array("states", states, shape=(self.state_dim,))
        q = states[..., :self.n_joints]
        tool = self.chain.forward_kinematics(q)
        conditioned = np.linalg.svd(self.chain.jacobian(q), compute_uv=False)[..., -1] >= self.min_singular_value
        inside = np.all((q >= self.chain.lower + self.query_margin) & (q <= self.chain.upper - self.query_margin),
                        axis=-1)
        valid = (self.safety(states) == "") & self.teaching_box.contains(tool) & conditioned & inside
        if self.conveyor is not None:
            low, high = self.conveyor.phase_range
            phase = states[..., -1]
            valid &= (phase >= low) & (phase <= high)
        return valid

    # -- the controller and the dynamics (for the generic rollout of a user's feature map) --------
    def hold(self, states, actions):
        """What the controller holds over a step for tool velocities (..., 3) at states.

        A dynamic arm: the joint torques (..., n); a kinematic arm: the tool velocities themselves
        (its joints follow the resolved rate at every stage of the step).
        """
        states = self.check_states("states", states)
        actions = as_float_array("actions", actions, shape=(3,))
        if self.kinematic:
            return np.broadcast_to(actions, np.broadcast_shapes(states.shape[:-1], actions.shape[:-1]) + (3,))
        n = self.n_joints
        q, qd = states[..., :n], states[..., n:2 * n]
        shape = np.broadcast_shapes(q.shape[:-1], actions.shape[:-1])
        M = np.broadcast_to(self.chain.mass_matrix(q), shape + (n, n)).reshape(-1, n, n)
        g = np.broadcast_to(self.chain.gravity_torque(q), shape + (n,)).reshape(-1, n)
        qd = np.broadcast_to(qd, shape + (n,)).reshape(-1, n)
        reference = self.joint_velocity_reference(np.broadcast_to(q, shape + (n,)),
                                                  np.broadcast_to(actions, shape + (3,))).reshape(-1, n)
        tau = np.empty((len(reference), n))
        for b in range(len(reference)):
            chain_rollout.held_torque(reference[b], np.ascontiguousarray(qd[b]), np.ascontiguousarray(M[b]),
                                      np.ascontiguousarray(g[b]), self.chain.effort_limit, self.velocity_gain, tau[b])
        return tau.reshape(shape + (n,))

    def joint_velocity_reference(self, q, actions) -> np.ndarray:
        """qd_ref (..., n) the resolved rate asks of joints q (..., n) for tool velocities (..., 3)."""
        n = self.n_joints
        shape = np.broadcast_shapes(q.shape[:-1], actions.shape[:-1])
        q = np.ascontiguousarray(np.broadcast_to(q, shape + (n,)).reshape(-1, n), dtype=float)
        u = np.ascontiguousarray(np.broadcast_to(actions, shape + (3,)).reshape(-1, 3), dtype=float)
        # Always read-only, as SerialChain._flat's: one compiled signature of the kernel, not one per writability.
        q.flags.writeable = u.flags.writeable = False
        out = np.empty((len(q), n))
        _reference_batch(self.chain.model, self.control(), q, u, out)
        return out.reshape(shape + (n,))

    def derivative(self, states, held_input):
        n = self.n_joints
        q = states[..., :n]
        if self.kinematic:
            parts = [self.joint_velocity_reference(q, held_input)]
        else:
            qd = states[..., n:2 * n]
            parts = [qd, self.chain.forward_dynamics(q, qd, held_input)]
        if self.conveyor is not None:
            parts.append(np.full(states.shape[:-1] + (1,), self.conveyor.speed))
        return np.concatenate(parts, axis=-1)

    def has_diverged(self, states):
        return self.safety(states) != ""

    def rollout(self, thetas, feature_map, start, duration, record_every=None):
        # The compiled engine evaluates the tool features (r, 1) or (r, s, 1) of this plant's own
        # chain inline; any other feature map runs through the generic RK4 loop of ContinuousPlant.
        expected = ToolFeatures if self.conveyor is None else ConveyorFeatures
        compiled = type(feature_map) is expected and feature_map.plant is self
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
        chain_rollout.rollout(self.chain.model, self.scene(), self.control(), thetas, start, dt, n_steps, record_every,
                              (states, positions, velocities, actions, lengths, stop_step, stop_code))
        stopped = stop_step >= 0
        diverged_at = np.where(stopped, stop_step * dt, np.nan)
        times = np.arange(n_samples) * record_every * dt
        reasons = tuple(chain_rollout.STOP_REASONS[code] for code in stop_code)
        return TrajectoryBatch(times, states, positions, velocities, actions, stopped, diverged_at, lengths,
                               self.units, reasons)



@njit(cache=True)
def _safety_batch(model, scene, speed_tolerance, Q, QD, points):
    codes = np.empty(Q.shape[0], dtype=np.int64)
    for b in range(Q.shape[0]):
        codes[b] = chain_rollout.safety_code(model, scene, speed_tolerance, Q[b], QD[b], points[b])
    return codes


@njit(cache=True)
def _reference_batch(model, control, Q, U, out):
    n = Q.shape[1]
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    tool, J = np.empty(3), np.empty((3, n))
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.world_frames(local_R, local_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, model.tool_p, tool)
        dyn.tool_jacobian(model, world_R, world_p, tool, J)
        chain_rollout.joint_velocity_reference(J, U[b], Q[b], model.velocity_limit, control.damping,
                                               control.null_gain, control.home, out[b])


@njit(cache=True)
def _position_ik(model, targets, Q, iterations, out_error):
    """Damped Newton steps dq = J^T (J J^T + mu^2 I)^-1 (target - tool) from each row of Q (in place)."""
    n = Q.shape[1]
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    tool, J, step = np.empty(3), np.empty((3, n)), np.empty(n)
    limits = np.full(n, np.inf)
    for b in range(Q.shape[0]):
        error = np.inf
        for _ in range(iterations):
            dyn.local_frames(model, Q[b], local_R, local_p)
            dyn.world_frames(local_R, local_p, world_R, world_p)
            dyn.tool_point(world_R, world_p, model.tool_p, tool)
            e = targets[b] - tool
            error = np.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            if error < 1e-12:
                break
            dyn.tool_jacobian(model, world_R, world_p, tool, J)
            # The controller's own resolved-rate map (no null-space term, no speed limit): a step towards the target.
            chain_rollout.joint_velocity_reference(J, e, Q[b], limits, 1e-3, 0.0, Q[b], step)
            for i in range(n):
                Q[b, i] += step[i]
        out_error[b] = error
