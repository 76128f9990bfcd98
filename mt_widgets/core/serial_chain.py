"""A serial chain of joints built from a robot's description as data (its URDF's numbers).

The description is what ``mt_widgets.robot_models.urdf`` reads from a URDF: the joints from the
root to a tool frame (origins as xyz + roll-pitch-yaw, axes, limits) and each link's inertial.
Revolute and continuous joints turn, prismatic joints slide. Fixed joints (and joints the
reader locked) are folded into the moving body they weld a link to (their links' inertias added
to it, the tool frame expressed in the last body), exactly as pinocchio does when it loads a
URDF, so both build the same chain from the same file.

Every method takes one configuration or a batch with leading axes and returns arrays of
matching leading shape; the algorithms are the compiled ones of ``chain_dynamics``, which take
the chain as one structure (``SerialChain.model``, a ``chain_dynamics.ChainModel``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import chain_dynamics as dyn
from .chain_dynamics import ChainModel
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
    """Kinematics and rigid-body dynamics of a serial chain of revolute and prismatic joints.

    Args:
        joints: dicts with name, type ("revolute", "continuous", "prismatic" or "fixed"), parent,
            child, xyz, rpy, axis and, for movable joints, lower, upper (rad or m), velocity
            (rad/s or m/s), effort (N m or N).
        inertials: dicts with link, mass (kg), xyz, rpy (the centre-of-mass frame) and inertia
            (ixx, ixy, ixz, iyy, iyz, izz) in kg m^2 about the centre of mass.
        tip: the frame whose origin is the tool point.
        gravity: gravitational acceleration in m/s^2 along the base frame's -z (pinocchio's 9.81).
        dynamics: whether the chain's dynamics are needed: then every moving body must have a
            positive mass (a kinematic plant needs none).
        source: where the description came from (a URDF's path), for messages.
    """

    def __init__(self, joints, inertials, tip: str, gravity: float = 9.81, dynamics: bool = True,
                 source: str = "description"):
        if not isinstance(dynamics, bool):
            raise TypeError(f"dynamics: expected a bool, got {type(dynamics).__name__}")
        self.source = str(source)
        by_child = {joint["child"]: joint for joint in joints}
        if tip not in by_child:
            raise ValueError(f"{self.source}: tip: expected a link reached by a joint, got {tip!r}")
        path, link = [], tip
        while link in by_child:
            path.append(by_child[link])
            link = by_child[link]["parent"]
        path.reverse()
        # Each link: (index of the moving body it is welded to, -1 for the base; its pose in that body's frame).
        attached = {link: (-1, np.eye(4))}
        placements, axes, names, limits, prismatic, moved_by = [], [], [], [], [], []
        body, pose = -1, np.eye(4)
        for joint in path:
            pose = pose @ _transform(joint["xyz"], joint["rpy"])
            if joint["type"] in ("revolute", "continuous", "prismatic"):
                axis = np.asarray(joint["axis"], dtype=float)
                placements.append(pose)
                axes.append(axis / np.linalg.norm(axis))
                names.append(joint["name"])
                prismatic.append(joint["type"] == "prismatic")
                limits.append((joint["lower"], joint["upper"], joint["velocity"], joint["effort"]))
                moved_by.append([joint["child"]])
                body, pose = body + 1, np.eye(4)
            elif joint["type"] != "fixed":
                raise ValueError(f"{self.source}: joint {joint['name']!r} is {joint['type']}; expected revolute, "
                                 f"continuous, prismatic or fixed")
            elif body >= 0:
                moved_by[body].append(joint["child"])
            attached[joint["child"]] = (body, pose)
        pending = [joint for joint in joints if joint["child"] not in attached]
        while pending:
            placed = [joint for joint in pending if joint["parent"] in attached]
            if not placed:
                raise ValueError(f"{self.source}: joints {[j['name'] for j in pending]} are not connected to the chain")
            for joint in placed:
                if joint["type"] != "fixed":
                    raise ValueError(f"{self.source}: joint {joint['name']!r} ({joint['type']}) branches off the chain")
                parent_body, parent_pose = attached[joint["parent"]]
                attached[joint["child"]] = (parent_body, parent_pose @ _transform(joint["xyz"], joint["rpy"]))
                if parent_body >= 0:
                    moved_by[parent_body].append(joint["child"])
            pending = [joint for joint in pending if joint not in placed]
        n = len(placements)
        if n == 0:
            raise ValueError(f"{self.source}: expected at least one movable joint between the root and the tip {tip!r}")
        self.joint_names = tuple(names)
        self.tip = tip
        self.prismatic = np.array(prismatic, dtype=np.int64)
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
        massless = np.flatnonzero(mass <= 0)
        if dynamics and len(massless):
            body = int(massless[0])
            raise ValueError(f"{self.source}: links {moved_by[body]} (moved by joint {names[body]!r}): expected an "
                             f"<inertial> with a positive mass, since the dynamics need it; got none")
        com = moment / np.where(mass > 0, mass, 1.0)[:, None]
        inertia = inertia_origin - mass[:, None, None] * (np.einsum("bi,bi->b", com, com)[:, None, None] * np.eye(3)
                                                          - np.einsum("bi,bj->bij", com, com))
        tip_body, tip_pose = attached[tip]
        if tip_body != n - 1:
            raise ValueError(f"{self.source}: tip: expected a frame on the last moving body, got {tip!r} on body "
                             f"{tip_body}")
        self.mass, self.com, self.inertia = mass, com, inertia
        self.tool_R, self.tool_p = tip_pose[:3, :3].copy(), tip_pose[:3, 3].copy()
        self.placement_R, self.placement_p = placement_R, placement_p
        self.axis = np.array(axes)
        self.gravity_vector = np.array([0.0, 0.0, -self.gravity])
        self.has_dynamics = bool(np.all(mass > 0))
        #: Joints off the chain the URDF reader held at zero (a gripper's), by name.
        self.locked = ()

    @classmethod
    def from_description(cls, description: dict, dynamics: bool = True, gravity: float = 9.81) -> SerialChain:
        """The chain of a description read from a URDF (``mt_widgets.robot_models.urdf.read_urdf``)."""
        if not isinstance(description, dict) or not {"joints", "inertials", "tip"} <= set(description):
            raise TypeError("description: expected the dict a URDF reader gives (joints, inertials, tip), got "
                            f"{type(description).__name__}")
        chain = cls(description["joints"], description["inertials"], description["tip"], gravity=gravity,
                    dynamics=dynamics, source=description.get("source", "description"))
        chain.locked = tuple(description.get("locked", ()))
        return chain

    def __repr__(self) -> str:
        return f"SerialChain({len(self.joint_names)} joints to {self.tip!r}: {', '.join(self.joint_names)})"

    def _dynamics(self) -> None:
        if not self.has_dynamics:
            raise ValueError(f"{self.source}: expected a positive mass on every moving body for the dynamics, got "
                             f"{self.mass.tolist()} kg (built with dynamics=False)")

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    @property
    def model(self) -> ChainModel:
        """The chain as the compiled kernels take it: one ``chain_dynamics.ChainModel``.

        Built from the attributes on each call, so a limit changed on the chain is the limit used.
        """
        return ChainModel(self.placement_R, self.placement_p, self.axis, self.prismatic, self.mass, self.com,
                          self.inertia, self.tool_R, self.tool_p, self.gravity_vector, self.lower, self.upper,
                          self.velocity_limit, self.effort_limit)

    def _q(self, name: str, value) -> np.ndarray:
        return as_float_array(name, value, shape=(self.n_joints,))

    def _flat(self, *arrays):
        shape = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
        flat = [np.ascontiguousarray(np.broadcast_to(a, shape + a.shape[-1:]).reshape(-1, a.shape[-1]))
                for a in arrays]
        # Always read-only (a broadcast view is; a reshape's copy would not be): numba compiles a
        # kernel once per signature, and writability is part of it (a cold cache compiled each twice).
        for a in flat:
            a.flags.writeable = False
        return shape, flat

    # -- kinematics ---------------------------------------------------------------------------------
    def frame_origins(self, q) -> np.ndarray:
        """The chain's points in the base frame: base origin, each joint's origin, the tool point.

        q: (..., n) rad -> (..., n + 2, 3) m.
        """
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), self.n_joints + 2, 3))
        _origins_batch(self.model, flat, out)
        return out.reshape(shape + out.shape[1:])

    def forward_kinematics(self, q) -> np.ndarray:
        """The tool point in the base frame: (..., n) rad -> (..., 3) m."""
        return self.frame_origins(q)[..., -1, :]

    def tool_pose(self, q) -> tuple[np.ndarray, np.ndarray]:
        """(rotation (..., 3, 3), position (..., 3)) of the tool frame in the base frame."""
        shape, (flat,) = self._flat(self._q("q", q))
        rotations, positions = np.empty((len(flat), 3, 3)), np.empty((len(flat), 3))
        _tool_pose_batch(self.model, flat, rotations, positions)
        return rotations.reshape(shape + (3, 3)), positions.reshape(shape + (3,))

    def jacobian(self, q) -> np.ndarray:
        """d(tool point)/dq in the base frame (a sliding joint's column in m/m): (..., n) -> (..., 3, n)."""
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), 3, self.n_joints))
        _jacobian_batch(self.model, flat, out)
        return out.reshape(shape + (3, self.n_joints))

    def tool_velocity(self, q, qd) -> np.ndarray:
        """J(q) qd: the tool point's velocity in m/s, (..., n), (..., n) -> (..., 3)."""
        qd = self._q("qd", qd)
        return np.einsum("...ij,...j->...i", self.jacobian(q), qd)

    # -- dynamics -----------------------------------------------------------------------------------
    def mass_matrix(self, q) -> np.ndarray:
        """M(q): (..., n) -> (..., n, n) in kg m^2."""
        self._dynamics()
        shape, (flat,) = self._flat(self._q("q", q))
        out = np.empty((len(flat), self.n_joints, self.n_joints))
        _mass_batch(self.model, flat, out)
        return out.reshape(shape + out.shape[1:])

    def inverse_dynamics(self, q, qd, qdd, gravity: bool = True) -> np.ndarray:
        """tau = M(q) qdd + C(q, qd) qd + g(q) (without g when ``gravity`` is False): -> (..., n) N m."""
        self._dynamics()
        shape, (fq, fqd, fqdd) = self._flat(self._q("q", q), self._q("qd", qd), self._q("qdd", qdd))
        out = np.empty((len(fq), self.n_joints))
        _rnea_batch(self.model, fq, fqd, fqdd, bool(gravity), out)
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
        self._dynamics()
        shape, (fq, fqd, ftau) = self._flat(self._q("q", q), self._q("qd", qd), self._q("torque", torque))
        out = np.empty((len(fq), self.n_joints))
        _forward_batch(self.model, fq, fqd, ftau, out)
        return out.reshape(shape + (self.n_joints,))


# -- batch kernels: one configuration after another, scratch allocated once per call ----------------

@njit(cache=True)
def _origins_batch(model, Q, out):
    n = Q.shape[1]
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    tool = np.empty(3)
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.world_frames(local_R, local_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, model.tool_p, tool)
        for k in range(3):
            out[b, 0, k] = 0.0
            for i in range(n):
                out[b, i + 1, k] = world_p[i, k]
            out[b, n + 1, k] = tool[k]


@njit(cache=True)
def _tool_pose_batch(model, Q, rotations, positions):
    n = Q.shape[1]
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    tool_R = model.tool_R
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.world_frames(local_R, local_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, model.tool_p, positions[b])
        for r in range(3):
            for c in range(3):
                acc = 0.0
                for k in range(3):
                    acc += world_R[n - 1, r, k] * tool_R[k, c]
                rotations[b, r, c] = acc


@njit(cache=True)
def _jacobian_batch(model, Q, out):
    n = Q.shape[1]
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    tool = np.empty(3)
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.world_frames(local_R, local_p, world_R, world_p)
        dyn.tool_point(world_R, world_p, model.tool_p, tool)
        dyn.tool_jacobian(model, world_R, world_p, tool, out[b])


@njit(cache=True)
def _mass_batch(model, Q, out):
    n = Q.shape[1]
    local_R, local_p, cm, ch, cJ = np.empty((n, 3, 3)), model.placement_p.copy(), np.empty(n), np.empty((n, 3)), \
        np.empty((n, 3, 3))
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.crba(model, local_R, local_p, cm, ch, cJ, out[b])


@njit(cache=True)
def _rnea_batch(model, Q, QD, QDD, use_gravity, out):
    n = Q.shape[1]
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.rnea(model, local_R, local_p, QD[b], QDD[b], use_gravity, w, v, aw, al, fn, fl, out[b])


@njit(cache=True)
def _forward_batch(model, Q, QD, TAU, out):
    n = Q.shape[1]
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    cm, ch, cJ, M, L = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.zeros((n, n))
    zeros, bias, rhs = np.zeros(n), np.empty(n), np.empty(n)
    for b in range(Q.shape[0]):
        dyn.local_frames(model, Q[b], local_R, local_p)
        dyn.rnea(model, local_R, local_p, QD[b], zeros, True, w, v, aw, al, fn, fl, bias)
        dyn.crba(model, local_R, local_p, cm, ch, cJ, M)
        for i in range(n):
            rhs[i] = TAU[b, i] - bias[i]
        if not dyn.cholesky_solve(M, rhs, L, out[b]):
            for i in range(n):
                out[b, i] = np.nan
