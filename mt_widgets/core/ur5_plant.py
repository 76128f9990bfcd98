"""A six-axis industrial arm (Universal Robots UR5) on a table, taught through its tool's velocity in space.

The arm is the serial chain of its URDF (the shipped ``ur5.urdf``, read at run time by
``mt_widgets.robot_models``), a dynamic ``ChainPlant`` mounted on a table top at
z = ``table_height`` in the base frame; the production line's conveyor may run past it.

State x = (q1..q6 rad, qd1..qd6 rad/s[, s m]). Query states are at rest, with the tool in the
teaching box above the table, reached from the home pose by position-only inverse kinematics
(so the wrist keeps the home pose's tool-down attitude as well as it can).
"""

from __future__ import annotations

import numpy as np

from ..robot_models.urdf import load_shipped
from .chain_plant import ChainPlant, Conveyor
from .serial_chain import SerialChain
from .workspace import Cuboid

#: The UR5's home pose (rad): upper arm up, forearm level, tool pointing down at about
#: (0.49, 0.11, 0.43) m.
UR5_HOME = (0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0)

#: Where the tool is taught, in the base frame (m): in front of the arm, above the table.
UR5_TEACHING_BOX = Cuboid((0.30, 0.65), (-0.25, 0.45), (0.05, 0.45))

#: What every view of the UR5 frames (m): the arm at home and all it does over the teaching box.
UR5_SCENE = Cuboid((-0.25, 0.90), (-0.50, 0.70), (0.0, 0.85))

__all__ = ["UR5_HOME", "UR5_SCENE", "UR5_TEACHING_BOX", "Conveyor", "UR5Plant", "ur5_chain"]


def ur5_chain() -> SerialChain:
    """The UR5's serial chain from its URDF (shipped with the package), tool point at ``tool0``."""
    return SerialChain.from_description(load_shipped("ur5"))


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
