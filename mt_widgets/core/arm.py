"""The planar two-link arm of the paper's simulation experiment: kinematics and rigid-body dynamics.

The arm moves in a vertical plane with its base at the origin; gravity points along -y.
``q1`` is measured from +x, ``q2`` relative to link 1. The equations are the standard
Euler-Lagrange model of a serial two-link arm with point-free links (each link has a mass, a
centre of mass along its axis and an inertia about that centre), so lengths, masses, centres
of mass and inertias are all parameters; the default is the paper's arm (1 m, 1 kg links)
with uniform rods, because the paper does not say how the mass is distributed.

Every method takes one state or a batch with leading axes and returns arrays with the same
leading shape.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .validation import as_bool, as_float_array, as_positive


def _pair(name: str, value, *, allow_zero: bool = False) -> tuple[float, float]:
    values = as_float_array(name, value, shape=(2,), ndim=1)
    for index, item in enumerate(values):
        as_positive(f"{name}[{index}]", float(item), allow_zero=allow_zero)
    return float(values[0]), float(values[1])


@dataclass(frozen=True)
class ArmParameters:
    """The numbers the closed-form dynamics need, in SI units."""

    l1: float
    l2: float
    m1: float
    m2: float
    lc1: float
    lc2: float
    i1: float
    i2: float
    gravity: float


class TwoLinkArm:
    """A planar two-link arm in a vertical plane, driven by an end-effector force.

    Args:
        link_lengths: (l1, l2) in metres.
        masses: (m1, m2) in kilograms.
        com_fractions: where each link's centre of mass sits along it, as a fraction of its
            length (0.5 = the middle, as for a uniform rod).
        inertias: (I1, I2) about each link's centre of mass in kg m^2; None gives uniform rods,
            m l^2 / 12.
        gravity: gravitational acceleration in m/s^2 along -y (0 for a horizontal arm).
        gravity_compensation: whether the arm's controller adds g(q) to the commanded torque.
            On by default: the paper's unit-gain skills cannot hold a 2 kg arm up otherwise
            (rolled out raw, sim-point hangs the arm near (0.31, -1.96) after 10 s).

    The dynamics are ``M(q) qdd + C(q, qd) qd + g(q) = tau`` with ``tau = J(q)^T u`` (plus
    ``g(q)`` under compensation) for the end-effector force ``u``.
    """

    def __init__(self, link_lengths=(1.0, 1.0), masses=(1.0, 1.0), com_fractions=(0.5, 0.5),
                 inertias=None, gravity=9.81, gravity_compensation=True):
        l1, l2 = _pair("link_lengths", link_lengths)
        m1, m2 = _pair("masses", masses)
        fractions = as_float_array("com_fractions", com_fractions, shape=(2,), ndim=1)
        if np.any(fractions < 0) or np.any(fractions > 1):
            raise ValueError(f"com_fractions: expected two fractions in [0, 1], got {fractions.tolist()}")
        if inertias is None:
            i1, i2 = m1 * l1**2 / 12.0, m2 * l2**2 / 12.0
        else:
            i1, i2 = _pair("inertias", inertias, allow_zero=True)
        gravity = as_positive("gravity", gravity, allow_zero=True)
        self.link_lengths = (l1, l2)
        self.masses = (m1, m2)
        self.com_fractions = (float(fractions[0]), float(fractions[1]))
        self.inertias = (i1, i2)
        self.gravity = gravity
        self.gravity_compensation = as_bool("gravity_compensation", gravity_compensation)
        self.parameters = ArmParameters(l1, l2, m1, m2, fractions[0] * l1, fractions[1] * l2, i1, i2, gravity)
        p = self.parameters
        # det M(q) = (m1 lc1^2 + I1 + m2 l1^2)(m2 lc2^2 + I2) - (m2 l1 lc2 cos q2)^2; positive for
        # every q2 exactly when it is positive at q2 = 0. Otherwise some pose cannot be accelerated.
        worst = (p.m1 * p.lc1**2 + p.i1 + p.m2 * p.l1**2) * (p.m2 * p.lc2**2 + p.i2) - (p.m2 * p.l1 * p.lc2) ** 2
        if not worst > 1e-12 * (p.m1 + p.m2) ** 2 * (p.l1 + p.l2) ** 4:
            raise ValueError(f"inertias: expected a mass distribution with a non-singular mass matrix in every pose; "
                             f"masses={self.masses}, com_fractions={self.com_fractions}, inertias={self.inertias} "
                             f"give a singular one when the arm is stretched (give the links some inertia)")

    def __repr__(self) -> str:
        return (f"TwoLinkArm(link_lengths={self.link_lengths}, masses={self.masses}, "
                f"com_fractions={self.com_fractions}, inertias={self.inertias}, gravity={self.gravity}, "
                f"gravity_compensation={self.gravity_compensation})")

    @property
    def reach(self) -> float:
        """The largest distance of the end-effector from the base, in metres."""
        return self.link_lengths[0] + self.link_lengths[1]

    def chain_description(self) -> dict:
        """The arm as a serial chain's description, as the URDF reader gives one (``SerialChain.from_description``).

        The arm's plane (x, y) becomes the chain's (x, z), so gravity is along the chain's -z as
        for every arm on the engine: the joints turn about -y (from +x towards +z), the links lie
        along x, the tool at the tip. Its chain's (x, z) and M, C qd + g, J equal this class's
        closed forms (tests/core/test_arm_dynamics.py, to 1e-12).
        """
        p = self.parameters
        unlimited = {"lower": -np.inf, "upper": np.inf, "velocity": np.inf, "effort": np.inf}
        joints = [
            {"name": "q1", "type": "continuous", "parent": "base", "child": "link1", "xyz": (0.0, 0.0, 0.0),
             "rpy": (0.0, 0.0, 0.0), "axis": (0.0, -1.0, 0.0)} | unlimited,
            {"name": "q2", "type": "continuous", "parent": "link1", "child": "link2", "xyz": (p.l1, 0.0, 0.0),
             "rpy": (0.0, 0.0, 0.0), "axis": (0.0, -1.0, 0.0)} | unlimited,
            {"name": "tip", "type": "fixed", "parent": "link2", "child": "tip", "xyz": (p.l2, 0.0, 0.0),
             "rpy": (0.0, 0.0, 0.0), "axis": (1.0, 0.0, 0.0)},
        ]
        # Only the inertia about the joints' axis (iyy) enters a planar motion; the others are set
        # alike so that each link's inertia is a physical one.
        inertials = [{"link": f"link{k}", "mass": m, "xyz": (lc, 0.0, 0.0), "rpy": (0.0, 0.0, 0.0),
                      "inertia": (i, 0.0, 0.0, i, 0.0, i)}
                     for k, m, lc, i in ((1, p.m1, p.lc1, p.i1), (2, p.m2, p.lc2, p.i2))]
        return {"robot": "two_link_arm", "source": repr(self), "joints": joints, "inertials": inertials, "tip": "tip",
                "locked": ()}

    # -- kinematics -------------------------------------------------------------------------
    def forward_kinematics(self, q) -> np.ndarray:
        """End-effector position. q: (..., 2) rad -> (..., 2) m."""
        return self.joint_positions(q)[..., 2, :]

    def joint_positions(self, q) -> np.ndarray:
        """Base, elbow and end-effector positions. q: (..., 2) rad -> (..., 3, 2) m."""
        q = as_float_array("q", q, shape=(2,))
        l1, l2 = self.link_lengths
        q1, q12 = q[..., 0], q[..., 0] + q[..., 1]
        elbow = np.stack([l1 * np.cos(q1), l1 * np.sin(q1)], axis=-1)
        tip = elbow + np.stack([l2 * np.cos(q12), l2 * np.sin(q12)], axis=-1)
        return np.stack([np.zeros_like(elbow), elbow, tip], axis=-2)

    def jacobian(self, q) -> np.ndarray:
        """d(end-effector position)/dq. q: (..., 2) -> (..., 2, 2), rows (x, y), columns (q1, q2)."""
        q = as_float_array("q", q, shape=(2,))
        l1, l2 = self.link_lengths
        s1, c1 = np.sin(q[..., 0]), np.cos(q[..., 0])
        s12, c12 = np.sin(q[..., 0] + q[..., 1]), np.cos(q[..., 0] + q[..., 1])
        row_x = np.stack([-l1 * s1 - l2 * s12, -l2 * s12], axis=-1)
        row_y = np.stack([l1 * c1 + l2 * c12, l2 * c12], axis=-1)
        return np.stack([row_x, row_y], axis=-2)

    def end_effector_velocity(self, q, qd) -> np.ndarray:
        """rdot = J(q) qd. q, qd: (..., 2) -> (..., 2) m/s."""
        qd = as_float_array("qd", qd, shape=(2,))
        return np.einsum("...ij,...j->...i", self.jacobian(q), qd)

    def inverse_kinematics(self, position, elbow_up: bool = True) -> np.ndarray:
        """Joint angles that put the end-effector at ``position``. (..., 2) m -> (..., 2) rad.

        Raises ValueError for positions outside the annulus the arm can reach.
        """
        position = as_float_array("position", position, shape=(2,))
        elbow_up = as_bool("elbow_up", elbow_up)
        l1, l2 = self.link_lengths
        distance_sq = np.sum(position**2, axis=-1)
        cos_q2 = (distance_sq - l1**2 - l2**2) / (2 * l1 * l2)
        if np.any(np.abs(cos_q2) > 1 + 1e-12):
            raise ValueError(f"position: expected points at a distance between {abs(l1 - l2)} and {l1 + l2} m "
                             f"from the base, got distances {np.sqrt(distance_sq).round(4).tolist()}")
        q2 = np.arccos(np.clip(cos_q2, -1.0, 1.0)) * (1.0 if elbow_up else -1.0)
        q1 = np.arctan2(position[..., 1], position[..., 0]) - np.arctan2(l2 * np.sin(q2), l1 + l2 * np.cos(q2))
        return np.stack([q1, q2], axis=-1)

    # -- dynamics ---------------------------------------------------------------------------
    def mass_matrix(self, q) -> np.ndarray:
        """M(q): (..., 2) -> (..., 2, 2) kg m^2."""
        q = as_float_array("q", q, shape=(2,))
        p = self.parameters
        c2 = np.cos(q[..., 1])
        m22 = np.full_like(c2, p.m2 * p.lc2**2 + p.i2)
        m12 = m22 + p.m2 * p.l1 * p.lc2 * c2
        m11 = p.m1 * p.lc1**2 + p.i1 + p.m2 * (p.l1**2 + 2 * p.l1 * p.lc2 * c2) + m22
        return np.stack([np.stack([m11, m12], -1), np.stack([m12, m22], -1)], -2)

    def coriolis_matrix(self, q, qd) -> np.ndarray:
        """C(q, qd) with Christoffel symbols, so that Mdot - 2C is skew-symmetric. -> (..., 2, 2)."""
        q = as_float_array("q", q, shape=(2,))
        qd = as_float_array("qd", qd, shape=(2,))
        p = self.parameters
        h = p.m2 * p.l1 * p.lc2 * np.sin(q[..., 1])
        qd1, qd2 = np.broadcast_arrays(qd[..., 0], qd[..., 1])
        h = np.broadcast_to(h, qd1.shape)
        row1 = np.stack([-h * qd2, -h * (qd1 + qd2)], -1)
        row2 = np.stack([h * qd1, np.zeros_like(h)], -1)
        return np.stack([row1, row2], -2)

    def gravity_torque(self, q) -> np.ndarray:
        """g(q) = dV/dq: (..., 2) -> (..., 2) N m (zero when ``gravity`` is 0)."""
        q = as_float_array("q", q, shape=(2,))
        p = self.parameters
        c1, c12 = np.cos(q[..., 0]), np.cos(q[..., 0] + q[..., 1])
        g2 = p.m2 * p.lc2 * p.gravity * c12
        g1 = (p.m1 * p.lc1 + p.m2 * p.l1) * p.gravity * c1 + g2
        return np.stack([g1, g2], -1)

    def joint_acceleration(self, q, qd, torque) -> np.ndarray:
        """qdd = M^-1 (tau - C qd - g) for a given joint torque (the raw plant, no controller)."""
        torque = as_float_array("torque", torque, shape=(2,))
        q = as_float_array("q", q, shape=(2,))
        qd = as_float_array("qd", qd, shape=(2,))
        bias = np.einsum("...ij,...j->...i", self.coriolis_matrix(q, qd), qd) + self.gravity_torque(q)
        return np.linalg.solve(self.mass_matrix(q), (torque - bias)[..., None])[..., 0]

    def applied_torque(self, q, force) -> np.ndarray:
        """The controller's joint torque for an end-effector force: J^T u, plus g(q) under compensation."""
        force = as_float_array("force", force, shape=(2,))
        torque = np.einsum("...ji,...j->...i", self.jacobian(q), force)
        if self.gravity_compensation:
            torque = torque + self.gravity_torque(q)
        return torque

    def forward_dynamics(self, q, qd, force) -> np.ndarray:
        """Joint accelerations under an end-effector force ``force`` (..., 2) N -> (..., 2) rad/s^2.

        Includes the controller's gravity compensation when it is on, evaluated at this very
        state (so gravity cancels exactly at this instant).
        """
        return self.joint_acceleration(q, qd, self.applied_torque(q, force))

    # -- energy -----------------------------------------------------------------------------
    def kinetic_energy(self, q, qd) -> np.ndarray:
        """0.5 qd^T M(q) qd in joules: (..., 2), (..., 2) -> (...)."""
        qd = as_float_array("qd", qd, shape=(2,))
        return 0.5 * np.einsum("...i,...ij,...j->...", qd, self.mass_matrix(q), qd)

    def potential_energy(self, q) -> np.ndarray:
        """Gravitational potential energy in joules (zero at y = 0): (..., 2) -> (...)."""
        q = as_float_array("q", q, shape=(2,))
        p = self.parameters
        s1, s12 = np.sin(q[..., 0]), np.sin(q[..., 0] + q[..., 1])
        return p.gravity * (p.m1 * p.lc1 * s1 + p.m2 * (p.l1 * s1 + p.lc2 * s12))
