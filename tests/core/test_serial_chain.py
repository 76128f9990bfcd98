"""The chain engine against pinocchio loading the same URDF, to 1e-9: kinematics, the tool Jacobian,
the mass matrix, bias forces, gravity and forward dynamics, for every shipped arm and every serial
arm of example-robot-data the loader accepts; and whole UR5 reproductions against pinocchio's ABA."""

from pathlib import Path

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.arms import ur5_chain
from mt_widgets.core import chain_dynamics as dyn
from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.robot_models.urdf import SHIPPED, URDFError, load_shipped, parse_urdf, read_urdf

pin = pytest.importorskip("pinocchio")
urdf = pytest.importorskip("mt_widgets.robot_models.urdf")
pinocchio_reference = pytest.importorskip("mt_widgets.robot_models.pinocchio_reference")

TOLERANCE = 1e-9

#: example-robot-data's arms whose URDF ends in two frames after the last joint: the tool named.
NAMED_TOOLS = {
    "ur_description/urdf/ur3_robot.urdf": "tool0",
    "ur_description/urdf/ur5_robot.urdf": "tool0",
    "ur_description/urdf/ur10_robot.urdf": "tool0",
    "ur_description/urdf/ur5_joint_limited_robot.urdf": "tool0",
}


def _example_robot_data_arms():
    """(id, description) of each URDF of example-robot-data the loader makes a serial arm of."""
    try:
        robots = urdf.example_robot_data_urdf("ur5").parents[2]
    except (ModuleNotFoundError, FileNotFoundError):
        return []
    found = []
    for path in sorted(robots.rglob("*.urdf")):
        relative = path.relative_to(robots).as_posix()
        try:
            found.append((relative, read_urdf(path, NAMED_TOOLS.get(relative))))
        except URDFError:
            continue   # a humanoid, a quadruped, a hand: not one serial arm (the refusals are tested below)
    return found


ARMS = [(f"shipped:{name}", load_shipped(name)) for name in SHIPPED] + _example_robot_data_arms()


def _reference(description):
    model, data, tool = pinocchio_reference.pinocchio_chain(description)
    return model, data, tool


def samples(chain, count, seed=0):
    rng = np.random.default_rng(seed)
    low = np.where(np.isfinite(chain.lower), chain.lower, -np.pi)
    high = np.where(np.isfinite(chain.upper), chain.upper, np.pi)
    n = chain.n_joints
    for _ in range(count):
        yield rng.uniform(low, high), rng.uniform(-2, 2, n), rng.uniform(-5, 5, n), rng.uniform(-3, 3, n)


def test_the_sweep_finds_the_arms_of_example_robot_data():
    names = {name for name, _ in ARMS}
    assert {"shipped:ur5", "shipped:panda", "shipped:so101"} <= names
    if len(names) > 3:   # example-robot-data installed (the test extra)
        assert {"ur_description/urdf/ur10_robot.urdf", "so_arm_description/urdf/so100.urdf",
                "z1_description/urdf/z1.urdf", "xarm_description/urdf/xarm7.urdf"} <= names


@pytest.mark.parametrize("name, description", ARMS, ids=[name for name, _ in ARMS])
def test_kinematics_jacobian_mass_matrix_and_bias_forces_match_pinocchio(name, description):
    model, data, tool = _reference(description)
    try:
        chain = SerialChain.from_description(description)
    except ValueError as error:
        assert "positive mass" in str(error)   # a massless moving body: kinematics only
        chain = SerialChain.from_description(description, dynamics=False)
    assert chain.joint_names == tuple(model.names[1:])
    assert model.nv == chain.n_joints
    for q, qd, qdd, tau in samples(chain, 3):
        q_pin = pinocchio_reference.pinocchio_configuration(model, q)
        pin.forwardKinematics(model, data, q_pin)
        pin.updateFramePlacements(model, data)
        rotation, position = chain.tool_pose(q)
        assert np.abs(position - data.oMf[tool].translation).max() < TOLERANCE
        assert np.abs(rotation - data.oMf[tool].rotation).max() < TOLERANCE
        joints = np.array([data.oMi[i].translation for i in range(1, model.njoints)])
        assert np.abs(chain.frame_origins(q)[1:-1] - joints).max() < TOLERANCE
        pin.computeJointJacobians(model, data, q_pin)
        pin.updateFramePlacements(model, data)
        expected = pin.getFrameJacobian(model, data, tool, pin.LOCAL_WORLD_ALIGNED)[:3]
        assert np.abs(chain.jacobian(q) - expected).max() < TOLERANCE
        if not chain.has_dynamics:
            continue
        mass = pin.crba(model, data, q_pin)
        mass = np.triu(mass) + np.triu(mass, 1).T
        assert np.abs(chain.mass_matrix(q) - mass).max() < TOLERANCE
        assert np.abs(chain.nonlinear_effects(q, qd) - pin.nonLinearEffects(model, data, q_pin, qd)).max() < TOLERANCE
        assert np.abs(chain.gravity_torque(q) - pin.computeGeneralizedGravity(model, data, q_pin)).max() < TOLERANCE
        assert np.abs(chain.inverse_dynamics(q, qd, qdd) - pin.rnea(model, data, q_pin, qd, qdd)).max() < TOLERANCE
        assert np.abs(chain.forward_dynamics(q, qd, tau) - pin.aba(model, data, q_pin, qd, tau)).max() < 1e-7 * max(
            1.0, np.abs(pin.aba(model, data, q_pin, qd, tau)).max())


#: A chain of every joint type the loader understands: continuous, prismatic (twice, one off-axis),
#: revolute, with fixed joints and a welded link between them.
EVERY_JOINT = """<robot name="every_joint">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0 0.2" rpy="0.1 0.2 0.3"/><mass value="2"/>
    <inertia ixx="0.1" ixy="0.01" ixz="0" iyy="0.2" iyz="0.02" izz="0.3"/></inertial></link>
  <link name="b"><inertial><origin xyz="0 0.1 0.1"/><mass value="1.5"/>
    <inertia ixx="0.05" ixy="0" ixz="0.01" iyy="0.04" iyz="0" izz="0.03"/></inertial></link>
  <link name="b_plate"><inertial><origin xyz="0.05 0 0"/><mass value="0.3"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <link name="c"><inertial><origin xyz="0.2 0 0"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <link name="d"><inertial><origin xyz="0 0 0.05"/><mass value="0.5"/>
    <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial></link>
  <link name="tool"/>
  <joint name="turn" type="continuous"><parent link="base"/><child link="a"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit effort="50" velocity="2"/></joint>
  <joint name="lift" type="prismatic"><parent link="a"/><child link="b"/><origin xyz="0.1 0 0.2" rpy="0.3 0 0"/>
    <axis xyz="0 0.6 0.8"/><limit effort="100" lower="-0.2" upper="0.3" velocity="0.5"/></joint>
  <joint name="plate" type="fixed"><parent link="b"/><child link="b_plate"/><origin xyz="0 0 0.1"/></joint>
  <joint name="elbow" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0.2 0" rpy="0 0.5 0"/>
    <axis xyz="1 0 0"/><limit effort="30" lower="-2" upper="2" velocity="3"/></joint>
  <joint name="reach" type="prismatic"><parent link="c"/><child link="d"/><origin xyz="0.4 0 0"/>
    <axis xyz="1 0 0"/><limit effort="20" lower="0" upper="0.2" velocity="0.3"/></joint>
  <joint name="flange" type="fixed"><parent link="d"/><child link="tool"/><origin xyz="0 0 0.1" rpy="0 0 1"/></joint>
</robot>"""


def test_continuous_and_prismatic_joints_match_pinocchio(tmp_path):
    path = tmp_path / "every_joint.urdf"
    path.write_text(EVERY_JOINT)
    description = read_urdf(path, "tool")
    chain = SerialChain.from_description(description)
    assert chain.prismatic.tolist() == [0, 1, 0, 1] and chain.lower[0] == -np.inf
    test_kinematics_jacobian_mass_matrix_and_bias_forces_match_pinocchio("every_joint", description)


def test_the_ur5_chain_is_the_urdfs_joints_and_limits():
    chain = ur5_chain()
    model, _, _ = _reference(load_shipped("ur5"))
    np.testing.assert_array_equal(chain.lower, model.lowerPositionLimit)
    np.testing.assert_array_equal(chain.upper, model.upperPositionLimit)
    np.testing.assert_array_equal(chain.velocity_limit, model.velocityLimit)
    np.testing.assert_array_equal(chain.effort_limit, model.effortLimit)
    assert np.allclose(chain.forward_kinematics(np.zeros(6)), [0.81725, 0.19145, -0.005491], atol=1e-12)


def test_a_batch_gives_what_one_configuration_at_a_time_gives():
    chain = ur5_chain()
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-3, 3, (3, 4, 6)), rng.uniform(-3, 3, (3, 4, 6))
    assert chain.mass_matrix(q).shape == (3, 4, 6, 6)
    np.testing.assert_array_equal(chain.nonlinear_effects(q, qd)[1, 2], chain.nonlinear_effects(q[1, 2], qd[1, 2]))
    np.testing.assert_array_equal(chain.jacobian(q)[2, 3], chain.jacobian(q[2, 3]))


def test_the_mass_matrix_is_symmetric_positive_definite_and_energy_is_consistent():
    # A check that needs no reference: Mdot - 2C is skew-symmetric, so the power of the inverse
    # dynamics without gravity is qd . (M qdd + C qd) = qd . M qdd + 0.5 qd . Mdot qd (Mdot by differences).
    chain = SerialChain.from_description(parse_urdf(EVERY_JOINT, "tool"))
    for q, qd, qdd, _ in samples(chain, 10, seed=1):
        mass = chain.mass_matrix(q)
        assert np.allclose(mass, mass.T, atol=1e-14) and np.all(np.linalg.eigvalsh(mass) > 0)
        step = 1e-6
        mass_dot = (chain.mass_matrix(q + step * qd) - chain.mass_matrix(q - step * qd)) / (2 * step)
        power = qd @ chain.inverse_dynamics(q, qd, qdd, gravity=False)
        assert power == pytest.approx(qd @ mass @ qdd + 0.5 * qd @ mass_dot @ qd, rel=1e-7, abs=1e-7)


def test_bad_configurations_are_refused_by_name():
    chain = ur5_chain()
    with pytest.raises(ValueError, match=r"q: expected shape \(6\)"):
        chain.mass_matrix(np.zeros(5))
    with pytest.raises(ValueError, match="qd: expected finite"):
        chain.nonlinear_effects(np.zeros(6), [0, 0, np.nan, 0, 0, 0])


def test_a_chain_without_inertias_gives_kinematics_and_refuses_dynamics_by_name():
    description = parse_urdf(EVERY_JOINT.replace('<mass value="1.5"/>', '<mass value="0"/>').replace(
        '<mass value="0.3"/>', '<mass value="0"/>'), "tool", source="arm.urdf")
    with pytest.raises(ValueError, match=r"arm.urdf: links \['b', 'b_plate'\] \(moved by joint 'lift'\): expected an "
                                         r"<inertial> with a positive mass"):
        SerialChain.from_description(description)
    chain = SerialChain.from_description(description, dynamics=False)
    assert chain.forward_kinematics(np.zeros(4)).shape == (3,)
    with pytest.raises(ValueError, match="arm.urdf: expected a positive mass on every moving body"):
        chain.mass_matrix(np.zeros(4))


@pytest.mark.parametrize("key", ["ur5-reach", "ur5-place", "ur5-conveyor"])
def test_a_reproduction_matches_pinocchios_aba_stepped_the_same_way(key):
    skill = SKILLS[key]
    # Not the skill itself, whose reproduction settles: a policy off the target keeps the arm moving.
    theta = skill.theta + 0.1 * np.random.default_rng(1).standard_normal(skill.theta.shape)
    ours = skill.reproduce(theta)
    assert not ours.diverged
    reference = pinocchio_reference.PinocchioArm(skill.plant).rollout(theta, skill.start, 10.0)
    assert np.abs(ours.states - reference).max() < TOLERANCE
    assert np.abs(ours.states[:, 6:12]).max() > 0.1          # it moved


def test_a_panda_reproduction_with_its_null_space_pull_matches_pinocchios_aba():
    skill = SKILLS["panda-conveyor"]
    theta = skill.theta + 0.1 * np.random.default_rng(2).standard_normal(skill.theta.shape)
    ours = skill.reproduce(theta, duration=2.0)
    assert not ours.diverged and skill.plant.null_gain > 0
    reference = pinocchio_reference.PinocchioArm(skill.plant).rollout(theta, skill.start, 2.0)
    assert np.abs(ours.states - reference).max() < TOLERANCE
    assert np.abs(ours.states[:, 7:14]).max() > 0.1          # it moved


def test_gravity_from_the_composite_bodies_equals_the_newton_euler_gravity():
    chain = SerialChain.from_description(parse_urdf(EVERY_JOINT, "tool"))
    model = chain.model
    n = chain.n_joints
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    cm, ch, cJ, M, out = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.empty(n)
    for q, *_ in samples(chain, 20, seed=3):
        dyn.local_frames(model, q, local_R, local_p)
        dyn.world_frames(local_R, local_p, world_R, world_p)
        dyn.crba(model, local_R, local_p, cm, ch, cJ, M)
        dyn.gravity_from_composites(model, world_R, cm, ch, out)
        assert np.abs(out - chain.gravity_torque(q)).max() < 1e-12


def test_the_shipped_urdfs_are_example_robot_datas_without_meshes():
    for name in SHIPPED:
        try:
            original = urdf.example_robot_data_urdf(name)
        except (ModuleNotFoundError, FileNotFoundError):
            pytest.skip("example-robot-data is not installed")
        shipped = load_shipped(name)
        theirs = read_urdf(original, shipped["tip"], shipped["locked"])
        assert {k: v for k, v in shipped.items() if k != "source"} == {k: v for k, v in theirs.items() if k != "source"}
        assert "<mesh" not in Path(shipped["source"]).read_text()   # no reference to a file not shipped
