"""The URDF loader: what it reads, and each kind of file it refuses, named with the file, the element
and what was expected."""

import pytest

from mt_widgets.robot_models.urdf import SHIPPED, URDFError, load_shipped, parse_urdf, read_urdf, shipped_urdf

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


def test_the_ur5_runs_from_the_root_through_six_revolute_joints_to_tool0():
    chain = load_shipped("ur5")
    movable = [joint["name"] for joint in chain["joints"] if joint["type"] == "revolute"]
    assert movable == ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                       "wrist_3_joint"]
    assert chain["joints"][len(movable) + 1]["child"] == "tool0"
    masses = {inertial["link"]: inertial["mass"] for inertial in chain["inertials"]}
    assert masses["upper_arm_link"] == 8.393 and masses["tool0"] == 0.0


def test_every_shipped_arm_loads_with_its_tool_and_locked_gripper():
    for name, (_, tool, locked) in SHIPPED.items():
        chain = load_shipped(name)
        assert chain["tip"] == tool and chain["locked"] == locked
        assert shipped_urdf(name).is_file() and chain["source"] == str(shipped_urdf(name))
    panda = load_shipped("panda")
    assert [j["name"] for j in panda["joints"] if j["type"] == "revolute"] == [f"panda_joint{i}" for i in range(1, 8)]
    so101 = load_shipped("so101")
    assert [j["name"] for j in so101["joints"] if j["type"] == "revolute"] == [
        "shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll"]
    gripper = next(j for j in so101["joints"] if j["name"] == "gripper")
    assert gripper["type"] == "fixed"   # locked: held at zero, welded to the wrist


def test_a_prismatic_joint_is_read_and_a_moving_branch_is_refused_by_name():
    chain = parse_urdf(URDF.format(kind="prismatic").replace(
        '<joint name="j3" type="revolute"', '<joint name="j3" type="fixed"'), "c")
    assert [j["type"] for j in chain["joints"]][:2] == ["revolute", "prismatic"]
    with pytest.raises(URDFError, match=r"urdf: <joint name='j3'> \(revolute\) branches off the chain to 'c'.*locked"):
        parse_urdf(URDF.format(kind="revolute"), "c")
    assert [j["type"] for j in parse_urdf(URDF.format(kind="revolute"), "c", locked=("j3",))["joints"]] == [
        "revolute", "revolute", "fixed"]


def test_a_tree_with_two_tool_candidates_is_refused_unless_the_tool_is_named():
    with pytest.raises(URDFError, match=r"a tree with 2 tool candidates \(c, d, each after 2 movable joints\).*tool="):
        parse_urdf(URDF.format(kind="revolute"))
    assert parse_urdf(URDF.format(kind="revolute").replace('type="revolute"><parent link="b"/><child link="d"/>',
                                                           'type="fixed"><parent link="b"/><child link="d"/>'))[
        "tip"] == "c"


@pytest.mark.parametrize("text, message", [
    ("<robot><link name='a'", r"toy.urdf: does not parse as XML .*; expected a URDF"),
    ("<model/>", r"toy.urdf: expected a <robot> root element, got <model>"),
    (URDF.format(kind="floating"), r"toy.urdf: <joint name='j2'>: a floating joint \(a floating base\)"),
    (URDF.format(kind="planar"), r"toy.urdf: <joint name='j2'>: a planar joint \(a floating base\)"),
    (URDF.format(kind="screw"), r"toy.urdf: <joint name='j2'>: expected a type among revolute, continuous, "
                                r"prismatic, fixed, got 'screw'"),
    (URDF.format(kind="fixed").replace('<child link="d"/>', '<child link="c"/>'),
     r"toy.urdf: <link name='c'> is the child of two joints \('j2', 'j3'\): a closed loop"),
    (URDF.format(kind="fixed").replace('<parent link="a"/><child link="b"/>', '<parent link="d"/><child link="b"/>')
     .replace('<link name="a"/>', ""), r"toy.urdf: every link is some joint's child: a closed loop"),
    (URDF.format(kind="revolute").replace('<limit effort="1" lower="-1" upper="1" velocity="1"/></joint>\n  '
                                          '<joint name="j3"', '</joint>\n  <joint name="j3"'),
     r"toy.urdf: <joint name='j2'>: expected a <limit>"),
    (URDF.format(kind="fixed").replace('<axis xyz="0 0 1"/>', '<axis xyz="0 zero 1"/>', 1),
     r"toy.urdf: <joint name='j1'> <axis xyz>: expected 3 finite numbers, got '0 zero 1'"),
    (URDF.format(kind="fixed").replace("<mass value=\"1\"/>", ""),
     r"toy.urdf: <link name='b'> <inertial>: expected a <mass> and an <inertia>, got no <mass>"),
])
def test_bad_files_are_refused_naming_the_file_the_element_and_the_expectation(tmp_path, text, message):
    path = tmp_path / "toy.urdf"
    path.write_text(text)
    with pytest.raises(URDFError, match=message.replace("toy.urdf", ".*toy.urdf")):
        read_urdf(path, "c")


def test_a_tool_not_in_the_chain_and_bad_arguments_are_refused_by_name(tmp_path):
    fixed = URDF.format(kind="fixed").replace('type="revolute"><parent link="b"/><child link="d"/>',
                                              'type="fixed"><parent link="b"/><child link="d"/>')
    with pytest.raises(URDFError, match=r"urdf: tool: expected a link reached by a joint from the root 'a', got "
                                        r"'nowhere' \(not a link of the file\)"):
        parse_urdf(fixed, "nowhere")
    with pytest.raises(URDFError, match=r"got 'a' \(the root link\)"):
        parse_urdf(fixed, "a")
    with pytest.raises(URDFError, match=r"locked: joint 'j1' is on the chain to 'c'"):
        parse_urdf(fixed, "c", locked=("j1",))
    with pytest.raises(URDFError, match=r"locked: expected joints of the file, got 'j9'"):
        parse_urdf(fixed, "c", locked=("j9",))
    with pytest.raises(FileNotFoundError, match=r"path: expected a URDF file, got '.*missing.urdf' \(no such file\)"):
        read_urdf(tmp_path / "missing.urdf")
    with pytest.raises(TypeError, match="path: expected a str or pathlib.Path"):
        read_urdf(3)
    with pytest.raises(ValueError, match=r"robot: expected one of \['panda', 'so101', 'ur5'\], got 'kuka'"):
        shipped_urdf("kuka")
