"""The arms the suite ships, read from their URDFs and built on core's chain engine, with their skills.

Core reads no file: this layer reads each arm's URDF (``mt_widgets/robot_models/urdf_files``, by
``mt_widgets.robot_models``), builds its ``ChainPlant`` with its home pose, teaching box and scene,
defines its production-line skills, and promises them to ``mt_widgets.core.SKILLS`` (``SHIPPED_ARMS``,
``promise_shipped_skills``): an arm is read and built the first time one of its skills is asked for,
so importing the package reads no URDF. ``mt_widgets/__init__.py`` imports this module, so every
``SKILLS`` a program reaches holds them. A user's own arm is built the same way
(docs/guide/your-own-arm.md, ``mt_widgets.arms.urdf_arm``).

- The Universal Robots UR5 (issue 31): six joints, torque-controlled, so a dynamic plant, mounted
  on a table top at z = ``table_height`` in the base frame; the production line's conveyor may run
  past it. State x = (q1..q6 rad, qd1..qd6 rad/s[, s m]). Query states are at rest, with the tool
  in the teaching box above the table, reached from the home pose by position-only inverse
  kinematics (so the wrist keeps the home pose's tool-down attitude as well as it can).
- The Franka Emika Panda: seven joints, torque-controlled, so a dynamic plant. The taught action
  is the tool's 3-D velocity, so four joint motions leave it unchanged: the controller takes the
  minimum-norm joint speeds plus a pull towards the home pose in the null space
  (``null_gain``; ``chain_rollout``'s docstring), which keeps the elbow up and the wrist near its
  home attitude over a reproduction instead of letting them drift. Tool point: ``panda_hand_tcp``
  (between the fingertips), the fingers locked at zero.
- The SO-101 (LeRobot's arm): five joints driven by Feetech STS3215 position servos, so a
  kinematic plant. A position-controlled servo takes a goal position and closes its own loop on
  it; the host never commands torque, and the links (about 0.1 kg each) are light enough that
  the servos track a smooth setpoint far faster than a taught motion changes. What the host
  commands is where the joints go, which is what a kinematic plant models: the joints follow the
  resolved-rate speeds exactly, limited to ``SO101_JOINT_SPEED`` (the URDF's 10 rad/s is a
  placeholder). Tool point: ``gripper_frame_link`` (between the jaws), the jaw locked at zero.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mt_widgets.core.chain_plant import ChainPlant, Conveyor
from mt_widgets.core.features import ConveyorFeatures, ToolFeatures
from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.core.skills import SKILLS, Skill, production_line_skills, production_line_titles
from mt_widgets.core.targets import ConveyorTarget, SpacePointTarget
from mt_widgets.core.workspace import Cuboid
from mt_widgets.robot_models.urdf import load_shipped

#: The UR5's home pose (rad): upper arm up, forearm level, tool pointing down at about
#: (0.49, 0.11, 0.43) m.
UR5_HOME = (0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0)

#: Where the tool is taught, in the base frame (m): in front of the arm, above the table.
UR5_TEACHING_BOX = Cuboid((0.30, 0.65), (-0.25, 0.45), (0.05, 0.45))

#: What every view of the UR5 frames (m): the arm at home and all it does over the teaching box.
UR5_SCENE = Cuboid((-0.25, 0.90), (-0.50, 0.70), (0.0, 0.85))

#: The Panda's home pose (rad): Franka's "ready" pose, the hand pointing down at about (0.31, 0, 0.49) m.
PANDA_HOME = (0.0, -np.pi / 4, 0.0, -3 * np.pi / 4, 0.0, np.pi / 2, np.pi / 4)

#: Where the Panda's tool is taught (m, base frame): in front of it, above the table.
PANDA_TEACHING_BOX = Cuboid((0.30, 0.60), (-0.25, 0.30), (0.08, 0.45))

#: What every view of the Panda frames (m).
PANDA_SCENE = Cuboid((-0.25, 0.85), (-0.50, 0.60), (0.0, 1.10))

#: The SO-101's home pose (rad): upper arm raised, forearm and wrist folded down, the jaws about
#: 20 cm in front of the base and 12 cm above the table.
SO101_HOME = (0.0, -0.9, 0.9, 1.2, 0.0)

#: Where the SO-101's tool is taught (m, base frame): a table-top region in front of it.
SO101_TEACHING_BOX = Cuboid((0.14, 0.28), (-0.12, 0.12), (0.03, 0.15))

#: What every view of the SO-101 frames (m).
SO101_SCENE = Cuboid((-0.08, 0.40), (-0.22, 0.22), (0.0, 0.36))

#: The SO-101's joint speed limit (rad/s) for teaching: about half the STS3215's no-load speed
#: (0.222 s per 60 degrees at 7.4 V, about 4.7 rad/s), so a servo under load still keeps up.
SO101_JOINT_SPEED = 2.0

#: How far inside the URDF's joint ranges the SO-101's query states stay (rad). The arm itself goes
#: only where its envelope allows (``mt_widgets.hardware.feetech.envelope``): the URDF's range
#: intersected with the range LeRobot calibrated, less a margin of 0.05 rad. This margin covers
#: that 0.05 rad and a calibrated range up to 0.1 rad (6 degrees) narrower than the URDF's at
#: either end, as a hand-calibrated real arm's may be, so a query state is one the arm will go to.
SO101_QUERY_MARGIN = 0.15


def ur5_chain() -> SerialChain:
    """The UR5's serial chain from its URDF (shipped with the package), tool point at ``tool0``."""
    return SerialChain.from_description(load_shipped("ur5"))


def panda_chain() -> SerialChain:
    """The Panda's chain from its shipped URDF to ``panda_hand_tcp``."""
    return SerialChain.from_description(load_shipped("panda"))


def so101_chain() -> SerialChain:
    """The SO-101's chain from its shipped URDF to ``gripper_frame_link``, joint speeds capped."""
    chain = SerialChain.from_description(load_shipped("so101"), dynamics=False)
    chain.velocity_limit = np.full(chain.n_joints, SO101_JOINT_SPEED)
    return chain


def panda_plant(conveyor: Conveyor | None = None) -> ChainPlant:
    """The Panda on a table, dynamic, with a null-space pull towards ``PANDA_HOME`` (2 per second)."""
    return ChainPlant(panda_chain(), PANDA_HOME, PANDA_TEACHING_BOX, PANDA_SCENE, robot="panda", conveyor=conveyor,
                      link_radius=0.04, first_table_point=3, collision_gap=4, velocity_gain=20.0, damping=0.01,
                      null_gain=2.0, min_singular_value=0.15, arrow_scale=0.5)


def so101_plant() -> ChainPlant:
    """The SO-101 on a table, kinematic (position servos), its tool taught in ``SO101_TEACHING_BOX``."""
    return ChainPlant(so101_chain(), SO101_HOME, SO101_TEACHING_BOX, SO101_SCENE, robot="so101", kinematic=True,
                      link_radius=0.015, first_table_point=3, collision_gap=3, damping=0.01, null_gain=1.0,
                      min_singular_value=0.05, arrow_scale=0.5, query_margin=SO101_QUERY_MARGIN)


class UR5Plant(ChainPlant):
    """The UR5 on a table, its tool's velocity commanded through a resolved-rate controller.

    Args:
        conveyor: a ``Conveyor`` whose phase the state carries, or None.
        teaching_box: a ``Cuboid`` (m) the tool of a query state is in.
        table_height, link_radius, velocity_gain, damping, min_singular_value, speed_tolerance:
            as ``ChainPlant``'s. The first three chain points (base, shoulder pan, shoulder lift)
            stand on the table by design; segments three or more apart may collide.
    """

    def __init__(self, conveyor: Conveyor | None = None, teaching_box: Cuboid = UR5_TEACHING_BOX,
                 table_height: float = 0.0, link_radius: float = 0.045, velocity_gain: float = 20.0,
                 damping: float = 0.01, min_singular_value: float = 0.15, speed_tolerance: float = 0.1):
        super().__init__(ur5_chain(), UR5_HOME, teaching_box, UR5_SCENE, robot="ur5", conveyor=conveyor,
                         table_height=table_height, link_radius=link_radius, first_table_point=3, collision_gap=3,
                         velocity_gain=velocity_gain, damping=damping, min_singular_value=min_singular_value,
                         speed_tolerance=speed_tolerance, arrow_scale=0.5)

    def __repr__(self) -> str:
        return f"UR5Plant(conveyor={self.conveyor})"


#: The UR5's production line (m, base frame; the base stands on the table top, z = 0): a part
#: waiting on the table, the fixture it goes to, and a conveyor running across in front of the arm.
UR5_PART = (0.55, -0.10, 0.10)
UR5_FIXTURE = (0.40, 0.35, 0.12)
UR5_CONVEYOR = Conveyor(origin=(0.45, -0.25, 0.10), direction=(0.0, 1.0, 0.0), speed=0.05, phase_range=(0.0, 0.6))


def ur5_skills() -> dict[str, Skill]:
    """The UR5's three production-line skills: the taught action is the tool's velocity (m/s)."""
    table = UR5Plant()
    line = UR5Plant(conveyor=UR5_CONVEYOR)
    home = np.concatenate([table.home, np.zeros(table.n_joints)])
    part, fixture = np.array(UR5_PART), np.array(UR5_FIXTURE)
    # reach: v = 0.8 (part - r), the tool closes 55% of the gap each second, from the home pose.
    # (+ 0.0 turns the -0.0 entries of -k I into 0.0, so Theta prints as it reads.)
    reach = np.hstack([-0.8 * np.eye(3), 0.8 * part[:, None]]) + 0.0
    # place: from above the part (as if just picked), across to the fixture and down onto it;
    # the vertical gain is half the horizontal one, so the tool crosses high and settles last.
    gains = np.diag([1.0, 1.0, 0.5])
    place = np.hstack([-gains, (gains @ fixture)[:, None]]) + 0.0
    # The pose the inverse kinematics (UR5Plant.state_at) gives for the tool 15 cm above the part,
    # rounded to 1e-4 rad (the tool within 0.1 mm of it; tests/core/test_ur5_skills.py checks).
    # Written out rather than solved here: solving would compile numba kernels on import.
    above_part = np.concatenate([[-0.3682, -1.2845, 1.6437, -1.5907, -1.6253, 0.0], np.zeros(6)])
    # conveyor: v = 1.5 (o + s d - r) + speed d: pulled onto the moving part, plus the belt's own
    # velocity as feed-forward, so the tool rides with the part without lagging behind it.
    direction, origin, speed = np.array(UR5_CONVEYOR.direction), np.array(UR5_CONVEYOR.origin), UR5_CONVEYOR.speed
    follow = np.hstack([-1.5 * np.eye(3), 1.5 * direction[:, None], (1.5 * origin + speed * direction)[:, None]]) + 0.0
    # Thresholds: about the median condition number of S random query-state candidates
    # (tests/core/test_ur5_skills.py measures them), as for the paper's skills.
    skills = [
        Skill("ur5-reach", "Reach the part on the table", table, ToolFeatures(table), reach, home,
              SpacePointTarget(UR5_PART),
              description="Move the tool to the part waiting on the table at (0.55, -0.10, 0.10) m: "
                          "velocity = 0.8 (part - tool).", max_condition=50.0),
        Skill("ur5-place", "Place the part at the fixture", table, ToolFeatures(table), place, above_part,
              SpacePointTarget(UR5_FIXTURE),
              description="Carry the part across to the fixture at (0.40, 0.35, 0.12) m, lowering it more slowly "
                          "than it moves across.", max_condition=50.0),
        Skill("ur5-conveyor", "Follow the part on the conveyor", line, ConveyorFeatures(line), follow,
              np.concatenate([home, [0.0]]),
              ConveyorTarget(UR5_CONVEYOR.origin, UR5_CONVEYOR.direction, UR5_CONVEYOR.phase_range),
              description="Catch up with the part riding the conveyor (5 cm/s along y) and move with it.",
              max_condition=70.0),
    ]
    return {skill.key: skill for skill in skills}


#: The Panda's production line (m, base frame; the base on the table top, z = 0).
PANDA_PART = (0.50, -0.15, 0.12)
PANDA_FIXTURE = (0.40, 0.22, 0.15)
PANDA_CONVEYOR = Conveyor(origin=(0.45, -0.25, 0.12), direction=(0.0, 1.0, 0.0), speed=0.05, phase_range=(0.0, 0.5))

#: The SO-101's table top (m, base frame): a part in front of it to the right, a fixture to the left.
#: The goals (the jaws' point when grasping) are 6 and 8 cm above the table: the arm's envelope keeps
#: every link 2 cm above it (``SO101Envelope.clearance``), and a skill learnt from demonstrations a
#: few millimetres off settles a centimetre or two from its goal, so a goal 4 cm above the clearance
#: leaves the reproduction of a nearly right skill room (tests/core/test_arm_skills.py measures it).
SO101_PART = (0.22, -0.08, 0.06)
SO101_FIXTURE = (0.18, 0.09, 0.08)


def panda_skills() -> dict[str, Skill]:
    """The Panda's three production-line skills (``production_line_skills``)."""
    # The pose the inverse kinematics (ChainPlant.state_at) gives for the tool 15 cm above the part,
    # rounded to 1e-4 rad (within 0.1 mm of it; tests/core/test_arm_skills.py checks), written out
    # so that importing compiles no kernel.
    above_part = np.concatenate([[-0.1257, -0.0099, -0.1412, -2.2396, -0.1149, 2.2294, 0.7854], np.zeros(7)])
    return production_line_skills("panda", "Panda", panda_plant(), PANDA_PART, PANDA_FIXTURE, above_part, 65.0,
                                  line=panda_plant(PANDA_CONVEYOR), conveyor_condition=72.0)


def so101_skills() -> dict[str, Skill]:
    """The SO-101's table-top skills: reach and place (``production_line_skills``, no conveyor)."""
    # The inverse kinematics' pose for the jaws 6 cm above the part (12 cm above the table), rounded
    # to 1e-4 rad (as the Panda's).
    above_part = np.array([0.4148, -0.894, 0.7088, 0.9771, 0.0237])
    return production_line_skills("so101", "SO-101", so101_plant(), SO101_PART, SO101_FIXTURE, above_part, 128.0)




@dataclass(frozen=True)
class ShippedArm:
    """A shipped arm as a chooser offers it: its label, its robot name, its skills' (title, key) and how to build them.

    Attributes:
        label: for an arm chooser ("Franka Panda (3-D)").
        robot: the plants' robot name ("panda"), as in the logs.
        skills: ((title, key), ...), known without building the arm.
        build: returns {key: Skill} (reads the URDF and builds the plants).
    """

    label: str
    robot: str
    skills: tuple[tuple[str, str], ...]
    build: Callable[[], dict]

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(key for _, key in self.skills)


UR5_ARM = ShippedArm("UR5 arm (3-D)", "ur5", (("Reach the part on the table", "ur5-reach"),
                                               ("Place the part at the fixture", "ur5-place"),
                                               ("Follow the part on the conveyor", "ur5-conveyor")), ur5_skills)
PANDA_ARM = ShippedArm("Franka Panda (3-D)", "panda", production_line_titles("panda", "Panda", conveyor=True),
                       panda_skills)
SO101_ARM = ShippedArm("SO-101 (3-D)", "so101", production_line_titles("so101", "SO-101", conveyor=False),
                       so101_skills)

#: The shipped arms, in the order ``SKILLS`` lists their skills.
SHIPPED_ARMS = (UR5_ARM, PANDA_ARM, SO101_ARM)

#: The shipped arms beyond the paper's and the UR5 (whose chooser entry has labels of its own), for an
#: arm chooser (the demo's): (label, ((title, key), ...)) each; their skills are in ``SKILLS``.
CHAIN_ARMS = tuple((arm.label, arm.skills) for arm in (PANDA_ARM, SO101_ARM))


def promise_shipped_skills(registry) -> None:
    """Promise every shipped arm's skills to ``registry`` (a ``SkillRegistry``), each arm built on first use."""
    for arm in SHIPPED_ARMS:
        registry.defer(arm.keys, lambda build=arm.build: build().values())


promise_shipped_skills(SKILLS)
