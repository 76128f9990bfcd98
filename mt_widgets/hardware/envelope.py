"""Software safety envelope for the uArm Swift Pro, checked before anything is sent.

Frame: the arm's own, in millimetres: X forward, Y left, Z up, origin on the base axis.
Yaw is ``atan2(y, x)``; radius (stretch) is ``hypot(x, y)``.

Why the defaults (``docs/uarm-protocol.md``, "Frame and workspace"): recomputed from the 4.x
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

import numpy as np

from mt_widgets.core.uarm_plant import UARM_WORKSPACE_CM
from mt_widgets.core.validation import is_real

from .errors import UnsafeMoveError

#: Fixed height of the teaching plane (mm), see the module docstring.
TEACHING_HEIGHT_MM = 80.0
#: The teaching plant's workspace (``mt_widgets.core.UARM_WORKSPACE_CM``, the one definition),
#: converted to the arm's millimetres: radius (mm) and yaw (degrees) it may use.
TEACHING_RADIUS_MM = (10.0 * UARM_WORKSPACE_CM.r_min, 10.0 * UARM_WORKSPACE_CM.r_max)
TEACHING_MAX_YAW_DEG = UARM_WORKSPACE_CM.max_yaw_deg


def _finite(name: str, value, expected: str) -> float:
    # The check is core.validation's; the error is the envelope's own UnsafeMoveError, with the
    # coordinate and limit a caller of a refused move needs.
    if not is_real(value):
        raise UnsafeMoveError(f"{name}: expected {expected}, got {value!r} ({type(value).__name__})",
                              coordinate=name, value=math.nan, limit=None)
    v = float(value)
    if not math.isfinite(v):
        raise UnsafeMoveError(f"{name}: expected {expected}, got {value!r}", coordinate=name, value=v, limit=None)
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
            if not is_real(v) or not math.isfinite(v):
                raise ValueError(f"{name}: expected a finite real number (not a bool), got {v!r} ({type(v).__name__})")
        if not 0 < self.min_radius_mm < self.max_radius_mm:
            raise ValueError(f"min_radius_mm, max_radius_mm: expected 0 < min_radius_mm < max_radius_mm, "
                             f"got {self.min_radius_mm}, {self.max_radius_mm}")
        if not 0 < self.max_yaw_deg < 90:
            raise ValueError(f"max_yaw_deg: expected a number in (0, 90), got {self.max_yaw_deg}")
        if not self.min_z_mm < self.max_z_mm:
            raise ValueError(f"min_z_mm, max_z_mm: expected min_z_mm < max_z_mm, got {self.min_z_mm}, {self.max_z_mm}")
        for name in ("max_step_mm", "max_speed_mm_s", "entry_speed_mm_s", "min_speed_mm_s"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name}: expected a positive number, got {getattr(self, name)}")
        if not self.min_speed_mm_s <= min(self.entry_speed_mm_s, self.max_speed_mm_s):
            raise ValueError(f"min_speed_mm_s: expected at most entry_speed_mm_s = {self.entry_speed_mm_s} and "
                             f"max_speed_mm_s = {self.max_speed_mm_s}, got {self.min_speed_mm_s}")

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
        mm = "a finite real number of mm (arm frame)"
        x, y, z = _finite("x", x, mm), _finite("y", y, mm), _finite("z", z, mm)
        z_range = f"z must be in [{self.min_z_mm}, {self.max_z_mm}] mm"
        if z < self.min_z_mm:
            raise UnsafeMoveError(f"z = {z:.3f} mm is below the envelope's min_z_mm = {self.min_z_mm} ({z_range})",
                                  coordinate="z", value=z, limit=self.min_z_mm)
        if z > self.max_z_mm:
            raise UnsafeMoveError(f"z = {z:.3f} mm is above the envelope's max_z_mm = {self.max_z_mm} ({z_range})",
                                  coordinate="z", value=z, limit=self.max_z_mm)
        r = math.hypot(x, y)
        r_range = f"hypot(x, y) must be in [{self.min_radius_mm}, {self.max_radius_mm}] mm"
        if r < self.min_radius_mm:
            raise UnsafeMoveError(f"radius hypot(x, y) = {r:.3f} mm is inside min_radius_mm = {self.min_radius_mm} "
                                  f"({r_range})", coordinate="radius", value=r, limit=self.min_radius_mm)
        if r > self.max_radius_mm:
            raise UnsafeMoveError(f"radius hypot(x, y) = {r:.3f} mm is beyond max_radius_mm = {self.max_radius_mm} "
                                  f"({r_range})", coordinate="radius", value=r, limit=self.max_radius_mm)
        yaw = math.degrees(math.atan2(y, x))
        if abs(yaw) > self.max_yaw_deg:
            raise UnsafeMoveError(f"yaw atan2(y, x) = {yaw:.3f} deg is outside +-max_yaw_deg = {self.max_yaw_deg} "
                                  f"(yaw must be in [{-self.max_yaw_deg}, {self.max_yaw_deg}] deg)",
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
        closest = _closest_to_axis(p0, p1)
        if closest < self.min_radius_mm:
            raise UnsafeMoveError(
                f"the straight path passes {closest:.3f} mm from the base axis, inside min_radius_mm = "
                f"{self.min_radius_mm}; go round in smaller steps",
                coordinate="radius", value=closest, limit=self.min_radius_mm)

    def check_entering_segment(self, start: tuple[float, float, float], end: tuple[float, float, float]) -> None:
        """Check one leg of :meth:`SwiftPro.home` that starts outside the envelope.

        Such a leg may end outside too, but it must never take the arm further out than it
        already is, in any respect: no lower or higher than ``start`` or the height band, no
        nearer the base axis (anywhere along the straight path) nor further from it, no wider
        yaw; at most ``max_step_mm`` long. Height band, outer disc and a yaw sector narrower
        than 180 degrees are convex, so the ends cover them; the nearest approach to the base
        axis along the chord is checked as in :meth:`check_segment`.

        Raises:
            UnsafeMoveError: naming what the leg would make worse.
        """
        mm = "a finite real number of mm (arm frame)"
        p0 = tuple(_finite(f"start {n}", v, mm) for n, v in zip("xyz", start))
        p1 = tuple(_finite(n, v, mm) for n, v in zip("xyz", end))
        tol = 1e-3  # targets are rounded to the 4 decimals sent on the wire
        r0, r1 = math.hypot(p0[0], p0[1]), math.hypot(p1[0], p1[1])
        yaw0, yaw1 = math.degrees(math.atan2(p0[1], p0[0])), math.degrees(math.atan2(p1[1], p1[0]))
        if abs(yaw0) >= 90.0:
            raise UnsafeMoveError(f"the arm is at yaw {yaw0:.3f} deg, behind the base axis (x <= 0): bring it "
                                  "forward by hand (motors detached)", coordinate="yaw", value=yaw0, limit=90.0)
        z_lo, z_hi = min(self.min_z_mm, p0[2]), max(self.max_z_mm, p0[2])
        r_lo, r_hi = min(self.min_radius_mm, r0), max(self.max_radius_mm, r0)
        yaw_hi = max(self.max_yaw_deg, abs(yaw0))
        bounds = (("z", p1[2], z_lo, z_hi), ("radius", r1, r_lo, r_hi), ("yaw", yaw1, -yaw_hi, yaw_hi))
        for name, value, lo, hi in bounds:
            if not lo - tol <= value <= hi + tol:
                raise UnsafeMoveError(
                    f"a move into the envelope from {tuple(round(v, 3) for v in p0)} mm must keep {name} in "
                    f"[{lo:.3f}, {hi:.3f}] (never further out than the start), got {value:.3f}",
                    coordinate=name, value=value, limit=lo if value < lo else hi)
        step = math.dist(p0, p1)
        if step > self.max_step_mm:
            raise UnsafeMoveError(f"step of {step:.3f} mm exceeds max_step_mm = {self.max_step_mm}",
                                  coordinate="step", value=step, limit=self.max_step_mm)
        closest = _closest_to_axis(p0, p1)
        if closest < r_lo - tol:
            raise UnsafeMoveError(
                f"the straight path passes {closest:.3f} mm from the base axis, nearer than both the start "
                f"({r0:.3f} mm) and min_radius_mm = {self.min_radius_mm}",
                coordinate="radius", value=closest, limit=r_lo)

    def entry_path(self, start: tuple[float, float, float], target: tuple[float, float, float],
                   max_segment_mm: float = 40.0) -> list[tuple[float, float, float]]:
        """The legs :meth:`SwiftPro.home` takes from ``start`` (anywhere in front of the base)
        to ``target`` (inside), ``start`` excluded, no leg longer than ``max_segment_mm``.

        1. Below the height band: straight up into it first (nothing is dragged over the table).
        2. Radius outside ``[min_radius_mm, max_radius_mm]``: along the current yaw (a ray from
           the base axis, so never nearer to it than the start) to 10 mm inside the band.
        3. Above the band: straight down into it.
        4. Then a polar path (radius, yaw and height interpolated) to ``target``, which never
           cuts through the hole round the base as a straight chord could.

        Every leg satisfies :meth:`check_entering_segment` (outside) or :meth:`check_segment`
        (once inside); the connector checks each again before sending it.
        """
        if not (is_real(max_segment_mm) and math.isfinite(max_segment_mm) and max_segment_mm > 0):
            raise ValueError(f"max_segment_mm: expected a positive number of mm, got {max_segment_mm!r}")
        mm = "a finite real number of mm (arm frame)"
        x0, y0, z0 = (_finite(f"start {n}", v, mm) for n, v in zip("xyz", start))
        target = self.check_point(*target)
        z_margin = min(5.0, (self.max_z_mm - self.min_z_mm) / 4)
        r_margin = min(10.0, (self.max_radius_mm - self.min_radius_mm) / 4)
        legs: list[tuple[float, float, float]] = []
        here = (x0, y0, z0)

        def straight_to(end):
            nonlocal here
            count = max(1, math.ceil(math.dist(here, end) / max_segment_mm))
            legs.extend(tuple(p + (q - p) * i / count for p, q in zip(here, end)) for i in range(1, count + 1))
            here = tuple(end)

        if z0 < self.min_z_mm:
            straight_to((x0, y0, self.min_z_mm + z_margin))
        r0 = math.hypot(x0, y0)
        r_in = min(max(r0, self.min_radius_mm + r_margin), self.max_radius_mm - r_margin)
        if r_in != r0:
            yaw = math.atan2(y0, x0)
            straight_to((r_in * math.cos(yaw), r_in * math.sin(yaw), here[2]))
        if here[2] > self.max_z_mm:
            straight_to((here[0], here[1], self.max_z_mm - z_margin))
        if math.dist(here, target) > 0:
            legs.extend(tuple(float(v) for v in p) for p in polar_waypoints(here, target, max_segment_mm))
        return legs

    def check_speed(self, speed_mm_s: float, *, entering: bool = False) -> float:
        """Check a speed in mm/s; ``entering`` applies the slower ``entry_speed_mm_s``.

        Raises:
            UnsafeMoveError: if it is below ``min_speed_mm_s`` or above the limit.
        """
        limit = self.entry_speed_mm_s if entering else self.max_speed_mm_s
        name = "entry_speed_mm_s" if entering else "max_speed_mm_s"
        v = _finite("speed", speed_mm_s, f"a finite real number of mm/s in [{self.min_speed_mm_s}, {limit}]")
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


def _closest_to_axis(p0: tuple[float, ...], p1: tuple[float, ...]) -> float:
    """Nearest horizontal distance to the base axis along the straight path p0 -> p1 (mm)."""
    dx, dy = p1[0] - p0[0], p1[1] - p0[1]
    d2 = dx * dx + dy * dy
    t = 0.0 if d2 == 0 else min(1.0, max(0.0, -(p0[0] * dx + p0[1] * dy) / d2))
    return math.hypot(p0[0] + t * dx, p0[1] + t * dy)


def polar_waypoints(start_mm, end_mm, max_segment_mm: float) -> np.ndarray:
    """Points (K, 3) in mm from ``start_mm`` (excluded) to ``end_mm`` (included) along a polar path.

    Radius, yaw and height are interpolated linearly, so the path stays in the annulus
    sector both ends are in (a straight chord between far-apart points may pass through the
    hole round the base, which the envelope forbids); no segment is longer than
    ``max_segment_mm``.

    Args:
        start_mm: (3,) x, y, z in mm.
        end_mm: (3,) x, y, z in mm.
        max_segment_mm: longest straight move between consecutive points.
    """
    if not (is_real(max_segment_mm) and math.isfinite(max_segment_mm) and max_segment_mm > 0):
        raise ValueError(f"max_segment_mm: expected a positive number of mm, got {max_segment_mm!r}")
    p0, p1 = np.asarray(start_mm, dtype=float), np.asarray(end_mm, dtype=float)
    for name, p in (("start_mm", p0), ("end_mm", p1)):
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"{name}: expected finite (x, y, z) in mm, got {p!r}")
    r0, r1 = math.hypot(p0[0], p0[1]), math.hypot(p1[0], p1[1])
    a0, a1 = math.atan2(p0[1], p0[0]), math.atan2(p1[1], p1[0])

    def at(s):
        s = np.asarray(s, dtype=float)[:, None]
        r, a, z = r0 + s * (r1 - r0), a0 + s * (a1 - a0), p0[2] + s * (p1[2] - p0[2])
        return np.hstack([r * np.cos(a), r * np.sin(a), z])

    fine = at(np.linspace(0.0, 1.0, 65))
    length = float(np.sum(np.linalg.norm(np.diff(fine, axis=0), axis=1)))
    # Chords are shorter than arcs, so equal parameter steps of at most max_segment_mm of arc
    # (plus 5 % for the uneven speed of the polar parameter along the path) suffice.
    count = max(1, math.ceil(1.05 * length / max_segment_mm))
    points = at(np.arange(1, count + 1) / count)
    points[-1] = p1
    return points
