"""Software safety envelope for the uArm Swift Pro, checked before anything is sent.

Frame: the arm's own, in millimetres: X forward, Y left, Z up, origin on the base axis.
Yaw is ``atan2(y, x)``; radius (stretch) is ``hypot(x, y)``.

Why the defaults (``UARM_PROTOCOL.md``, "Frame and workspace"): recomputed from the 4.x
kinematics (suction mode), the arm reaches at least 101..347 mm of stretch for every
height in 40..120 mm (z = 40: 100.5..361, z = 80: 118.5..357, z = 120: 127..347.5); the
paper claims 50..320 mm, which does not match. We keep a margin of at least 8 mm inside the
worst case of that band: radius 135..310 mm, yaw within +-65 degrees (the base turns
+-90), height 40..120 mm. The teaching plant (``core``) works at 140..300 mm, yaw
+-60 degrees, at the fixed teaching height of 80 mm, which sits 40 mm from both ends of
the height band and where the arm reaches 118.5..357 mm. Speeds stop at 100 mm/s, the cap
on linear moves in the 4.x firmware; one step at most 200 mm, so a wrong target cannot send
the arm across the table in one go.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mt_widgets.core.uarm_plant import UARM_WORKSPACE_CM

from .errors import UnsafeMoveError

#: Fixed height of the teaching plane (mm), see the module docstring.
TEACHING_HEIGHT_MM = 80.0
#: The teaching plant's workspace (``mt_widgets.core.UARM_WORKSPACE_CM``, the one definition),
#: converted to the arm's millimetres: radius (mm) and yaw (degrees) it may use.
TEACHING_RADIUS_MM = (10.0 * UARM_WORKSPACE_CM.r_min, 10.0 * UARM_WORKSPACE_CM.r_max)
TEACHING_MAX_YAW_DEG = UARM_WORKSPACE_CM.max_yaw_deg


def _finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise UnsafeMoveError(f"{name} must be a real number in mm, got {value!r}", coordinate=name,
                              value=math.nan, limit=None) from exc
    if not math.isfinite(v):
        raise UnsafeMoveError(f"{name} must be finite, got {value!r}", coordinate=name, value=v, limit=None)
    return v


@dataclass(frozen=True)
class SafetyEnvelope:
    """Where and how fast the connector lets the arm move.

    Args:
        min_radius_mm: smallest horizontal distance from the base axis.
        max_radius_mm: largest horizontal distance from the base axis.
        max_yaw_deg: largest ``|atan2(y, x)|`` in degrees (x must be positive).
        min_z_mm: lowest height.
        max_z_mm: highest height.
        max_step_mm: longest single move, from the last known position.
        max_speed_mm_s: fastest move.
        min_speed_mm_s: slowest move (a speed that rounds to F0 would mean "no speed" to 4.x).
        entry_speed_mm_s: fastest move when the arm starts outside the envelope (as after
            power-up): it is brought in slowly; its target must be inside.
    """

    min_radius_mm: float = 135.0
    max_radius_mm: float = 310.0
    max_yaw_deg: float = 65.0
    min_z_mm: float = 40.0
    max_z_mm: float = 120.0
    max_step_mm: float = 200.0
    max_speed_mm_s: float = 100.0
    entry_speed_mm_s: float = 20.0
    min_speed_mm_s: float = 1.0

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        if not 0 < self.min_radius_mm < self.max_radius_mm:
            raise ValueError(f"need 0 < min_radius_mm < max_radius_mm, got {self.min_radius_mm}, {self.max_radius_mm}")
        if not 0 < self.max_yaw_deg < 90:
            raise ValueError(f"max_yaw_deg must be in (0, 90), got {self.max_yaw_deg}")
        if not self.min_z_mm < self.max_z_mm:
            raise ValueError(f"need min_z_mm < max_z_mm, got {self.min_z_mm}, {self.max_z_mm}")
        for name in ("max_step_mm", "max_speed_mm_s", "entry_speed_mm_s", "min_speed_mm_s"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)}")
        if not self.min_speed_mm_s <= min(self.entry_speed_mm_s, self.max_speed_mm_s):
            raise ValueError(f"min_speed_mm_s = {self.min_speed_mm_s} must not exceed entry_speed_mm_s "
                             f"= {self.entry_speed_mm_s} nor max_speed_mm_s = {self.max_speed_mm_s}")

    def contains(self, x: float, y: float, z: float) -> bool:
        """Whether the point (mm) is inside; False for non-finite input."""
        try:
            self.check_point(x, y, z)
        except UnsafeMoveError:
            return False
        return True

    def check_point(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        """Check one target.

        Args:
            x, y, z: the target in mm, arm frame.

        Returns:
            The target as floats.

        Raises:
            UnsafeMoveError: naming the coordinate and the limit it breaks.
        """
        x, y, z = _finite("x", x), _finite("y", y), _finite("z", z)
        if z < self.min_z_mm:
            raise UnsafeMoveError(f"z = {z:.3f} mm is below the envelope's min_z_mm = {self.min_z_mm}",
                                  coordinate="z", value=z, limit=self.min_z_mm)
        if z > self.max_z_mm:
            raise UnsafeMoveError(f"z = {z:.3f} mm is above the envelope's max_z_mm = {self.max_z_mm}",
                                  coordinate="z", value=z, limit=self.max_z_mm)
        r = math.hypot(x, y)
        if r < self.min_radius_mm:
            raise UnsafeMoveError(f"radius hypot(x, y) = {r:.3f} mm is inside min_radius_mm = {self.min_radius_mm}",
                                  coordinate="radius", value=r, limit=self.min_radius_mm)
        if r > self.max_radius_mm:
            raise UnsafeMoveError(f"radius hypot(x, y) = {r:.3f} mm is beyond max_radius_mm = {self.max_radius_mm}",
                                  coordinate="radius", value=r, limit=self.max_radius_mm)
        yaw = math.degrees(math.atan2(y, x))
        if abs(yaw) > self.max_yaw_deg:
            raise UnsafeMoveError(f"yaw atan2(y, x) = {yaw:.3f} deg is outside +-max_yaw_deg = {self.max_yaw_deg}",
                                  coordinate="yaw", value=yaw, limit=self.max_yaw_deg)
        return x, y, z

    def check_segment(self, start: tuple[float, float, float], end: tuple[float, float, float]) -> None:
        """Check that the straight move ``start -> end`` stays inside and is short enough.

        Height band, outer disc and yaw sector (narrower than 180 degrees) are convex, so
        checking the ends covers them; the inner hole is not: a chord between two inside
        points may pass close to the base, so the closest approach is checked too.

        Raises:
            UnsafeMoveError: if an end is outside, the step is longer than ``max_step_mm``,
                or the path comes closer than ``min_radius_mm`` to the base axis.
        """
        p0 = self.check_point(*start)
        p1 = self.check_point(*end)
        step = math.dist(p0, p1)
        if step > self.max_step_mm:
            raise UnsafeMoveError(f"step of {step:.3f} mm exceeds max_step_mm = {self.max_step_mm}",
                                  coordinate="step", value=step, limit=self.max_step_mm)
        dx, dy = p1[0] - p0[0], p1[1] - p0[1]
        d2 = dx * dx + dy * dy
        t = 0.0 if d2 == 0 else min(1.0, max(0.0, -(p0[0] * dx + p0[1] * dy) / d2))
        closest = math.hypot(p0[0] + t * dx, p0[1] + t * dy)
        if closest < self.min_radius_mm:
            raise UnsafeMoveError(
                f"the straight path passes {closest:.3f} mm from the base axis, inside min_radius_mm = "
                f"{self.min_radius_mm}; go round in smaller steps",
                coordinate="radius", value=closest, limit=self.min_radius_mm)

    def check_speed(self, speed_mm_s: float, *, entering: bool = False) -> float:
        """Check a speed in mm/s; ``entering`` applies the slower ``entry_speed_mm_s``.

        Raises:
            UnsafeMoveError: if it is below ``min_speed_mm_s`` or above the limit.
        """
        v = _finite("speed", speed_mm_s)
        limit = self.entry_speed_mm_s if entering else self.max_speed_mm_s
        name = "entry_speed_mm_s" if entering else "max_speed_mm_s"
        if not self.min_speed_mm_s <= v <= limit:
            raise UnsafeMoveError(f"speed = {v} mm/s must be in [min_speed_mm_s = {self.min_speed_mm_s}, "
                                  f"{name} = {limit}]",
                                  coordinate="speed", value=v, limit=limit)
        return v

    def contains_teaching_workspace(self, z_mm: float = TEACHING_HEIGHT_MM, samples: int = 181) -> bool:
        """Whether the teaching plant's sector (radius 140..300 mm, yaw +-60 deg) at height
        ``z_mm`` lies inside, boundary sampled at ``samples`` points per edge."""
        r0, r1 = TEACHING_RADIUS_MM
        for i in range(samples):
            a = math.radians(-TEACHING_MAX_YAW_DEG + 2 * TEACHING_MAX_YAW_DEG * i / (samples - 1))
            r = r0 + (r1 - r0) * i / (samples - 1)
            for rr, aa in ((r0, a), (r1, a), (r, math.radians(TEACHING_MAX_YAW_DEG)),
                           (r, -math.radians(TEACHING_MAX_YAW_DEG))):
                if not self.contains(rr * math.cos(aa), rr * math.sin(aa), z_mm):
                    return False
        return True
