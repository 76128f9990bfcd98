"""The arms: robot descriptions read from their URDFs (``mt_widgets.robot_models``) built into plants
and skills on ``mt_widgets.core``'s chain engine.

``shipped``: the UR5, the Franka Panda and the SO-101, whose skills it promises to
``mt_widgets.core.SKILLS`` (each arm read and built when one of its skills is first asked for).
``urdf_arm``: a user's own arm from a URDF file and a few numbers (what a study protocol's
``[arm]`` table names). Core reads no file; this layer sits on it and on the data layer, and
everything above core may use it (tests/test_architecture.py).
"""

from .shipped import (
    CHAIN_ARMS,
    PANDA_HOME,
    SHIPPED_ARMS,
    SO101_HOME,
    SO101_JOINT_SPEED,
    SO101_QUERY_MARGIN,
    UR5_HOME,
    ShippedArm,
    UR5Plant,
    panda_chain,
    panda_plant,
    so101_chain,
    so101_plant,
    ur5_chain,
)
from .urdf_arm import arm_skills

__all__ = ["CHAIN_ARMS", "PANDA_HOME", "SHIPPED_ARMS", "SO101_HOME", "SO101_JOINT_SPEED", "SO101_QUERY_MARGIN",
           "UR5_HOME", "ShippedArm",
           "UR5Plant", "arm_skills", "panda_chain", "panda_plant", "so101_chain", "so101_plant", "ur5_chain"]
