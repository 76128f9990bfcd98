"""The UR5 chain built from its URDF's numbers against pinocchio loading the same URDF, to 1e-9:
kinematics, the mass matrix, bias forces, gravity, forward dynamics and whole reproductions."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.core import chain_dynamics as dyn
from mt_widgets.core import ur5_description
from mt_widgets.core.serial_chain import SerialChain

pin = pytest.importorskip("pinocchio")
urdf = pytest.importorskip("mt_widgets.robot_models.urdf")
pinocchio_reference = pytest.importorskip("mt_widgets.robot_models.pinocchio_reference")

TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def reference():
    model = pin.buildModelFromUrdf(str(urdf.example_robot_data_urdf("ur5")))
    return model, model.createData(), model.getFrameId("tool0")


@pytest.fixture(scope="module")
def chain():
    return SerialChain(ur5_description.JOINTS, ur5_description.INERTIALS, ur5_description.TIP)


def samples(count=50, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (rng.uniform(-2 * np.pi, 2 * np.pi, 6), rng.uniform(-3.2, 3.2, 6), rng.uniform(-10, 10, 6),
               rng.uniform(-30, 30, 6))


def test_the_chain_has_the_urdfs_joints_and_limits(chain, reference):
    model = reference[0]
    assert chain.joint_names == tuple(model.names[1:])
    np.testing.assert_array_equal(chain.lower, model.lowerPositionLimit)
    np.testing.assert_array_equal(chain.upper, model.upperPositionLimit)
    np.testing.assert_array_equal(chain.velocity_limit, model.velocityLimit)
    np.testing.assert_array_equal(chain.effort_limit, model.effortLimit)


def test_forward_kinematics_and_the_tool_pose_match_pinocchio(chain, reference):
    model, data, tool = reference
    assert np.allclose(chain.forward_kinematics(np.zeros(6)), [0.81725, 0.19145, -0.005491], atol=1e-12)
    for q, *_ in samples():
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        rotation, position = chain.tool_pose(q)
        assert np.abs(position - data.oMf[tool].translation).max() < TOLERANCE
        assert np.abs(rotation - data.oMf[tool].rotation).max() < TOLERANCE
        origins = chain.frame_origins(q)
        joints = np.array([data.oMi[i].translation for i in range(1, 7)])
        assert np.abs(origins[1:-1] - joints).max() < TOLERANCE


def test_the_tool_jacobian_matches_pinocchio(chain, reference):
    model, data, tool = reference
    for q, *_ in samples():
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        expected = pin.getFrameJacobian(model, data, tool, pin.LOCAL_WORLD_ALIGNED)[:3]
        assert np.abs(chain.jacobian(q) - expected).max() < TOLERANCE


def test_mass_matrix_bias_gravity_and_inverse_dynamics_match_pinocchio(chain, reference):
    model, data, _ = reference
    for q, qd, qdd, _ in samples():
        expected_mass = pin.crba(model, data, q)
        expected_mass = np.triu(expected_mass) + np.triu(expected_mass, 1).T
        assert np.abs(chain.mass_matrix(q) - expected_mass).max() < TOLERANCE
        assert np.abs(chain.nonlinear_effects(q, qd) - pin.nonLinearEffects(model, data, q, qd)).max() < TOLERANCE
        assert np.abs(chain.gravity_torque(q) - pin.computeGeneralizedGravity(model, data, q)).max() < TOLERANCE
        assert np.abs(chain.inverse_dynamics(q, qd, qdd) - pin.rnea(model, data, q, qd, qdd)).max() < TOLERANCE


def test_forward_dynamics_matches_pinocchios_aba(chain, reference):
    model, data, _ = reference
    for q, qd, _, tau in samples():
        assert np.abs(chain.forward_dynamics(q, qd, tau) - pin.aba(model, data, q, qd, tau)).max() < TOLERANCE


def test_a_batch_gives_what_one_configuration_at_a_time_gives(chain):
    q = np.array([s[0] for s in samples(12)]).reshape(3, 4, 6)
    qd = np.array([s[1] for s in samples(12)]).reshape(3, 4, 6)
    assert chain.mass_matrix(q).shape == (3, 4, 6, 6)
    np.testing.assert_array_equal(chain.nonlinear_effects(q, qd)[1, 2], chain.nonlinear_effects(q[1, 2], qd[1, 2]))
    np.testing.assert_array_equal(chain.jacobian(q)[2, 3], chain.jacobian(q[2, 3]))


def test_the_mass_matrix_is_symmetric_positive_definite_and_energy_is_consistent(chain):
    # A check that needs no reference: Mdot - 2C is skew-symmetric, so the power of the inverse
    # dynamics without gravity is qd . (M qdd + C qd) = qd . M qdd + 0.5 qd . Mdot qd (Mdot by differences).
    for q, qd, qdd, _ in samples(10, seed=1):
        mass = chain.mass_matrix(q)
        assert np.allclose(mass, mass.T, atol=1e-14) and np.all(np.linalg.eigvalsh(mass) > 0)
        step = 1e-6
        mass_dot = (chain.mass_matrix(q + step * qd) - chain.mass_matrix(q - step * qd)) / (2 * step)
        power = qd @ chain.inverse_dynamics(q, qd, qdd, gravity=False)
        assert power == pytest.approx(qd @ mass @ qdd + 0.5 * qd @ mass_dot @ qd, rel=1e-7, abs=1e-7)


def test_bad_configurations_are_refused_by_name(chain):
    with pytest.raises(ValueError, match=r"q: expected shape \(6\)"):
        chain.mass_matrix(np.zeros(5))
    with pytest.raises(ValueError, match="qd: expected finite"):
        chain.nonlinear_effects(np.zeros(6), [0, 0, np.nan, 0, 0, 0])


@pytest.mark.parametrize("key", ["ur5-reach", "ur5-place", "ur5-conveyor"])
def test_a_reproduction_matches_pinocchios_aba_stepped_the_same_way(key):
    skill = SKILLS[key]
    # Not the skill itself, whose reproduction settles: a policy off the target keeps the arm moving.
    theta = skill.theta + 0.1 * np.random.default_rng(1).standard_normal(skill.theta.shape)
    ours = skill.reproduce(theta)
    assert not ours.diverged
    reference = pinocchio_reference.PinocchioUR5(skill.plant).rollout(theta, skill.start, 10.0)
    assert np.abs(ours.states - reference).max() < TOLERANCE
    assert np.abs(ours.states[:, 6:12]).max() > 0.1          # it moved


def test_gravity_from_the_composite_bodies_equals_the_newton_euler_gravity(chain):
    n = chain.n_joints
    local_R, world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3, 3)), np.empty((n, 3))
    cm, ch, cJ, M, out = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.empty(n)
    for q, *_ in samples(20, seed=3):
        dyn.local_rotations(chain.placement_R, chain.axis, q, local_R)
        dyn.world_frames(local_R, chain.placement_p, world_R, world_p)
        dyn.crba(local_R, chain.placement_p, chain.axis, chain.mass, chain.com, chain.inertia, cm, ch, cJ, M)
        dyn.gravity_from_composites(world_R, chain.axis, ch, chain.gravity_vector, out)
        assert np.abs(out - chain.gravity_torque(q)).max() < 1e-12
