"""The SO-101's safety envelope: every goal the connector sends is checked here first.

A goal is refused (``UnsafeMoveError``, nothing sent) when a joint leaves its range, when the
tool or a link would come below the table on the way (the straight line in joint space the
servos follow, sampled), or when the speed or acceleration asked is above the envelope's. A
joint's range is the intersection of the calibrated range (the arm's real stops) and the
URDF's limits, each narrowed by ``margin``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ..errors import UnsafeMoveError
from .arm import ARM_JOINTS, GRIPPER, SO101_IDS
from .calibration import JointCalibration
from .kinematics import ArmKinematics

#: Points checked along a move's joint-space line, ends included.
PATH_SAMPLES = 16
#: The largest joint step (rad) between two points of a move checked against the table.
MAX_PATH_STEP = 0.01


@dataclass(frozen=True)
class SO101Envelope:
    """Where the SO-101 may go.

    Args:
        calibration: {joint: JointCalibration} (the arm's ranges).
        kinematics: the arm's points over the table; None: no task-space check is possible,
            so every move is refused (reads and teaching by hand still work).
        table_height: the table's height in the base frame (m; the base stands on it: 0).
        clearance: how far above the table every link point stays (m).
        margin: how far inside each joint range goals stay (rad).
        max_speed: the fastest joint speed a move may ask (rad/s).
        max_acceleration: the largest joint acceleration a move may ask (rad/s^2).
    """

    calibration: dict[str, JointCalibration]
    kinematics: ArmKinematics | None
    table_height: float = 0.0
    clearance: float = 0.02
    margin: float = 0.05
    max_speed: float = 1.5
    max_acceleration: float = 6.0

    def __post_init__(self):
        if set(self.calibration) != set(SO101_IDS):
            raise ValueError(f"calibration: expected the joints {list(SO101_IDS)}, got {sorted(self.calibration)}")
        for name in ("table_height", "clearance", "margin", "max_speed", "max_acceleration"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)):
                raise ValueError(f"{name}: expected a finite number, got {value!r}")
            if name != "table_height" and value < 0:
                raise ValueError(f"{name}: expected a number >= 0, got {value!r}")
        urdf = self.kinematics.limits if self.kinematics is not None else {}
        ranges: dict[str, tuple[float, float]] = {}
        for joint, calibration in self.calibration.items():
            low, high = calibration.range_radians
            if joint in urdf:
                low, high = max(low, urdf[joint][0]), min(high, urdf[joint][1])
            low, high = low + self.margin, high - self.margin
            if low >= high:
                raise ValueError(f"calibration: {joint}: the calibrated range and the URDF's limits leave no "
                                 f"room inside the margin of {self.margin} rad")
            ranges[joint] = (low, high)
        # Frozen: the limits a live arm is checked against cannot be loosened by assigning to them.
        object.__setattr__(self, "ranges", MappingProxyType(ranges))

    def check_joints(self, goal: dict[str, float]) -> None:
        """Raise ``UnsafeMoveError`` if a joint of ``goal`` (rad) is outside its range."""
        for joint, value in goal.items():
            if joint not in self.ranges:
                raise ValueError(f"goal: expected joints among {list(SO101_IDS)}, got {joint!r}")
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)):
                raise ValueError(f"goal: {joint}: expected a finite number of radians, got {value!r}")
            low, high = self.ranges[joint]
            if not low <= value <= high:
                limit = low if value < low else high
                raise UnsafeMoveError(f"{joint} to {value:.3f} rad leaves the arm's safe range "
                                      f"[{low:.3f}, {high:.3f}] rad", coordinate=joint, value=value, limit=limit)

    def check_path(self, start: dict[str, float], goal: dict[str, float]) -> None:
        """Raise ``UnsafeMoveError`` if a link point comes below the table between ``start`` and
        ``goal`` (both with every arm joint), or if there is no kinematics to check it with."""
        if self.kinematics is None:
            raise UnsafeMoveError("the arm has no kinematic model, so the table cannot be checked: give "
                                  "SO101(kinematics=...) to move it", coordinate="table", value=math.nan,
                                  limit=None)
        a = np.array([start[j] for j in ARM_JOINTS])
        b = np.array([goal[j] for j in ARM_JOINTS])
        # Samples no further apart than MAX_PATH_STEP in any joint: between two, a link point's dip
        # below the straight chord is second order in the step (under a millimetre at 0.01 rad).
        samples = max(PATH_SAMPLES, int(np.ceil(float(np.abs(b - a).max()) / MAX_PATH_STEP)) + 1)
        s = np.linspace(0.0, 1.0, samples)[:, None]
        heights = self.kinematics.points(a + s * (b - a))[..., 2]
        floor = self.table_height + self.clearance
        lowest = float(heights.min())
        if lowest < floor:
            raise UnsafeMoveError(f"the move would bring the arm to {lowest * 1000:.0f} mm, below the table's "
                                  f"{floor * 1000:.0f} mm (table plus clearance)", coordinate="z", value=lowest,
                                  limit=floor)

    def check_speed(self, speed: float, acceleration: float) -> None:
        """Raise ``UnsafeMoveError`` for a speed or acceleration above the envelope's (or not > 0)."""
        for name, value, limit in (("speed", speed, self.max_speed),
                                   ("acceleration", acceleration, self.max_acceleration)):
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                    and value > 0):
                raise ValueError(f"{name}: expected a number > 0, got {value!r}")
            if value > limit:
                raise UnsafeMoveError(f"{name} {value} is above the envelope's {limit}", coordinate=name,
                                      value=value, limit=limit)

    def check_gripper(self, value: float) -> None:
        self.check_joints({GRIPPER: value})
