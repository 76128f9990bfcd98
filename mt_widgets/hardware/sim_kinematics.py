"""The simulated uArm Swift Pro's kinematics: its geometry, joint angles, reach.

The 4.x firmware's geometry and joint limits (docs/uarm-protocol.md "Frame and workspace"),
the inverse (:func:`joint_angles`) and forward (:func:`tool_position`) kinematics its
coordinate conversions and position reports use, and the reach rule every simulated move is
checked on (:func:`is_reachable`). Pure geometry: no state, no time, no command.
"""

from __future__ import annotations

import math

# 4.x firmware geometry, docs/uarm-protocol.md "Frame and workspace" (mm, degrees).
LOWER_ARM_MM = 142.07
UPPER_ARM_MM = 158.81
SHOULDER_OFFSET_MM = 13.2
SHOULDER_HEIGHT_MM = 107.4
#: Suction-cup offsets of mode 0 (4.x): the tool point is this far in front of and below the wrist.
EFFECTOR_FRONT_MM = 56.65
EFFECTOR_HEIGHT_MM = 74.55
LOWER_ARM_LIMITS_DEG = (-4.0, 135.6)
UPPER_ARM_LIMITS_DEG = (-4.0, 119.9)
BETWEEN_ARMS_LIMITS_DEG = (10.0, 151.0)
BASE_LIMIT_DEG = 90.0

#: The joints driven by steppers (base, lower arm, upper arm); joint 3, the wrist, is a servo.
STEPPERS = frozenset({0, 1, 2})


def joint_angles(x: float, y: float, z: float) -> tuple[float, float, float, float] | None:
    """Joint angles of the 4.x arm for a tool position, or None if no triangle exists.

    Args:
        x, y, z: tool position in mm (arm frame, suction mode offsets).

    Returns:
        ``(base, lower, upper, between)`` in degrees: base yaw; lower arm above the
        horizontal; upper arm below the horizontal; angle between the two arms. This
        convention reproduces the reach table of docs/uarm-protocol.md (z = 0: 87..359 mm, z = 100: 124..353,
        nothing from z = 190).
    """
    if x <= 0:
        return None
    stretch = math.hypot(x, y)
    sw = stretch - SHOULDER_OFFSET_MM - EFFECTOR_FRONT_MM
    zw = z + EFFECTOR_HEIGHT_MM - SHOULDER_HEIGHT_MM
    d = math.hypot(sw, zw)
    a, b = LOWER_ARM_MM, UPPER_ARM_MM
    if not abs(a - b) < d < a + b:
        return None
    lower = math.degrees(math.atan2(zw, sw) + math.acos((a * a + d * d - b * b) / (2 * a * d)))
    between = math.degrees(math.acos((a * a + b * b - d * d) / (2 * a * b)))
    upper = 180.0 - lower - between
    return math.degrees(math.atan2(y, x)), lower, upper, between


def tool_position(base: float, lower: float, upper: float) -> tuple[float, float, float]:
    """The tool position (mm) of joint angles (degrees, the convention of :func:`joint_angles`):
    the forward kinematics the firmware's M2221 and position reports use."""
    sw = LOWER_ARM_MM * math.cos(math.radians(lower)) + UPPER_ARM_MM * math.cos(math.radians(upper))
    zw = LOWER_ARM_MM * math.sin(math.radians(lower)) - UPPER_ARM_MM * math.sin(math.radians(upper))
    stretch = sw + SHOULDER_OFFSET_MM + EFFECTOR_FRONT_MM
    z = zw - EFFECTOR_HEIGHT_MM + SHOULDER_HEIGHT_MM
    return stretch * math.cos(math.radians(base)), stretch * math.sin(math.radians(base)), z


def angles_legal(base: float, lower: float, upper: float) -> bool:
    """Whether joint angles are within the 4.x limits (``is_angle_legal``)."""
    between = 180.0 - lower - upper
    return (abs(base) <= BASE_LIMIT_DEG
            and LOWER_ARM_LIMITS_DEG[0] <= lower <= LOWER_ARM_LIMITS_DEG[1]
            and UPPER_ARM_LIMITS_DEG[0] <= upper <= UPPER_ARM_LIMITS_DEG[1]
            and BETWEEN_ARMS_LIMITS_DEG[0] <= between <= BETWEEN_ARMS_LIMITS_DEG[1])


def is_reachable(x: float, y: float, z: float) -> bool:
    """Whether the simulated arm can put its tool at (x, y, z) mm (4.x rule, mode 0)."""
    if not all(math.isfinite(v) for v in (x, y, z)):
        return False
    angles = joint_angles(x, y, z)
    return angles is not None and angles_legal(*angles[:3])


# -- searches along the reach's edge: where a hand or a jog stops
def reachable_towards(start, target):
    """Where a hand pushing the tool from ``start`` towards ``target`` stops: the target if it
    is reachable, else the last reachable point on the way (a joint at its limit); ``start``
    if that is out of reach itself."""
    if is_reachable(*target) or not is_reachable(*start):
        return target if is_reachable(*target) else start
    lo, hi = 0.0, 1.0
    for _ in range(40):
        mid = (lo + hi) / 2
        p = tuple(a + mid * (b - a) for a, b in zip(start, target))
        lo, hi = (mid, hi) if is_reachable(*p) else (lo, mid)
    return tuple(a + lo * (b - a) for a, b in zip(start, target))


def axis_edge(direction, start):
    """The 3Plus jog G2207's goal: 1 mm inside the reach's edge along an axis from ``start``
    (direction 0..2: +x, +y, +z; 3..5: the same axes negative), or None without room (E22)."""
    axis, sign = direction % 3, (1.0 if direction < 3 else -1.0)

    def at(d):
        p = list(start)
        p[axis] += sign * d
        return tuple(p)
    if not is_reachable(*start) or not is_reachable(*at(0.7)):
        return None  # no room to move: E22
    lo, hi = 0.7, 400.0
    for _ in range(40):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if is_reachable(*at(mid)) else (lo, mid)
    return at(lo - 1.0) if lo - 1.0 >= 0.7 else None


def joint_limit(direction, start):
    """The 3Plus jog G2208's goal: the tool position with one joint at its limit, or None if
    it is already there (E22). Direction 0/3: the base to +/- its limit; 1/4: the lower arm
    until the angle between the arms is at its min/max; 2/5: the upper arm likewise."""
    angles = joint_angles(*start)
    if angles is None:
        return None
    b, lo, up, _ = angles
    if direction in (0, 3):
        goal = BASE_LIMIT_DEG - 0.5 if direction == 0 else -BASE_LIMIT_DEG + 0.5
        b, moved = goal, abs(goal - b)
    elif direction in (1, 4):  # lower arm: until the angle between the arms is at its min / max
        between = BETWEEN_ARMS_LIMITS_DEG[0] if direction == 1 else BETWEEN_ARMS_LIMITS_DEG[1]
        goal = min(max(180.0 - between - up, LOWER_ARM_LIMITS_DEG[0] + 1), LOWER_ARM_LIMITS_DEG[1] - 1)
        lo, moved = goal, abs(goal - lo)
    else:  # upper arm, likewise
        between = BETWEEN_ARMS_LIMITS_DEG[0] if direction == 2 else BETWEEN_ARMS_LIMITS_DEG[1]
        goal = min(max(180.0 - between - lo, UPPER_ARM_LIMITS_DEG[0] + 1), UPPER_ARM_LIMITS_DEG[1] - 1)
        up, moved = goal, abs(goal - up)
    if moved < 0.7:
        return None  # already at the limit: E22
    return tool_position(b, lo, up)
