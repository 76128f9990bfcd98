"""The UR5's data in core is exactly what its URDF says, regenerated here from the file itself."""

from pathlib import Path

import pytest

from mt_widgets.robot_models.urdf import description_module, example_robot_data_urdf, generate, read_serial_chain

pytest.importorskip("pinocchio")  # the test extra: example-robot-data comes with it

SHIPPED = Path(__file__).resolve().parents[2] / "mt_widgets" / "core" / "ur5_description.py"


def test_the_shipped_ur5_description_is_the_urdf_regenerated():
    assert SHIPPED.read_text(encoding="utf-8") == generate("ur5")


def test_the_chain_runs_from_the_root_through_six_revolute_joints_to_tool0():
    chain = read_serial_chain(example_robot_data_urdf("ur5").read_text(encoding="utf-8"), "tool0")
    movable = [joint["name"] for joint in chain["joints"] if joint["type"] == "revolute"]
    assert movable == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                       "wrist_3_joint"]
    assert chain["joints"][len(movable) + 1]["child"] == "tool0"
    masses = {inertial["link"]: inertial["mass"] for inertial in chain["inertials"]}
    assert masses["upper_arm_link"] == 8.393 and masses["tool0"] == 0.0


URDF = """<robot name="toy">
  <link name="a"/><link name="b"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0"
  izz="1"/></inertial></link><link name="c"/><link name="d"/>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit effort="1" lower="-1" upper="1" velocity="1"/></joint>
  <joint name="j2" type="{kind}"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/>
    <limit effort="1" lower="-1" upper="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="d"/><axis xyz="0 0 1"/>
    <limit effort="1" lower="-1" upper="1" velocity="1"/></joint>
</robot>"""


def test_a_prismatic_joint_or_a_moving_branch_is_refused_by_name():
    with pytest.raises(ValueError, match="'j2' is prismatic"):
        read_serial_chain(URDF.format(kind="prismatic"), "c")
    with pytest.raises(ValueError, match="'j3' .*branches off"):
        read_serial_chain(URDF.format(kind="revolute"), "c")
    with pytest.raises(ValueError, match="tip: .*'nowhere'"):
        read_serial_chain(URDF.format(kind="fixed"), "nowhere")


def test_the_module_holds_every_number_exactly():
    chain = read_serial_chain(URDF.format(kind="fixed").replace('<link name="d"/>', "").replace(
        '<joint name="j3" type="revolute"><parent link="b"/><child link="d"/><axis xyz="0 0 1"/>\n    '
        '<limit effort="1" lower="-1" upper="1" velocity="1"/></joint>', ""), "c")
    namespace = {}
    exec(description_module(chain, "a test"), namespace)
    assert namespace["JOINTS"] == tuple(chain["joints"]) and namespace["INERTIALS"] == tuple(chain["inertials"])
