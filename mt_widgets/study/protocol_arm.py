"""A protocol's ``[arm]`` table: the arm the study teaches, a shipped one by name or a URDF file beside it.

Two forms::

    [arm]                                 # a shipped arm: every phase (and a practice that runs)
    robot = "panda"                       # teaches one of its skills ("panda-reach", ...)

    [arm]                                 # a lab's own arm, from its URDF
    urdf = "my_arm.urdf"                  # relative to the protocol file
    tool = "flange"                       # the link whose origin is the tool point
    name = "mine"                         # the skills' prefix: "mine-reach", "mine-place"
    label = "My arm"                      # optional: the arm's name in the skills' titles
    home = [0.0, 0.3, 1.2]                # rad (m for a prismatic joint): where inverse kinematics starts
    teaching_box = [[0.25, 0.40], [-0.15, 0.15], [0.05, 0.25]]   # m: where query states put the tool
    part = [0.32, -0.08, 0.08]            # m: the reach skill's goal
    fixture = [0.30, 0.10, 0.10]          # m: the place skill's goal
    kinematic = false                     # optional: position servos (true) or torque drives (false)
    locked = []                           # optional: joints off the chain held at zero (a gripper's)
    lift = 0.1                            # optional: how far above the part the place skill starts (m)
    link_radius = 0.02                    # optional: the links' capsule radius (m)
    max_condition = 60.0                  # optional: the query-state sampler's threshold
    min_singular_value = 0.05             # optional: query states away from singular poses (m/rad)
    query_margin = 0.1                    # optional: query states this far inside each joint's range (rad/m)
    scene_box = [[...], [...], [...]]     # optional: what the views frame (m)
    [arm.conveyor]                        # optional: a belt, for "<name>-conveyor"
    origin = [0.3, -0.2, 0.08]
    direction = [0.0, 1.0, 0.0]
    speed = 0.05
    phase_range = [0.0, 0.3]

The URDF's skills join the protocol's skills (``mt_widgets.arms.urdf_arm.arm_skills`` builds them);
every phase, and the practice unless it lasts 0 s, must teach a skill of the named arm. The stored
protocol (``study.json``) keeps the URDF's text as ``urdf_text`` beside the file name as written, so
the protocol's hash covers the arm and a study folder rebuilds it without the file.

Errors name the protocol file, the field and, for the URDF itself, the URDF file and its element:
a missing file, a URDF that is not a serial arm, a tool frame not in it, a part, fixture or
teaching box the arm cannot reach.
"""

from __future__ import annotations

from pathlib import Path

from mt_widgets.arms import SHIPPED_ARMS
from mt_widgets.arms.urdf_arm import arm_skills
from mt_widgets.core import Skill
from mt_widgets.core.chain_plant import Conveyor
from mt_widgets.robot_models.urdf import URDFError, parse_urdf

_URDF_FIELDS = ("urdf", "urdf_text", "tool", "name", "label", "home", "teaching_box", "part", "fixture", "kinematic",
                "locked", "lift", "link_radius", "max_condition", "min_singular_value", "query_margin", "scene_box",
                "conveyor")
_CONVEYOR_FIELDS = ("origin", "direction", "speed", "phase_range")


def resolve_protocol_arm(raw: dict, check, source: str, skills: dict) -> tuple[str | None, dict | None]:
    """Reads ``[arm]``: adds a URDF arm's skills to ``skills`` (name -> Skill, in place).

    Returns:
        (the arm's robot name, the ``[arm]`` table as stored), or (None, None) without one.
    """
    if "arm" not in raw:
        return None, None
    table = check.get(raw, ("arm",), "table")
    if ("robot" in table) == ("urdf" in table):
        check.fail(("arm",), f"expected either robot = (a shipped arm: {', '.join(a.robot for a in SHIPPED_ARMS)}) "
                             f"or urdf = (a URDF file beside the protocol), got {sorted(table) or 'neither'}")
    if "robot" in table:
        check.unknown(table, ("arm",), ("robot",))
        robot = check.get(table, ("arm", "robot"), "text", choices=tuple(arm.robot for arm in SHIPPED_ARMS))
        return robot, dict(table)
    check.unknown(table, ("arm",), _URDF_FIELDS)
    given = check.get(table, ("arm", "urdf"), "text", nonempty=True)
    tool = check.get(table, ("arm", "tool"), "text", nonempty=True)
    name = check.get(table, ("arm", "name"), "text", name=True, default="arm")
    label = check.get(table, ("arm", "label"), "text", nonempty=True, default=None)
    locked = table.get("locked", [])
    if not isinstance(locked, list) or not all(isinstance(joint, str) for joint in locked):
        check.fail(("arm", "locked"), f"expected a list of joint names, got {locked!r}"[:200])
    if "urdf_text" in table:  # the stored form (study.json): the file's text, read when the study was created
        text = check.get(table, ("arm", "urdf_text"), "text", nonempty=True)
        urdf = given
    else:
        base = Path(source).parent if source not in ("<string>", "") else Path.cwd()
        path = (base / given).resolve()
        if not path.is_file():
            check.fail(("arm", "urdf"), f"expected a URDF file (relative to {base}), got {given!r}: no file at {path}")
        text = path.read_text(encoding="utf-8")
        urdf = str(path)
    try:
        description = parse_urdf(text, tool, tuple(locked), source=urdf)
    except URDFError as error:
        # The reader's message names the URDF file and its element; the field is the protocol's.
        field = "tool" if f"{urdf}: tool:" in str(error) else "locked" if f"{urdf}: locked:" in str(error) else "urdf"
        check.fail(("arm", field), str(error))
    numbers = {key: _numbers(check, table, key) for key in ("home", "teaching_box", "part", "fixture", "scene_box")}
    options = {key: check.get(table, ("arm", key), "number", positive=True)
               for key in ("lift", "link_radius", "max_condition", "min_singular_value") if key in table}
    if "query_margin" in table:
        options["query_margin"] = check.get(table, ("arm", "query_margin"), "number", minimum=0.0)
    kinematic = table.get("kinematic", False)
    if not isinstance(kinematic, bool):
        check.fail(("arm", "kinematic"), f"expected true or false, got {kinematic!r}")
    conveyor = _conveyor(check, table)
    taken = [key for key in (f"{name}-reach", f"{name}-place", f"{name}-conveyor") if key in skills]
    if taken:
        check.fail(("arm", "name"), f"expected a name whose skills are not taken, got {name!r} ({taken[0]!r} is a "
                                    f"skill already)")
    try:
        made = arm_skills(description, name, numbers["home"], numbers["teaching_box"], numbers["part"],
                          numbers["fixture"], kinematic=kinematic, scene_box=numbers["scene_box"], conveyor=conveyor,
                          label=label, **options)
    except (ValueError, TypeError) as error:
        # arm_skills names its argument first ("part: expected ..."); a chain's own error names the URDF.
        field = str(error).split(":", 1)[0]
        field = field if field in _URDF_FIELDS else "kinematic" if "kinematic" in str(error) else "urdf"
        check.fail(("arm", field), str(error))
    skills.update(made)
    stored = {key: value for key, value in table.items() if key != "urdf_text"}
    stored["urdf_text"] = text
    return name, stored


def _numbers(check, table: dict, key: str):
    if key not in table:
        if key == "scene_box":
            return None
        check.fail(("arm", key), "missing required field (numbers)")
    value = table[key]

    def numeric(item):
        return (isinstance(item, (int, float)) and not isinstance(item, bool)) or (
            isinstance(item, list) and all(numeric(inner) for inner in item))

    if not isinstance(value, list) or not numeric(value):
        check.fail(("arm", key), f"expected a list of numbers, got {value!r}"[:200])
    return value


def _conveyor(check, table: dict) -> Conveyor | None:
    if "conveyor" not in table:
        return None
    belt = check.get(table, ("arm", "conveyor"), "table")
    check.unknown(belt, ("arm", "conveyor"), _CONVEYOR_FIELDS)
    for key in _CONVEYOR_FIELDS:
        if key not in belt:
            check.fail(("arm", "conveyor", key), "missing required field")
    try:
        return Conveyor(belt["origin"], belt["direction"], belt["speed"], belt["phase_range"])
    except (ValueError, TypeError) as error:
        check.fail(("arm", "conveyor"), str(error))


def check_arm_skills(check, robot: str, skills, practice, phases) -> None:
    """Every phase ((field path, ``Phase``) pairs), and a practice that runs, teaches a skill of the arm ``robot``."""
    for path, phase in phases:
        skill: Skill = skills[phase.skill]
        if skill.robot != robot:
            check.fail(path, f"phase {phase.id}: expected a skill of the protocol's arm {robot!r} "
                             f"([arm]), got {phase.skill!r} on {skill.robot!r}")
    if practice.duration_s > 0 and skills[practice.skill].robot != robot:
        check.fail(("practice", "skill"), f"expected a skill of the protocol's arm {robot!r} ([arm]) or a practice "
                                          f"of 0 s, got {practice.skill!r} on {skills[practice.skill].robot!r}")
