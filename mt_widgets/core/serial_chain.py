"""A serial chain of revolute joints built from a robot's description as data (its URDF's numbers).

The description is what ``mt_widgets.robot_models.urdf`` reads from a URDF: the joints from the
root to a tip frame (origins as xyz + roll-pitch-yaw, axes, limits) and each link's inertial.
Fixed joints are folded into the moving body they weld a link to (their links' inertias added
to it, the tip frame expressed in the last body), exactly as pinocchio does when it loads a
URDF, so both build the same chain from the same file.

Every method takes one configuration or a batch with leading axes and returns arrays of
matching leading shape; the algorithms are the compiled ones of ``chain_dynamics``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import chain_dynamics as dyn
from .validation import as_float_array


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's roll-pitch-yaw: Rz(yaw) @ Ry(pitch) @ Rx(roll)."""
    roll, pitch, yaw = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _transform(xyz, rpy) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(rpy)
    T[:3, 3] = np.asarray(xyz, dtype=float)
    return T


class SerialChain:
    """Kinematics and rigid-body dynamics of a serial chain of revolute joints.

    Args:
        joints: dicts with name, type ("revolute" or "fixed"), parent, child, xyz, rpy, axis and,
            for revolute joints, lower, upper (rad), velocity (rad/s), effort (N m).
        inertials: dicts with link, mass (kg), xyz, rpy (the centre-of-mass frame) and inertia
            (ixx, ixy, ixz, iyy, iyz, izz) in kg m^2 about the centre of mass.
        tip: the frame whose origin is the tool point.
        gravity: gravitational acceleration in m/s^2 along the base frame's -z (pinocchio's 9.81).
    """

    def __init__(self, joints, inertials, tip: str, gravity: float = 9.81):
        by_child = {joint["child"]: joint for joint in joints}
        if tip not in by_child:
            raise ValueError(f"tip: expected a link reached by a joint, got {tip!r}")
        path, link = [], tip
        while link in by_child:
            path.append(by_child[link])
            link = by_child[link]["parent"]
        path.reverse()
        # Each link: (index of the moving body it is welded to, -1 for the base; its pose in that body's frame).
        attached = {link: (-1, np.eye(4))}
        placements, axes, names, limits = [], [], [], []
        body, pose = -1, np.eye(4)
        for joint in path:
            pose = pose @ _transform(joint["xyz"], joint["rpy"])
            if joint["type"] == "revolute":
                axis = np.asarray(joint["axis"], dtype=float)
                placements.append(pose)
                axes.append(axis / np.linalg.norm(axis))
                names.append(joint["name"])
                limits.append((joint["lower"], joint["upper"], joint["velocity"], joint["effort"]))
                body, pose = body + 1, np.eye(4)
            elif joint["type"] != "fixed":
                raise ValueError(f"joints: {joint['name']!r} is {joint['type']}; expected revolute or fixed")
            attached[joint["child"]] = (body, pose)
        pending = [joint for joint in joints if joint["child"] not in attached]
        while pending:
            placed = [joint for joint in pending if joint["parent"] in attached]
            if not placed:
                raise ValueError(f"joints: {[j['name'] for j in pending]} are not connected to the chain")
            for joint in placed:
                if joint["type"] != "fixed":
                    raise ValueError(f"joints: {joint['name']!r} ({joint['type']}) branches off the chain")
                parent_body, parent_pose = attached[joint["parent"]]
                attached[joint["child"]] = (parent_body, parent_pose @ _transform(joint["xyz"], joint["rpy"]))
            pending = [joint for joint in pending if joint not in placed]
        n = len(placements)
        if n == 0:
            raise ValueError("joints: expected at least one revolute joint between the root and the tip")
        self.joint_names = tuple(names)
        self.tip = tip
        limits = np.array(limits, dtype=float)
        self.lower, self.upper, self.velocity_limit, self.effort_limit = (limits[:, k].copy() for k in range(4))
        self.gravity = float(gravity)
        placement_R = np.array([T[:3, :3] for T in placements])
        placement_p = np.array([T[:3, 3] for T in placements])
        # Each body's mass, first moment and inertia about its origin, summed over its welded links.
        mass, moment, inertia_origin = np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3, 3))
        for inertial in inertials:
            body, pose = attached.get(inertial["link"], (None, None))
            if body is None or body < 0 or inertial["mass"] == 0.0:
                continue
            ixx, ixy, ixz, iyy, iyz, izz = inertial["inertia"]
            frame = pose @ _transform(inertial["xyz"], inertial["rpy"])
            R, c, m = frame[:3, :3], frame[:3, 3], float(inertial["mass"])
            I_com = R @ np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) @ R.T
            mass[body] += m
            moment[body] += m * c
            inertia_origin[body] += I_com + m * (c @ c * np.eye(3) - np.outer(c, c))
        if np.any(mass <= 0):
            raise ValueError(f"inertials: expected a positive mass on every moving body, got {mass.tolist()}")
        com = moment / mass[:, None]
        inertia = inertia_origin - mass[:, None, None] * (np.einsum("bi,bi->b", com, com)[:, None, None] * np.eye(3)
                                                          - np.einsum("bi,bj->bij", com, com))
        tip_body, tip_pose = attached[tip]
        if tip_body != n - 1:
            raise ValueError(f"tip: expected a frame on the last moving body, got {tip!r} on body {tip_body}")
        self.mass, self.com, self.inertia = mass, com, inertia
        self.tool_R, self.tool_p = tip_pose[:3, :3].copy(), tip_pose[:3, 3].copy()
        self.placement_R, self.placement_p = placement_R, placement_p
        self.axis = np.array(axes)
        self.gravity_vector = np.array([0.0, 0.0, -self.gravity])

    def __repr__(self) -> str:
        return f"SerialChain({len(self.joint_names)} joints to {self.tip!r}: {', '.join(self.joint_names)})"

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    @property
    def model(self) -> tuple:
        """The arrays the compiled kernels take, in ``chain_dynamics``' order."""
        return (self.placement_R, self.placement_p, self.axis, self.mass, self.com, self.inertia, self.tool_R,
                self.tool_p, self.gravity_vector)

    def _q(self, name: str, value) -> np.ndarray:
        return as_float_array(name, value, shape=(self.n_joints,))

    def _flat(self, *arrays):
        shape = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
        flat = [np.ascontiguousarray(np.broadcast_to(a, shape + a.shape[-1:]).reshape(-1, a.shape[-1]))
                for a in arrays]
        return shape, flat

    # -- kinematics ---------------------------------------------------------------------------------
    def frame_origins(self, q) -> np.ndarray:
        """The chain's points in the base frame: base origin, each joint's origin, the tool point.

        q: (..., n) rad -> (..., n + 2, 3) m.
        """
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), self.n_joints + 2, 3))
        _origins_batch(self.placement_R, self.placement_p, self.axis, self.tool_p, flat, out)
        return out.reshape(shape + out.shape[1:])

    def forward_kinematics(self, q) -> np.ndarray:
        """The tool point in the base frame: (..., n) rad -> (..., 3) m."""
        return self.frame_origins(q)[..., -1, :]

    def tool_pose(self, q) -> tuple[np.ndarray, np.ndarray]:
        """(rotation (..., 3, 3), position (..., 3)) of the tool frame in the base frame."""
        shape, (flat,) = self._flat(self._q("q", q))
        rotations, positions = np.empty((len(flat), 3, 3)), np.empty((len(flat), 3))
        _tool_pose_batch(self.placement_R, self.placement_p, self.axis, self.tool_R, self.tool_p, flat, rotations,
                         positions)
        return rotations.reshape(shape + (3, 3)), positions.reshape(shape + (3,))

    def jacobian(self, q) -> np.ndarray:
        """d(tool point)/dq in the base frame: (..., n) -> (..., 3, n)."""
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), 3, self.n_joints))
        _jacobian_batch(self.placement_R, self.placement_p, self.axis, self.tool_p, flat, out)
        return out.reshape(shape + (3, self.n_joints))

    def tool_velocity(self, q, qd) -> np.ndarray:
        """J(q) qd: the tool point's velocity in m/s, (..., n), (..., n) -> (..., 3)."""
        qd = self._q("qd", qd)
        return np.einsum("...ij,...j->...i", self.jacobian(q), qd)

    # -- dynamics -----------------------------------------------------------------------------------
    def mass_matrix(self, q) -> np.ndarray:
        """M(q): (..., n) -> (..., n, n) in kg m^2."""
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), self.n_joints, self.n_joints))
        _mass_batch(self.placement_R, self.placement_p, self.axis, self.mass, self.com, self.inertia, flat, out)
        return out.reshape(shape + out.shape[1:])

    def inverse_dynamics(self, q, qd, qdd, gravity: bool = True) -> np.ndarray:
        """tau = M(q) qdd + C(q, qd) qd + g(q) (without g when ``gravity`` is False): -> (..., n) N m."""
        shape, (fq, fqd, fqdd) = self._flat(self._q("q", q), self._q("qd", qd), self._q("qdd", qdd))
        out = np.empty((len(fq), self.n_joints))
        _rnea_batch(self.placement_R, self.placement_p, self.axis, self.mass, self.com, self.inertia,
                    self.gravity_vector, fq, fqd, fqdd, bool(gravity), out)
        return out.reshape(shape + (self.n_joints,))

    def nonlinear_effects(self, q, qd) -> np.ndarray:
        """The bias forces C(q, qd) qd + g(q): (..., n), (..., n) -> (..., n) N m."""
        q = self._q("q", q)
        return self.inverse_dynamics(q, qd, np.zeros(q.shape[-1:]))

    def gravity_torque(self, q) -> np.ndarray:
        """g(q): (..., n) -> (..., n) N m."""
        zeros = np.zeros(self.n_joints)
        return self.inverse_dynamics(q, zeros, zeros)

    def forward_dynamics(self, q, qd, torque) -> np.ndarray:
        """qdd = M(q)^-1 (tau - C(q, qd) qd - g(q)): -> (..., n) rad/s^2."""
        shape, (fq, fqd, ftau) = self._flat(self._q("q", q), self._q("qd", qd), self._q("torque", torque))
        out = np.empty((len(fq), self.n_joints))
        _forward_batch(self.placement_R, self.placement_p, self.axis, self.mass, self.com, self.inertia,
                       self.gravity_vector, fq, fqd, ftau, out)
        return out.reshape(shape + (self.n_joints,))


# -- batch kernels: one configuration after another, scratch allocated once per call ----------------

@njit(cache=True)
def _origins_batch(placement_R, placement_p, axis, tool_p, Q, out):
    n = Q.shape[1]
    local_R, world_R, world_p, tool = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, 3)), np.empty(3)
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.world_frames(local_R, placement_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, tool_p, tool)
        for k in range(3):
            out[b, 0, k] = 0.0
            for i in range(n):
                out[b, i + 1, k] = world_p[i, k]
            out[b, n + 1, k] = tool[k]


@njit(cache=True)
def _tool_pose_batch(placement_R, placement_p, axis, tool_R, tool_p, Q, rotations, positions):
    n = Q.shape[1]
    local_R, world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, 3))
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.world_frames(local_R, placement_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, tool_p, positions[b])
        for r in range(3):
            for c in range(3):
                acc = 0.0
                for k in range(3):
                    acc += world_R[n - 1, r, k] * tool_R[k, c]
                rotations[b, r, c] = acc


@njit(cache=True)
def _jacobian_batch(placement_R, placement_p, axis, tool_p, Q, out):
    n = Q.shape[1]
    local_R, world_R, world_p, tool = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, 3)), np.empty(3)
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.world_frames(local_R, placement_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, tool_p, tool)
        dyn.tool_jacobian(world_R, world_p, axis, tool, out[b])


@njit(cache=True)
def _mass_batch(placement_R, placement_p, axis, mass, com, inertia, Q, out):
    n = Q.shape[1]
    local_R, cm, ch, cJ = np.empty((n, 3, 3)), np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3))
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.crba(local_R, placement_p, axis, mass, com, inertia, cm, ch, cJ, out[b])


@njit(cache=True)
def _rnea_batch(placement_R, placement_p, axis, mass, com, inertia, gravity, Q, QD, QDD, use_gravity, out):
    n = Q.shape[1]
    local_R = np.empty((n, 3, 3))
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.rnea(local_R, placement_p, axis, mass, com, inertia, gravity, QD[b], QDD[b], use_gravity,
                 w, v, aw, al, fn, fl, out[b])


@njit(cache=True)
def _forward_batch(placement_R, placement_p, axis, mass, com, inertia, gravity, Q, QD, TAU, out):
    n = Q.shape[1]
    local_R = np.empty((n, 3, 3))
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    cm, ch, cJ, M, L = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.zeros((n, n))
    zeros, bias, rhs = np.zeros(n), np.empty(n), np.empty(n)
    for b in range(Q.shape[0]):
        dyn.local_rotations(placement_R, axis, Q[b], local_R)
        dyn.rnea(local_R, placement_p, axis, mass, com, inertia, gravity, QD[b], zeros, True, w, v, aw, al, fn, fl,
                 bias)
        dyn.crba(local_R, placement_p, axis, mass, com, inertia, cm, ch, cJ, M)
        for i in range(n):
            rhs[i] = TAU[b, i] - bias[i]
        if not dyn.cholesky_solve(M, rhs, L, out[b]):
            for i in range(n):
                out[b, i] = np.nan
