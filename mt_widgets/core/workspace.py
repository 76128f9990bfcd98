"""Regions of the plane (and a box in space): where query states are drawn from and where a plant may go."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .validation import as_float_array


@dataclass(frozen=True)
class Box:
    """An axis-aligned rectangle ``xlim x ylim`` (used as a view extent too)."""

    xlim: tuple[float, float]
    ylim: tuple[float, float]

    def contains(self, points) -> np.ndarray:
        points = as_float_array("points", points, shape=(2,))
        return ((points[..., 0] >= self.xlim[0]) & (points[..., 0] <= self.xlim[1])
                & (points[..., 1] >= self.ylim[0]) & (points[..., 1] <= self.ylim[1]))


@dataclass(frozen=True)
class Cuboid:
    """An axis-aligned box ``xlim x ylim x zlim`` in space (where an arm's tool may be taught)."""

    xlim: tuple[float, float]
    ylim: tuple[float, float]
    zlim: tuple[float, float]

    def __post_init__(self):
        for name in ("xlim", "ylim", "zlim"):
            low, high = as_float_array(name, getattr(self, name), ndim=1, shape=(2,))
            if not low < high:
                raise ValueError(f"{name}: expected (low, high) with low < high, got {(float(low), float(high))}")
            object.__setattr__(self, name, (float(low), float(high)))

    @property
    def low(self) -> np.ndarray:
        return np.array([self.xlim[0], self.ylim[0], self.zlim[0]])

    @property
    def high(self) -> np.ndarray:
        return np.array([self.xlim[1], self.ylim[1], self.zlim[1]])

    def contains(self, points) -> np.ndarray:
        points = as_float_array("points", points, shape=(3,))
        return np.all((points >= self.low) & (points <= self.high), axis=-1)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n points uniform in the box: (n, 3)."""
        return rng.uniform(self.low, self.high, size=(n, 3))


@dataclass(frozen=True)
class AnnulusSector:
    """Points at a distance in [r_min, r_max] from the origin with a bearing in [-max_yaw, max_yaw].

    This is the shape of what a desktop arm such as the uArm Swift Pro can reach in the
    horizontal plane: not too close to its base, not beyond its reach, not behind it.
    Bearings are measured from +x (the arm's forward axis), in degrees.
    """

    r_min: float
    r_max: float
    max_yaw_deg: float

    def __post_init__(self):
        if not 0 <= self.r_min < self.r_max:
            raise ValueError(f"r_min, r_max: expected 0 <= r_min < r_max, got {self.r_min}, {self.r_max}")
        if not 0 < self.max_yaw_deg <= 180:
            raise ValueError(f"max_yaw_deg: expected a bearing in (0, 180], got {self.max_yaw_deg}")

    @property
    def bounding_box(self) -> Box:
        yaw = np.deg2rad(self.max_yaw_deg)
        x_min = self.r_min * np.cos(yaw) if self.max_yaw_deg <= 90 else -self.r_max
        y_max = self.r_max * (np.sin(yaw) if self.max_yaw_deg <= 90 else 1.0)
        return Box((float(min(x_min, self.r_max * np.cos(yaw))), self.r_max), (-float(y_max), float(y_max)))

    def contains(self, points, tolerance: float = 1e-9) -> np.ndarray:
        points = as_float_array("points", points, shape=(2,))
        radius = np.hypot(points[..., 0], points[..., 1])
        yaw = np.degrees(np.arctan2(points[..., 1], points[..., 0]))
        return ((radius >= self.r_min - tolerance) & (radius <= self.r_max + tolerance)
                & (np.abs(yaw) <= self.max_yaw_deg + tolerance))

    def project(self, points) -> np.ndarray:
        """A point of the sector for each point: its radius and bearing clamped to the sector's.

        Inside the sector a point is its own projection. Outside it, this is the polar clamp, not
        always the Euclidean nearest point (beyond the yaw limit at a large radius the nearest
        point lies on the edge ray at a smaller radius); what matters for a kinematic plant is
        that the result is inside the sector and moves with the input continuously.
        """
        points = as_float_array("points", points, shape=(2,))
        radius = np.clip(np.hypot(points[..., 0], points[..., 1]), self.r_min, self.r_max)
        yaw = np.clip(np.arctan2(points[..., 1], points[..., 0]), -np.deg2rad(self.max_yaw_deg),
                      np.deg2rad(self.max_yaw_deg))
        return np.stack([radius * np.cos(yaw), radius * np.sin(yaw)], axis=-1)

    def outline(self, points_per_arc: int = 61) -> np.ndarray:
        """The sector's boundary as a closed polyline (K, 2): the outer arc, the inner arc back."""
        yaw = np.deg2rad(np.linspace(-self.max_yaw_deg, self.max_yaw_deg, int(points_per_arc)))
        outer = np.stack([self.r_max * np.cos(yaw), self.r_max * np.sin(yaw)], axis=-1)
        inner = np.stack([self.r_min * np.cos(yaw[::-1]), self.r_min * np.sin(yaw[::-1])], axis=-1)
        return np.vstack([outer, inner, outer[:1]])

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n points uniform over the sector's area."""
        radius = np.sqrt(rng.uniform(self.r_min**2, self.r_max**2, size=n))
        yaw = np.deg2rad(rng.uniform(-self.max_yaw_deg, self.max_yaw_deg, size=n))
        return np.stack([radius * np.cos(yaw), radius * np.sin(yaw)], axis=-1)
