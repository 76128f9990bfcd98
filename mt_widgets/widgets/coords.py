"""World <-> pixel mapping, the one place every view converts coordinates.

The world is the skill's plane (metres for the simulated arm, centimetres for the uArm),
y pointing up. The canvas has its origin at the top-left corner, y pointing down. Pointer
events from ipycanvas already arrive in canvas pixels (the front end divides by the
element's bounding box), so a CSS-scaled canvas needs no correction here.

Actions (forces in newtons, or displacements in centimetres) are drawn as arrows whose
length is the action times ``action_length`` (world units per action unit), so one scale
applies to every arrow in a view and is shown on screen.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mt_widgets.core.validation import as_float_array


@dataclass(frozen=True)
class ViewTransform:
    """Map a world rectangle onto a canvas with equal scale on both axes.

    The rectangle ``xlim x ylim`` is fitted inside the canvas minus ``margin`` pixels on every
    side, keeping the aspect ratio (a circle stays a circle) and centring the slack.

    Args:
        xlim: (x_min, x_max) of the world shown, in world units.
        ylim: (y_min, y_max) of the world shown, in world units.
        width: Canvas width in pixels.
        height: Canvas height in pixels.
        margin: Pixels kept free around the world rectangle (for axis labels).
        action_length: World units of arrow per action unit (e.g. 0.35 m per N).
    """

    xlim: tuple[float, float]
    ylim: tuple[float, float]
    width: int
    height: int
    margin: float = 30.0
    action_length: float = 1.0

    def __post_init__(self):
        for name, (low, high) in (("xlim", self.xlim), ("ylim", self.ylim)):
            if not (np.isfinite(low) and np.isfinite(high) and high > low):
                raise ValueError(f"{name}: expected (low, high) with low < high, got {(low, high)}")
        if self.width <= 2 * self.margin or self.height <= 2 * self.margin:
            raise ValueError(
                f"width, height: expected more than 2 * margin = {2 * self.margin} pixels, "
                f"got {self.width} x {self.height}")
        if not self.action_length > 0:
            raise ValueError(f"action_length: expected a positive number, got {self.action_length}")

    @property
    def pixels_per_unit(self) -> float:
        """Pixels per world unit (the same on both axes)."""
        span_x = self.xlim[1] - self.xlim[0]
        span_y = self.ylim[1] - self.ylim[0]
        return min((self.width - 2 * self.margin) / span_x, (self.height - 2 * self.margin) / span_y)

    @property
    def pixels_per_action(self) -> float:
        """Pixels of arrow per action unit (e.g. pixels per newton)."""
        return self.pixels_per_unit * self.action_length

    @property
    def _origin(self) -> tuple[float, float]:
        # Pixel of the world point (xlim[0], ylim[1]), with the slack split evenly.
        scale = self.pixels_per_unit
        used_w = (self.xlim[1] - self.xlim[0]) * scale
        used_h = (self.ylim[1] - self.ylim[0]) * scale
        return (self.width - used_w) / 2.0, (self.height - used_h) / 2.0

    def to_pixel(self, points) -> np.ndarray:
        """World points (..., 2) -> canvas pixels (..., 2)."""
        points = as_float_array("points", points, shape=(2,), finite=False)
        left, top = self._origin
        scale = self.pixels_per_unit
        px = left + (points[..., 0] - self.xlim[0]) * scale
        py = top + (self.ylim[1] - points[..., 1]) * scale
        return np.stack([px, py], axis=-1)

    def to_world(self, pixels) -> np.ndarray:
        """Canvas pixels (..., 2) -> world points (..., 2)."""
        pixels = as_float_array("pixels", pixels, shape=(2,), finite=False)
        left, top = self._origin
        scale = self.pixels_per_unit
        x = self.xlim[0] + (pixels[..., 0] - left) / scale
        y = self.ylim[1] - (pixels[..., 1] - top) / scale
        return np.stack([x, y], axis=-1)

    def action_tip(self, origin_world, action) -> np.ndarray:
        """Pixel of the tip of the arrow drawing ``action`` (..., 2) from ``origin_world``."""
        action = as_float_array("action", action, shape=(2,), finite=False)
        base = self.to_pixel(origin_world)
        scale = self.pixels_per_action
        return base + np.stack([action[..., 0] * scale, -action[..., 1] * scale], axis=-1)

    def action_from_drag(self, origin_world, pointer_pixel) -> np.ndarray:
        """The action (2,) whose arrow from ``origin_world`` ends at ``pointer_pixel``."""
        base = self.to_pixel(origin_world)
        pointer = as_float_array("pointer_pixel", pointer_pixel, shape=(2,), finite=False)
        delta = pointer - base
        return np.array([delta[0], -delta[1]]) / self.pixels_per_action

    def nice_action_step(self, target_pixels: float = 60.0) -> float:
        """A round action magnitude (1, 2 or 5 times a power of ten) about ``target_pixels`` long.

        Used for the scale bar, so the user reads e.g. "1 N" rather than "0.8731 N".
        """
        raw = target_pixels / self.pixels_per_action
        exponent = np.floor(np.log10(raw))
        for mantissa in (1.0, 2.0, 5.0, 10.0):
            if mantissa * 10**exponent >= raw * 0.7:
                return float(mantissa * 10**exponent)
        return float(10 ** (exponent + 1))


def nice_ticks(low: float, high: float, max_ticks: int = 9) -> np.ndarray:
    """Round tick positions (steps of 1, 2 or 5 times a power of ten) covering [low, high]."""
    if not high > low:
        raise ValueError(f"low, high: expected low < high, got {low}, {high}")
    span = high - low
    for exponent in range(int(np.floor(np.log10(span))) - 2, int(np.ceil(np.log10(span))) + 2):
        for mantissa in (1.0, 2.0, 5.0):
            step = mantissa * 10.0**exponent
            first = np.ceil(low / step - 1e-9) * step
            count = int(np.floor((high - first) / step + 1e-9)) + 1
            if count <= max_ticks:
                return first + step * np.arange(count)
    return np.array([low, high])
