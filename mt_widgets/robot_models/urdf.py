"""Reading a robot's URDF into the plain data ``mt_widgets.core`` builds a serial chain from.

``core`` does no I/O, so a robot model reaches it as data: this module reads the URDF (the
source of truth: kinematics, inertias, limits), keeps what a serial chain from the root to one
tip frame needs, and writes it as a Python module of literals (``mt_widgets/core/ur5_description.py``
for the UR5). ``tests/robot_models/test_urdf.py`` regenerates that module from the URDF that
example-robot-data ships and checks it is identical, so the shipped numbers never drift from
the file and are never typed by hand.

Regenerate with ``python -m mt_widgets.robot_models.urdf ur5 --write`` (the module is generated
first, then written: importing this package imports ``core``, which imports the old module).
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ElementTree
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

#: The URDFs of example-robot-data this suite uses, by robot name: (file, tip frame).
EXAMPLE_ROBOT_DATA = {
    "ur5": ("robots/ur_description/urdf/ur5_robot.urdf", "tool0"),
}


def example_robot_data_urdf(robot: str) -> Path:
    """The path of a robot's URDF in the installed example-robot-data (the ``test`` extra).

    Args:
        robot: a key of ``EXAMPLE_ROBOT_DATA`` ("ur5").
    """
    if robot not in EXAMPLE_ROBOT_DATA:
        raise ValueError(f"robot: expected one of {sorted(EXAMPLE_ROBOT_DATA)}, got {robot!r}")
    try:
        package = distribution("example-robot-data")
    except PackageNotFoundError as error:
        raise ModuleNotFoundError("example-robot-data is not installed: pip install 'mt-widgets[test]' "
                                  "(or pip install example-robot-data)") from error
    # The wheel (a cmeel package) puts its share/ folder under site-packages/cmeel.prefix.
    path = Path(str(package.locate_file(f"cmeel.prefix/share/example-robot-data/{EXAMPLE_ROBOT_DATA[robot][0]}")))
    if not path.is_file():
        raise FileNotFoundError(f"robot: example-robot-data {package.version} has no {EXAMPLE_ROBOT_DATA[robot][0]}")
    return path


def _numbers(text: str | None, count: int, default: str) -> tuple[float, ...]:
    values = tuple(float(item) for item in (text if text is not None else default).split())
    if len(values) != count:
        raise ValueError(f"urdf: expected {count} numbers, got {text!r}")
    return values


def read_serial_chain(urdf_text: str, tip: str) -> dict:
    """The chain from the URDF's root link to the frame ``tip``, as plain data.

    Returns a dict with:

    - ``robot``: the URDF's robot name;
    - ``joints``: the joints on the path root -> tip, in order, plus every fixed joint hanging
      off a link of that path (their links' inertias ride with the body they are welded to),
      each a dict of name, type, parent, child, xyz, rpy, axis and (movable joints) the
      limits lower, upper, velocity, effort;
    - ``inertials``: per link with an ``<inertial>``: mass, xyz, rpy and the inertia
      (ixx, ixy, ixz, iyy, iyz, izz) about the centre of mass in the inertial frame;
    - ``tip``: the tip frame's name.

    Raises ValueError when the path holds a joint that is neither revolute nor fixed, or a
    movable joint branches off it (not a serial chain).
    """
    root_element = ElementTree.fromstring(urdf_text)
    joints = {}
    for element in root_element.findall("joint"):
        origin = element.find("origin")
        axis = element.find("axis")
        limit = element.find("limit")
        joint = {
            "name": element.get("name"),
            "type": element.get("type"),
            "parent": element.find("parent").get("link"),
            "child": element.find("child").get("link"),
            "xyz": _numbers(origin.get("xyz") if origin is not None else None, 3, "0 0 0"),
            "rpy": _numbers(origin.get("rpy") if origin is not None else None, 3, "0 0 0"),
            "axis": _numbers(axis.get("xyz") if axis is not None else None, 3, "1 0 0"),
        }
        if joint["type"] in ("revolute", "prismatic"):
            joint.update(lower=float(limit.get("lower")), upper=float(limit.get("upper")),
                         velocity=float(limit.get("velocity")), effort=float(limit.get("effort")))
        joints[joint["child"]] = joint
    links = [element.get("name") for element in root_element.findall("link")]
    roots = [link for link in links if link not in joints]
    if len(roots) != 1:
        raise ValueError(f"urdf: expected one root link, got {roots}")
    if tip not in joints:
        raise ValueError(f"tip: expected a link of the URDF other than its root, got {tip!r}")
    path = []
    link = tip
    while link in joints:
        path.append(joints[link])
        link = joints[link]["parent"]
    path.reverse()
    for joint in path:
        if joint["type"] not in ("revolute", "fixed"):
            raise ValueError(f"urdf: joint {joint['name']!r} is {joint['type']}; only revolute and fixed joints "
                             f"are supported on the chain")
    on_path = {roots[0]} | {joint["child"] for joint in path}
    branches = []
    # Breadth first from the root, in the URDF's order: the same file always gives the same list.
    frontier = [roots[0]] + [joint["child"] for joint in path]
    while frontier:
        parent = frontier.pop(0)
        for joint in joints.values():
            if joint["parent"] == parent and joint["child"] not in on_path and joint not in branches:
                if joint["type"] != "fixed":
                    raise ValueError(f"urdf: joint {joint['name']!r} ({joint['type']}) branches off the chain "
                                     f"to {tip!r}: not a serial chain")
                branches.append(joint)
                frontier.append(joint["child"])
    inertials = []
    for element in root_element.findall("link"):
        inertial = element.find("inertial")
        if inertial is None:
            continue
        origin = inertial.find("origin")
        inertia = inertial.find("inertia")
        inertials.append({
            "link": element.get("name"),
            "mass": float(inertial.find("mass").get("value")),
            "xyz": _numbers(origin.get("xyz") if origin is not None else None, 3, "0 0 0"),
            "rpy": _numbers(origin.get("rpy") if origin is not None else None, 3, "0 0 0"),
            "inertia": tuple(float(inertia.get(key)) for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")),
        })
    return {"robot": root_element.get("name"), "joints": path + branches, "inertials": inertials, "tip": tip}


def _literal(record: dict) -> list[str]:
    return ["    {"] + [f"        {key!r}: {value!r}," for key, value in record.items()] + ["    },"]


def description_module(chain: dict, source: str) -> str:
    """Python source of a module holding ``chain`` (from ``read_serial_chain``) as literals.

    Floats are written with ``repr``, which reads back to the same double: the module holds
    exactly the URDF's numbers.
    """
    lines = [
        f'"""The {chain["robot"]} as data: its serial chain to ``{chain["tip"]}``, read from its URDF.',
        "",
        "Generated by mt_widgets.robot_models.urdf (do not edit) from",
        f"{source}.",
        "tests/robot_models/test_urdf.py regenerates it from that file and checks it is identical.",
        '"""',
        "",
        f"ROBOT = {chain['robot']!r}",
        f"TIP = {chain['tip']!r}",
        f"SOURCE = {source!r}",
        "",
        "#: The joints from the root to the tip, then the fixed joints hanging off the chain.",
        "JOINTS = (",
    ]
    for joint in chain["joints"]:
        lines += _literal(joint)
    lines += [")", "", "#: Each link's mass, centre of mass (xyz, rpy) and inertia (ixx, ixy, ixz, iyy, iyz, izz).",
              "INERTIALS = ("]
    for inertial in chain["inertials"]:
        lines += _literal(inertial)
    lines += [")", ""]
    return "\n".join(lines)


def generate(robot: str) -> str:
    """The description module's source for a robot of ``EXAMPLE_ROBOT_DATA``, from the installed URDF."""
    path = example_robot_data_urdf(robot)
    version = distribution("example-robot-data").version
    chain = read_serial_chain(path.read_text(encoding="utf-8"), EXAMPLE_ROBOT_DATA[robot][1])
    return description_module(chain, f"example-robot-data {version}: {EXAMPLE_ROBOT_DATA[robot][0]}")


#: Where each robot's description module lives in the source tree.
DESCRIPTION_MODULES = {"ur5": Path(__file__).resolve().parents[1] / "core" / "ur5_description.py"}


if __name__ == "__main__":
    name = next((arg for arg in sys.argv[1:] if not arg.startswith("--")), "ur5")
    source = generate(name)
    if "--write" in sys.argv[1:]:
        DESCRIPTION_MODULES[name].write_text(source, encoding="utf-8")
    else:
        sys.stdout.write(source)
