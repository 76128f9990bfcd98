"""The arm's dynamics against an independent Euler-Lagrange derivation done symbolically here, and the
chain engine against the arm's closed form (the two-link arm as a two-joint chain)."""

import numpy as np
import pytest
import sympy as sp

from mt_widgets import TwoLinkArm
from mt_widgets.core.serial_chain import SerialChain

ARMS = {
    "paper arm": dict(),
    "non-default arm": dict(link_lengths=(0.7, 1.3), masses=(2.0, 0.6), com_fractions=(0.3, 0.8),
                            inertias=(0.05, 0.21), gravity=3.7),
}


def euler_lagrange_model(arm: TwoLinkArm):
    """M(q), the velocity bias (Mdot qd - dT/dq) and g(q), derived from the Lagrangian with sympy."""
    q1, q2, qd1, qd2 = sp.symbols("q1 q2 qd1 qd2", real=True)
    (l1, _), (m1, m2), (f1, f2), (i1, i2) = arm.link_lengths, arm.masses, arm.com_fractions, arm.inertias
    lc1, lc2 = f1 * arm.link_lengths[0], f2 * arm.link_lengths[1]
    g = arm.gravity
    q, qd = sp.Matrix([q1, q2]), sp.Matrix([qd1, qd2])
    com1 = sp.Matrix([lc1 * sp.cos(q1), lc1 * sp.sin(q1)])
    com2 = sp.Matrix([l1 * sp.cos(q1) + lc2 * sp.cos(q1 + q2), l1 * sp.sin(q1) + lc2 * sp.sin(q1 + q2)])
    v1, v2 = com1.jacobian(q) * qd, com2.jacobian(q) * qd
    kinetic = (m1 * v1.dot(v1) + m2 * v2.dot(v2)) / 2 + i1 * qd1**2 / 2 + i2 * (qd1 + qd2) ** 2 / 2
    potential = g * (m1 * com1[1] + m2 * com2[1])
    mass = sp.hessian(kinetic, qd)
    mass_dot = sum((mass.diff(qk) * qdk for qk, qdk in zip(q, qd)), sp.zeros(2, 2))
    bias = mass_dot * qd - sp.Matrix([kinetic.diff(qk) for qk in q])
    gravity = sp.Matrix([potential.diff(qk) for qk in q])
    args = (q1, q2, qd1, qd2)
    return (sp.lambdify(args, mass, "numpy"), sp.lambdify(args, bias, "numpy"), sp.lambdify(args, gravity, "numpy"),
            sp.lambdify(args, mass_dot, "numpy"))


@pytest.fixture(scope="module", params=list(ARMS))
def arm_and_model(request):
    arm = TwoLinkArm(**ARMS[request.param], gravity_compensation=False)
    return arm, euler_lagrange_model(arm)


def random_states(n=25, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (n, 2)), rng.uniform(-3, 3, (n, 2))


def test_mass_coriolis_and_gravity_match_the_symbolic_derivation(arm_and_model):
    arm, (mass, bias, gravity, _) = arm_and_model
    q, qd = random_states()
    M, C, g = arm.mass_matrix(q), arm.coriolis_matrix(q, qd), arm.gravity_torque(q)
    for k in range(len(q)):
        args = (*q[k], *qd[k])
        np.testing.assert_allclose(M[k], mass(*args), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(C[k] @ qd[k], np.ravel(bias(*args)), rtol=1e-12, atol=1e-11)
        np.testing.assert_allclose(g[k], np.ravel(gravity(*args)), rtol=1e-12, atol=1e-12)


def test_forward_dynamics_solves_the_symbolic_equations_of_motion(arm_and_model):
    arm, (mass, bias, gravity, _) = arm_and_model
    q, qd = random_states(seed=1)
    force = np.random.default_rng(2).normal(size=(len(q), 2))
    qdd = arm.forward_dynamics(q, qd, force)
    for k in range(len(q)):
        args = (*q[k], *qd[k])
        torque = arm.jacobian(q[k]).T @ force[k]
        residual = mass(*args) @ qdd[k] + np.ravel(bias(*args)) + np.ravel(gravity(*args)) - torque
        np.testing.assert_allclose(residual, 0, atol=1e-10)


def test_mdot_minus_two_c_is_skew_symmetric(arm_and_model):
    arm, (_, _, _, mass_dot) = arm_and_model
    q, qd = random_states(seed=3)
    C = arm.coriolis_matrix(q, qd)
    for k in range(len(q)):
        N = mass_dot(*q[k], *qd[k]) - 2 * C[k]
        np.testing.assert_allclose(N, -N.T, atol=1e-12)
        assert abs(N[0, 1]) > 1e-6 or np.allclose(qd[k], 0)  # not trivially zero


def test_paper_mass_matrix_is_the_design_formula():
    arm = TwoLinkArm()
    q = np.array([[0.1, 0.0], [0.4, 1.1], [-2.0, 2.9]])
    c2 = np.cos(q[:, 1])
    expected = np.stack([np.stack([5 / 3 + c2, 1 / 3 + c2 / 2], -1),
                         np.stack([1 / 3 + c2 / 2, np.full(3, 1 / 3)], -1)], -2)
    np.testing.assert_allclose(arm.mass_matrix(q), expected, rtol=1e-14)


def test_jacobian_is_the_derivative_of_forward_kinematics():
    arm = TwoLinkArm(link_lengths=(0.8, 1.1))
    q, _ = random_states(seed=4)
    h = 1e-6
    numeric = np.stack([(arm.forward_kinematics(q + h * e) - arm.forward_kinematics(q - h * e)) / (2 * h)
                        for e in np.eye(2)], axis=-1)
    np.testing.assert_allclose(arm.jacobian(q), numeric, atol=1e-8)


def test_inverse_kinematics_round_trips_and_refuses_unreachable_points():
    arm = TwoLinkArm()
    q = np.array([[0.3, 0.5], [-1.0, 1.7], [2.5, 0.2]])
    np.testing.assert_allclose(arm.forward_kinematics(arm.inverse_kinematics(arm.forward_kinematics(q))),
                               arm.forward_kinematics(q), atol=1e-12)
    with pytest.raises(ValueError, match="position"):
        arm.inverse_kinematics([2.5, 0.0])


def test_every_method_keeps_leading_batch_axes():
    arm = TwoLinkArm()
    q = np.zeros((3, 4, 2))
    assert arm.forward_kinematics(q).shape == (3, 4, 2)
    assert arm.joint_positions(q).shape == (3, 4, 3, 2)
    assert arm.jacobian(q).shape == (3, 4, 2, 2)
    assert arm.mass_matrix(q).shape == (3, 4, 2, 2)
    assert arm.coriolis_matrix(q, q).shape == (3, 4, 2, 2)
    assert arm.gravity_torque(q).shape == (3, 4, 2)
    assert arm.forward_dynamics(q, q, q).shape == (3, 4, 2)
    assert arm.forward_dynamics([0.1, 0.2], [0, 0], [1, 0]).shape == (2,)


def test_gravity_compensation_cancels_gravity_at_the_instant():
    q, qd = random_states(seed=5)
    compensated = TwoLinkArm(gravity_compensation=True).forward_dynamics(q, qd, np.zeros_like(q))
    weightless = TwoLinkArm(gravity=0.0, gravity_compensation=False).forward_dynamics(q, qd, np.zeros_like(q))
    np.testing.assert_allclose(compensated, weightless, atol=1e-12)


@pytest.mark.parametrize("kwargs, name", [
    (dict(link_lengths=(1.0, -1.0)), "link_lengths"),
    (dict(masses=(1.0,)), "masses"),
    (dict(com_fractions=(0.5, 1.5)), "com_fractions"),
    (dict(inertias=(0.1, float("nan"))), "inertias"),
    (dict(gravity=-9.81), "gravity"),
    (dict(gravity_compensation="yes"), "gravity_compensation"),
])
def test_bad_arm_parameters_are_refused_by_name(kwargs, name):
    with pytest.raises(TypeError if name == "gravity_compensation" else ValueError, match=name):   # a str, not a bool
        TwoLinkArm(**kwargs)


def test_bad_states_are_refused_by_name():
    arm = TwoLinkArm()
    with pytest.raises(ValueError, match=r"q: expected shape \(2\)"):
        arm.mass_matrix([0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="qd: expected finite"):
        arm.coriolis_matrix([0.1, 0.2], [np.nan, 0.0])


def test_a_mass_distribution_with_a_singular_mass_matrix_is_refused():
    with pytest.raises(ValueError, match="inertias: expected a mass distribution"):
        TwoLinkArm(com_fractions=(0.0, 0.0), inertias=(0.0, 0.0))
    with pytest.raises(ValueError, match="singular"):
        TwoLinkArm(com_fractions=(0.0, 1.0), inertias=(0.0, 0.0))  # point mass at the tip, none at the elbow
    TwoLinkArm(com_fractions=(1.0, 1.0), inertias=(0.0, 0.0))       # point masses at elbow and tip: fine


def test_a_state_at_a_singular_pose_is_refused_with_a_velocity_and_allowed_at_rest():
    from mt_widgets.core import ArmPlant

    plant = ArmPlant()
    np.testing.assert_allclose(plant.end_effector(plant.state_at([2.0, 0.0]))[0], [2.0, 0.0], atol=1e-9)
    with pytest.raises(ValueError, match="position"):
        plant.state_at([2.0, 0.0], velocity=[0.0, 1.0])


@pytest.mark.parametrize("arm", [TwoLinkArm(), TwoLinkArm(link_lengths=(0.7, 1.2), masses=(2.0, 0.5),
                                                          com_fractions=(0.3, 0.6), inertias=(0.05, 0.02),
                                                          gravity=3.0)])
def test_the_two_link_arm_on_the_chain_engine_agrees_with_its_closed_form(arm):
    chain = SerialChain.from_description(arm.chain_description(), gravity=arm.gravity)
    rng = np.random.default_rng(0)
    for _ in range(10):
        q, qd, force = rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3, 3, 2), rng.uniform(-5, 5, 2)
        tool = chain.forward_kinematics(q)
        assert np.abs(tool[[0, 2]] - arm.forward_kinematics(q)).max() < 1e-12 and abs(tool[1]) < 1e-12
        assert np.abs(chain.jacobian(q)[[0, 2]] - arm.jacobian(q)).max() < 1e-12
        assert np.abs(chain.mass_matrix(q) - arm.mass_matrix(q)).max() < 1e-12
        bias = arm.coriolis_matrix(q, qd) @ qd + arm.gravity_torque(q)
        assert np.abs(chain.nonlinear_effects(q, qd) - bias).max() < 1e-12
        torque = arm.applied_torque(q, force)
        assert np.abs(chain.forward_dynamics(q, qd, torque) - arm.joint_acceleration(q, qd, torque)).max() < 1e-12
