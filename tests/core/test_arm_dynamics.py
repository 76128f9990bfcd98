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


# -- rollouts: the chain engine (its planar fast path and its general algorithms) against the closed form --

def engine_rollout(leading, kernel, thetas, start, n_steps):
    """Runs one of the engine's serial kernels (its arguments before thetas: ``leading``) into fresh outputs."""
    batch, dim, n_task = thetas.shape[0], start.shape[0], thetas.shape[1]
    out = (np.empty((batch, n_steps + 1, dim)), np.empty((batch, n_steps + 1, n_task)),
           np.empty((batch, n_steps + 1, n_task)), np.empty((batch, n_steps + 1, n_task)),
           np.empty(batch, dtype=np.int64), np.empty(batch, dtype=np.int64), np.empty(batch, dtype=np.int64))
    kernel(*leading, thetas, start, 1e-3, n_steps, 1, out)
    return out


@pytest.mark.parametrize("compensate", [True, False])
@pytest.mark.parametrize("arm_name", list(ARMS))
def test_the_two_link_arms_rollouts_on_the_chain_engine_agree_with_its_closed_form(arm_name, compensate):
    from mt_widgets import SKILLS
    from mt_widgets.core import ArmPlant, EndEffectorFeatures, FunctionFeatures, chain_rollout
    from mt_widgets.core.plants import ContinuousPlant

    plant = ArmPlant(TwoLinkArm(**ARMS[arm_name], gravity_compensation=compensate))
    features = EndEffectorFeatures(plant)
    rng = np.random.default_rng(1)
    thetas = SKILLS["sim-point"].theta + rng.normal(scale=0.3, size=(3, 2, 5))
    start = np.array([0.3, 0.5, 0.4, -0.7])
    model, scene, control = plant.chain.model, plant.scene(), plant.control()
    assert chain_rollout.planar_pair(model, scene, control, 5).shape == (chain_rollout._PLANAR_SIZE,)
    # the plant's rollout (the engine's fast path) against RK4 of the closed form (the generic numpy loop)
    engine = plant.rollout(thetas, features, start, 0.5)
    oracle = ContinuousPlant.rollout(plant, thetas, FunctionFeatures(plant, features, names=features.names), start, 0.5)
    for name in ("states", "positions", "velocities", "actions"):
        assert np.abs(getattr(engine, name) - getattr(oracle, name)).max() < 1e-12, name
    # the engine's general algorithms (RNEA, CRBA, Cholesky) give the same rollout as its fast path
    general = engine_rollout((model, scene, control), chain_rollout.rollout_serial, thetas, start, 500)
    for got, expected in zip(general[:4], (engine.states, engine.positions, engine.velocities, engine.actions)):
        assert np.abs(got - expected).max() < 1e-12
    assert np.all(general[5] == -1) and not np.any(engine.diverged)


def tilted_pair():
    """A two-joint chain in a tilted plane, its second joint and every inertial off the links' line."""
    joints = [
        {"name": "a", "type": "revolute", "parent": "base", "child": "l1", "xyz": (0.1, -0.2, 0.3),
         "rpy": (0.3, 0.0, 0.2), "axis": (0.0, -1.0, 0.0), "lower": -2.0, "upper": 2.0, "velocity": 9.0,
         "effort": 40.0},
        # turned about its own axis (rpy about y) and set off along it (y): still parallel to the first
        {"name": "b", "type": "revolute", "parent": "l1", "child": "l2", "xyz": (0.8, 0.05, 0.1),
         "rpy": (0.0, 0.4, 0.0), "axis": (0.0, -1.0, 0.0), "lower": -2.5, "upper": 2.5, "velocity": 9.0,
         "effort": 30.0},
        {"name": "tool", "type": "fixed", "parent": "l2", "child": "tip", "xyz": (0.7, 0.02, -0.05),
         "rpy": (0.0, 0.0, 0.0), "axis": (1.0, 0.0, 0.0)},
    ]
    inertials = [
        {"link": "l1", "mass": 1.7, "xyz": (0.4, 0.02, 0.07), "rpy": (0.1, 0.2, 0.3),
         "inertia": (0.04, 0.002, 0.001, 0.05, 0.003, 0.03)},
        {"link": "l2", "mass": 0.9, "xyz": (0.3, -0.03, -0.06), "rpy": (0.0, 0.5, 0.0),
         "inertia": (0.02, 0.001, 0.0, 0.03, 0.002, 0.025)},
    ]
    return {"robot": "tilted", "source": "tilted pair", "joints": joints, "inertials": inertials, "tip": "tip",
            "locked": ()}


@pytest.mark.parametrize("compensate", [True, False])
def test_a_planar_pair_in_any_pose_takes_the_fast_path_with_the_general_algorithms_results(compensate):
    from mt_widgets.core import chain_rollout

    chain = SerialChain.from_description(tilted_pair())
    scene = chain_rollout.ChainScene(-np.inf, 4, np.empty((0, 2), dtype=np.int64), 0.0, 0.0, False)
    task = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, 0.8]])
    task.flags.writeable = False   # as the plants' tasks: the engine's kernels compiled for them serve
    control = chain_rollout.ChainControl(0.0, 0.0, 0.05, 0.0, np.zeros(2), False, task, True, compensate, True)
    p = chain_rollout.planar_pair(chain.model, scene, control, 5)
    assert p.shape == (chain_rollout._PLANAR_SIZE,)
    assert abs(p[chain_rollout._B]) > 1e-3 and abs(p[chain_rollout._PHI1]) > 1e-3  # the general case, not the paper's
    rng = np.random.default_rng(2)
    # small policies swing inside the limits; large ones reach a joint limit or a speed limit and stop
    thetas = np.concatenate([rng.normal(scale=0.5, size=(4, 2, 5)), rng.normal(scale=40.0, size=(4, 2, 5))])
    start = np.array([0.2, -0.4, 0.5, 0.3])
    fast = engine_rollout((p, compensate), chain_rollout.planar_rollout_serial, thetas, start, 500)
    general = engine_rollout((chain.model, scene, control), chain_rollout.rollout_serial, thetas, start, 500)
    assert np.array_equal(fast[4], general[4]) and np.array_equal(fast[5], general[5])
    assert np.array_equal(fast[6], general[6])
    stopped = set(fast[6].tolist()) - {0}
    assert np.any(fast[5] == -1) and stopped, "the test should hold rollouts that run through and ones that stop"
    for got, expected in zip(fast[:4], general[:4]):
        assert np.abs(got - expected).max() < 1e-12
    # the readouts agree with the chain's kinematics: positions are the task's view of the tool point
    for b in range(len(thetas)):
        n = fast[4][b]
        q, qd = fast[0][b, :n, :2], fast[0][b, :n, 2:]
        assert np.abs(fast[1][b, :n] - chain.forward_kinematics(q) @ task.T).max() < 1e-12
        assert np.abs(fast[2][b, :n] - chain.tool_velocity(q, qd) @ task.T).max() < 1e-12


def test_a_chain_that_is_not_a_planar_pair_takes_the_general_path():
    from mt_widgets.core import chain_rollout

    description = tilted_pair()
    scene = chain_rollout.ChainScene(-np.inf, 4, np.empty((0, 2), dtype=np.int64), 0.0, 0.0, False)
    task = np.eye(3)[[0, 2]]
    task.flags.writeable = False
    control = chain_rollout.ChainControl(0.0, 0.0, 0.0, 0.0, np.zeros(2), False, task, True, True, True)
    description["joints"][1]["axis"] = (0.0, -0.8, 0.6)   # the second axis no longer parallel to the first
    assert chain_rollout.planar_pair(SerialChain.from_description(description).model, scene, control, 5).size == 0
    chain = SerialChain.from_description(tilted_pair())
    table = scene._replace(table_height=-0.5, first_table_point=2)
    assert chain_rollout.planar_pair(chain.model, table, control, 5).size == 0   # a table to check
    velocity = control._replace(force_control=False, velocity_features=False)
    assert chain_rollout.planar_pair(chain.model, scene, velocity, 3).size == 0   # a velocity-taught arm


def test_a_kinematic_arm_with_velocity_features_is_refused_by_name():
    from mt_widgets.core import chain_rollout

    chain = SerialChain.from_description(tilted_pair())
    scene = chain_rollout.ChainScene(-np.inf, 4, np.empty((0, 2), dtype=np.int64), 0.0, 0.0, False)
    task = np.eye(3)[[0, 2]]
    control = chain_rollout.ChainControl(1.0, 0.01, 0.05, 0.0, np.zeros(2), True, task, False, False, True)
    thetas, start = np.zeros((1, 2, 5)), np.zeros(2)
    out = tuple(np.empty(shape) for shape in ((1, 3, 2), (1, 3, 2), (1, 3, 2), (1, 3, 2))) + tuple(
        np.empty(1, dtype=np.int64) for _ in range(3))
    with pytest.raises(ValueError, match=r"control: velocity_features=True needs a dynamic arm .* got kinematic=True"):
        chain_rollout.rollout(chain.model, scene, control, thetas, start, 0.01, 2, 1, out)
