"""The suite's other shipped arms on the one chain engine: the Franka Panda and the SO-101.

Each is a ``ChainPlant`` of the URDF shipped with the package (``mt_widgets/robot_models/urdf_files``,
read at run time by ``mt_widgets.robot_models``) with its home pose, teaching box and scene; the
skills on them are in ``skills``. A user's own arm is built the same way
(docs/guide/your-own-arm.md).

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

import numpy as np

from ..robot_models.urdf import load_shipped
from .chain_plant import ChainPlant, Conveyor
from .serial_chain import SerialChain
from .workspace import Cuboid

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
                      min_singular_value=0.05, arrow_scale=0.5)
