"""Reading a robot's URDF into the plain data ``mt_widgets.core`` builds a serial chain from.

``core`` does no file I/O, so a robot model reaches it as data: this module reads a URDF (the
source of truth: kinematics, inertias, limits) with the standard library's XML parser and keeps
what a serial chain from the root link to one tool frame needs. It imports nothing of the
package and core imports nothing of it: ``mt_widgets.arms`` hands what it reads to core
(tests/test_architecture.py).

Understood joints: revolute, continuous (a revolute joint without a range), prismatic and fixed.
A joint that moves but is not on the path root -> tool (a gripper's finger) is refused unless it
is named in ``locked``: then it is held at zero, its links welded to the body it hangs from (as
pinocchio's ``buildReducedModel`` does). Refused, with the file, the element and what was
expected: a file that does not parse, a floating or planar joint (a floating base), an unknown
joint type, a link that is the child of two joints (a closed loop), no root, two roots, a tool
frame not in the tree, two tool candidates when no tool is named.

The suite's own URDFs (``SHIPPED``) are package data in ``urdf_files/``; a user passes a path.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from importlib.metadata import PackageNotFoundError, distribution
from importlib.resources import files
from pathlib import Path

#: The arms the suite ships, by robot name: (file in urdf_files/, tool frame, joints held locked).
SHIPPED = {
    "ur5": ("ur5.urdf", "tool0", ()),
    "panda": ("panda.urdf", "panda_hand_tcp", ("panda_finger_joint1", "panda_finger_joint2")),
    "so101": ("so101.urdf", "gripper_frame_link", ("gripper",)),
}

#: Where each shipped file came from in example-robot-data (the tests compare the two).
EXAMPLE_ROBOT_DATA = {
    "ur5": ("robots/ur_description/urdf/ur5_robot.urdf", "tool0"),
    "panda": ("robots/panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "so101": ("robots/so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
}

MOVABLE = ("revolute", "continuous", "prismatic")
SUPPORTED = MOVABLE + ("fixed",)


class URDFError(ValueError):
    """A URDF the loader cannot make a serial arm of; the message names the file and the element."""


def shipped_urdf(robot: str) -> Path:
    """The path of a shipped arm's URDF (package data). robot: a key of ``SHIPPED``."""
    if robot not in SHIPPED:
        raise ValueError(f"robot: expected one of {sorted(SHIPPED)}, got {robot!r}")
    return Path(str(files(__package__).joinpath("urdf_files", SHIPPED[robot][0])))


def load_shipped(robot: str) -> dict:
    """A shipped arm's description (``read_urdf`` of its file with its tool frame and locked joints)."""
    path = shipped_urdf(robot)
    _, tool, locked = SHIPPED[robot]
    return read_urdf(path, tool, locked)


def example_robot_data_urdf(robot: str) -> Path:
    """The path of a robot's URDF in the installed example-robot-data (the ``test`` extra).

    Args:
        robot: a key of ``EXAMPLE_ROBOT_DATA``.
    """
    if robot not in EXAMPLE_ROBOT_DATA:
        raise ValueError(f"robot: expected one of {sorted(EXAMPLE_ROBOT_DATA)}, got {robot!r}")
    return example_robot_data_file(EXAMPLE_ROBOT_DATA[robot][0])


def example_robot_data_file(relative: str) -> Path:
    """A file of the installed example-robot-data by its path under share/example-robot-data."""
    try:
        package = distribution("example-robot-data")
    except PackageNotFoundError as error:
        raise ModuleNotFoundError("example-robot-data is not installed: pip install 'mt-widgets[test]' "
                                  "(or pip install example-robot-data)") from error
    # The wheel (a cmeel package) puts its share/ folder under site-packages/cmeel.prefix.
    path = Path(str(package.locate_file(f"cmeel.prefix/share/example-robot-data/{relative}")))
    if not path.is_file():
        raise FileNotFoundError(f"example-robot-data {package.version} has no {relative}")
    return path


def read_urdf(path, tool: str | None = None, locked=()) -> dict:
    """Reads the URDF file at ``path`` into a serial chain's description (see ``parse_urdf``).

    Args:
        path: a str or ``pathlib.Path`` of a URDF file.
        tool: the link or frame whose origin is the tool point; None picks the one leaf link
            that ends the longest run of movable joints (refused when two do).
        locked: names of movable joints off the chain to hold at zero (a gripper's).
    """
    if not isinstance(path, (str, Path)):
        raise TypeError(f"path: expected a str or pathlib.Path of a URDF file, got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"path: expected a URDF file, got {str(path)!r} (no such file)")
    return parse_urdf(path.read_text(encoding="utf-8"), tool, locked, source=str(path))


def _numbers(source: str, where: str, text: str | None, count: int, default: str) -> tuple[float, ...]:
    try:
        values = tuple(float(item) for item in (text if text is not None else default).split())
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise URDFError(f"{source}: {where}: expected {count} finite numbers, got {text!r}")
    return values


def _number(source: str, where: str, element, key: str, default: float | None = None) -> float:
    text = element.get(key) if element is not None else None
    if text is None:
        if default is None:
            raise URDFError(f"{source}: {where}: expected an attribute {key}=\"...\", got none")
        return default
    try:
        return float(text)
    except ValueError:
        raise URDFError(f"{source}: {where}: expected a number for {key}, got {text!r}") from None


def _joint(source: str, element) -> dict:
    name = element.get("name")
    kind = element.get("type")
    where = f"<joint name={name!r}>"
    if kind in ("floating", "planar"):
        raise URDFError(f"{source}: {where}: a {kind} joint (a floating base) is not a serial arm; expected "
                        f"one of {', '.join(SUPPORTED)}")
    if kind not in SUPPORTED:
        raise URDFError(f"{source}: {where}: expected a type among {', '.join(SUPPORTED)}, got {kind!r}")
    links = {}
    for tag in ("parent", "child"):
        found = element.find(tag)
        if found is None or not found.get("link"):
            raise URDFError(f"{source}: {where}: expected a <{tag} link=\"...\"/>, got none")
        links[tag] = found.get("link")
    origin, axis, limit = element.find("origin"), element.find("axis"), element.find("limit")
    joint = {
        "name": name,
        "type": kind,
        "parent": links["parent"],
        "child": links["child"],
        "xyz": _numbers(source, f"{where} <origin xyz>", origin.get("xyz") if origin is not None else None, 3,
                        "0 0 0"),
        "rpy": _numbers(source, f"{where} <origin rpy>", origin.get("rpy") if origin is not None else None, 3,
                        "0 0 0"),
        "axis": _numbers(source, f"{where} <axis xyz>", axis.get("xyz") if axis is not None else None, 3, "1 0 0"),
    }
    if kind in ("revolute", "prismatic"):
        if limit is None:
            raise URDFError(f"{source}: {where}: expected a <limit> (a {kind} joint needs lower, upper, velocity "
                            f"and effort), got none")
        joint.update(lower=_number(source, f"{where} <limit>", limit, "lower", 0.0),
                     upper=_number(source, f"{where} <limit>", limit, "upper", 0.0),
                     velocity=_number(source, f"{where} <limit>", limit, "velocity"),
                     effort=_number(source, f"{where} <limit>", limit, "effort"))
    elif kind == "continuous":
        joint.update(lower=-math.inf, upper=math.inf,
                     velocity=_number(source, f"{where} <limit>", limit, "velocity", math.inf),
                     effort=_number(source, f"{where} <limit>", limit, "effort", math.inf))
    if kind in MOVABLE and not any(joint["axis"]):
        raise URDFError(f"{source}: {where} <axis xyz>: expected a non-zero axis, got {joint['axis']}")
    return joint


def _inertial(source: str, element):
    inertial = element.find("inertial")
    if inertial is None:
        return None
    where = f"<link name={element.get('name')!r}> <inertial>"
    origin, inertia, mass = inertial.find("origin"), inertial.find("inertia"), inertial.find("mass")
    if mass is None or inertia is None:
        raise URDFError(f"{source}: {where}: expected a <mass> and an <inertia>, got "
                        f"{'no <mass>' if mass is None else 'no <inertia>'}")
    return {
        "link": element.get("name"),
        "mass": _number(source, f"{where} <mass>", mass, "value"),
        "xyz": _numbers(source, f"{where} <origin xyz>", origin.get("xyz") if origin is not None else None, 3,
                        "0 0 0"),
        "rpy": _numbers(source, f"{where} <origin rpy>", origin.get("rpy") if origin is not None else None, 3,
                        "0 0 0"),
        "inertia": tuple(_number(source, f"{where} <inertia>", inertia, key)
                         for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")),
    }


def parse_urdf(urdf_text: str, tool: str | None = None, locked=(), source: str = "urdf") -> dict:
    """The chain from the URDF's root link to the frame ``tool``, as plain data.

    Returns a dict with:

    - ``robot``: the URDF's robot name; ``source``: where it came from (for messages);
    - ``joints``: the joints on the path root -> tool, in order, then every joint hanging off a
      link of that path (fixed, or locked and so given as fixed), breadth first, each a dict of
      name, type, parent, child, xyz, rpy, axis and (movable joints) the limits lower, upper,
      velocity, effort;
    - ``inertials``: per link with an ``<inertial>``: mass, xyz, rpy and the inertia
      (ixx, ixy, ixz, iyy, iyz, izz) about the centre of mass in the inertial frame;
    - ``tip``: the tool frame's name; ``locked``: the joints held at zero.
    """
    if not isinstance(urdf_text, str):
        raise TypeError(f"urdf_text: expected the URDF's text as a str, got {type(urdf_text).__name__}")
    locked = tuple(locked)
    if not all(isinstance(name, str) for name in locked):
        raise TypeError(f"locked: expected joint names (str), got {locked!r}")
    try:
        root_element = ElementTree.fromstring(urdf_text)
    except ElementTree.ParseError as error:
        raise URDFError(f"{source}: does not parse as XML ({error}); expected a URDF") from None
    if root_element.tag != "robot":
        raise URDFError(f"{source}: expected a <robot> root element, got <{root_element.tag}>")
    links = [element.get("name") for element in root_element.findall("link")]
    joints = {}
    for element in root_element.findall("joint"):
        joint = _joint(source, element)
        if joint["child"] in joints:
            raise URDFError(f"{source}: <link name={joint['child']!r}> is the child of two joints "
                            f"({joints[joint['child']]['name']!r}, {joint['name']!r}): a closed loop; expected a tree")
        for end in ("parent", "child"):
            if joint[end] not in links:
                raise URDFError(f"{source}: <joint name={joint['name']!r}>: expected a {end} link of the file, got "
                                f"{joint[end]!r}")
        joints[joint["child"]] = joint
    inertials = [inertial for element in root_element.findall("link")
                 if (inertial := _inertial(source, element)) is not None]
    roots = [link for link in links if link not in joints]
    if not roots:
        raise URDFError(f"{source}: every link is some joint's child: a closed loop; expected one root link")
    if len(roots) != 1:
        raise URDFError(f"{source}: expected one root link, got {roots}")
    root = roots[0]

    def path_to(link):
        path = []
        while link in joints:
            path.append(joints[link])
            link = joints[link]["parent"]
        return path[::-1]

    if tool is None:
        parents = {joint["parent"] for joint in joints.values()}
        leaves = [link for link in links if link not in parents and link != root]
        movable = {leaf: sum(joint["type"] in MOVABLE for joint in path_to(leaf)) for leaf in leaves}
        most = max(movable.values(), default=0)
        candidates = [leaf for leaf in leaves if movable[leaf] == most]
        if most == 0:
            raise URDFError(f"{source}: expected a movable joint between the root and a leaf link, got none")
        if len(candidates) != 1:
            raise URDFError(f"{source}: a tree with {len(candidates)} tool candidates ({', '.join(candidates)}, each "
                            f"after {most} movable joints); expected one: name the tool frame (tool=...)")
        tool = candidates[0]
    if not isinstance(tool, str):
        raise TypeError(f"tool: expected a link name (str) or None, got {type(tool).__name__}")
    if tool not in joints:
        where = "the root link" if tool == root else "not a link of the file"
        raise URDFError(f"{source}: tool: expected a link reached by a joint from the root {root!r}, got {tool!r} "
                        f"({where})")
    path = path_to(tool)
    if not any(joint["type"] in MOVABLE for joint in path):
        raise URDFError(f"{source}: tool: expected a movable joint between the root and {tool!r}, got only fixed "
                        f"joints")
    on_path = {root} | {joint["child"] for joint in path}
    path_names = {joint["name"] for joint in path}
    for name in locked:
        if name in path_names:
            raise URDFError(f"{source}: locked: joint {name!r} is on the chain to {tool!r}; expected joints off it")
        if name not in {joint["name"] for joint in joints.values()}:
            raise URDFError(f"{source}: locked: expected joints of the file, got {name!r}")
    branches = []
    # Breadth first from the root, in the URDF's order: the same file always gives the same list.
    frontier = [root] + [joint["child"] for joint in path]
    while frontier:
        parent = frontier.pop(0)
        for joint in joints.values():
            if joint["parent"] == parent and joint["child"] not in on_path and joint not in branches:
                if joint["type"] != "fixed":
                    if joint["name"] not in locked:
                        raise URDFError(f"{source}: <joint name={joint['name']!r}> ({joint['type']}) branches off "
                                        f"the chain to {tool!r}: not a serial chain; expected it fixed, or named in "
                                        f"locked=(...) to hold it at zero (a gripper's joint)")
                    joint = {key: joint[key] for key in ("name", "parent", "child", "xyz", "rpy", "axis")} | {
                        "type": "fixed"}
                branches.append(joint)
                frontier.append(joint["child"])
    return {"robot": root_element.get("name"), "source": source, "joints": path + branches,
            "inertials": inertials, "tip": tool, "locked": locked}

