"""The uArm teaching view at true scale, for a screen lying flat under the arm.

The paper's physical set-up (Fig. 2b) puts a 518 mm x 325 mm display under the uArm: the
black dot is the arm's state, the red dot (or line) the target, and the user's and optimal
arrows start at the black dot. Drawn at true scale and aligned with the arm, the black dot
lies right under the arm's tool and an arrow of 3 cm on the screen is a step of 3 cm.

Calibration (documented parameters of :class:`ScreenGeometry`):

- ``screen_mm`` and ``resolution_px`` give the pixels per millimetre. ``resolution_px`` is
  the screen's size in CSS pixels, i.e. its native resolution divided by the operating
  system's scaling factor (what ``window.screen.width/height`` say in the browser), and the
  browser zoom must be 100 %.
- ``base_px`` is where the arm's base axis stands, in pixels of the teaching canvas (it may
  lie outside the canvas: the base usually stands beside the screen).
- ``heading_deg`` is the screen direction the arm's +X (forward) points to, in degrees
  anticlockwise from the screen's right (90: the arm stands at the bottom edge and reaches
  up the screen).

The canvas is pinned to the bottom-left corner of the screen (``position: fixed``), so its
place on the screen does not depend on the texts above it; ``canvas_px`` is its size. To
check a calibration, :func:`calibration_painter` draws a cross where the arm's tool should
be and a 10 cm ruler: move the arm to the cross (``UArmBridge.show_state``) and measure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from ipywidgets import HTML

from mt_widgets.core import Box
from mt_widgets.core.validation import as_bool
from mt_widgets.widgets import ViewTransform
from mt_widgets.widgets.episode import keep_canvas_size

#: The paper's display: 518 mm x 325 mm (a 24-inch 16:10 monitor, 1920 x 1200 pixels).
PAPER_SCREEN_MM = (518.0, 325.0)
PAPER_SCREEN_PX = (1920, 1200)
#: Height kept free above the canvas for the texts and buttons (pixels), by default.
CONTROL_BAND_PX = 260
#: CSS class of the pinned canvases.
SCREEN_CLASS = "mt-uarm-screen"
MM_PER_CM = 10.0


def _pair(name: str, value, positive: bool = True) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a pair of numbers, got {value!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or (positive and not (a > 0 and b > 0)):
        kind = "positive finite" if positive else "finite"
        raise ValueError(f"{name}: expected two {kind} numbers, got {value!r}")
    return a, b


@dataclass(frozen=True)
class ScreenTransform(ViewTransform):
    """A ``ViewTransform`` with a fixed scale, a fixed origin pixel and a rotation.

    World units are the skill's (cm for the uArm). ``xlim``/``ylim`` are the world box
    the canvas shows (for the ``ViewTransform`` interface); the mapping itself is
    ``pixel = base_px + scale * R(heading) @ world`` with the screen's y pointing down.

    Args (besides ``ViewTransform``'s):
        scale_px: pixels per world unit.
        base_px: the pixel of the world origin (the arm's base axis).
        heading_deg: screen direction of world +x, anticlockwise from the screen's right.
    """

    scale_px: float = 1.0
    base_px: tuple[float, float] = (0.0, 0.0)
    heading_deg: float = 0.0

    @property
    def pixels_per_unit(self) -> float:
        return self.scale_px

    def _rotate(self, vectors: np.ndarray) -> np.ndarray:
        # World (x, y) -> screen offsets in pixels per unit, screen y pointing down.
        c, s = math.cos(math.radians(self.heading_deg)), math.sin(math.radians(self.heading_deg))
        x, y = vectors[..., 0], vectors[..., 1]
        return np.stack([c * x - s * y, -(s * x + c * y)], axis=-1)

    def _unrotate(self, offsets: np.ndarray) -> np.ndarray:
        c, s = math.cos(math.radians(self.heading_deg)), math.sin(math.radians(self.heading_deg))
        u, v = offsets[..., 0], -offsets[..., 1]
        return np.stack([c * u + s * v, -s * u + c * v], axis=-1)

    def to_pixel(self, points) -> np.ndarray:
        points = np.asarray(points, dtype=float)
        if points.shape[-1:] != (2,):
            raise ValueError(f"points: expected an array of shape (..., 2), got shape {points.shape}")
        return np.asarray(self.base_px) + self.scale_px * self._rotate(points)

    def to_world(self, pixels) -> np.ndarray:
        pixels = np.asarray(pixels, dtype=float)
        if pixels.shape[-1:] != (2,):
            raise ValueError(f"pixels: expected an array of shape (..., 2), got shape {pixels.shape}")
        return self._unrotate(pixels - np.asarray(self.base_px)) / self.scale_px

    def action_tip(self, origin_world, action) -> np.ndarray:
        action = np.asarray(action, dtype=float)
        return self.to_pixel(origin_world) + self.pixels_per_action * self._rotate(action)

    def action_from_drag(self, origin_world, pointer_pixel) -> np.ndarray:
        delta = np.asarray(pointer_pixel, dtype=float) - self.to_pixel(origin_world)
        return self._unrotate(delta) / self.pixels_per_action


@dataclass(frozen=True)
class ScreenGeometry:
    """Where the teaching canvas is on a screen under the arm, and at what scale.

    Args:
        screen_mm: (width, height) of the screen's picture in mm (the paper's: 518 x 325).
        resolution_px: (width, height) of the screen in CSS pixels (see the module docstring).
        canvas_px: (width, height) of the teaching canvas in pixels, pinned to the screen's
            bottom-left corner (default: the full width, the height less a band of
            ``CONTROL_BAND_PX`` for texts and buttons).
        base_px: (x, y) canvas pixel of the arm's base axis (default: centred below the
            canvas, the base 60 mm below its bottom edge, for ``heading_deg = 90``).
        heading_deg: screen direction of the arm's +X, degrees anticlockwise from the right.
        action_length: cm of arrow per cm of action (1: arrows at true scale, the tip of the
            user's arrow is where the tool would go).
        pinned: pin the canvas to the screen (full-screen use); False leaves it in the page.
    """

    screen_mm: tuple[float, float] = PAPER_SCREEN_MM
    resolution_px: tuple[int, int] = PAPER_SCREEN_PX
    canvas_px: tuple[int, int] | None = None
    base_px: tuple[float, float] | None = None
    heading_deg: float = 90.0
    action_length: float = 1.0
    pinned: bool = True

    def __post_init__(self):
        object.__setattr__(self, "screen_mm", _pair("screen_mm", self.screen_mm))
        res = _pair("resolution_px", self.resolution_px)
        object.__setattr__(self, "resolution_px", (int(round(res[0])), int(round(res[1]))))
        ratio = self.pixels_per_mm_xy
        if abs(ratio[0] / ratio[1] - 1.0) > 0.03:
            raise ValueError(
                f"screen_mm, resolution_px: expected square pixels (the same pixels per mm across and down, "
                f"within 3 %), got {ratio[0]:.3f} and {ratio[1]:.3f} px/mm from {self.screen_mm} mm and "
                f"{self.resolution_px} px: check both are (width, height)")
        if self.canvas_px is None:
            canvas = (self.resolution_px[0], max(100, self.resolution_px[1] - CONTROL_BAND_PX))
        else:
            canvas = _pair("canvas_px", self.canvas_px)
            canvas = (int(round(canvas[0])), int(round(canvas[1])))
            if canvas[0] > self.resolution_px[0] or canvas[1] > self.resolution_px[1]:
                raise ValueError(f"canvas_px: expected at most the screen's resolution_px {self.resolution_px}, "
                                 f"got {canvas}")
        object.__setattr__(self, "canvas_px", canvas)
        if self.base_px is None:
            base = (canvas[0] / 2.0, canvas[1] + 60.0 * self.pixels_per_mm)
        else:
            base = _pair("base_px", self.base_px, positive=False)
        object.__setattr__(self, "base_px", base)
        object.__setattr__(self, "pinned", as_bool("pinned", self.pinned))
        if not math.isfinite(self.heading_deg):
            raise ValueError(f"heading_deg: expected a finite angle in degrees, got {self.heading_deg!r}")
        if not (math.isfinite(self.action_length) and self.action_length > 0):
            raise ValueError(f"action_length: expected a positive number, got {self.action_length!r}")

    @property
    def pixels_per_mm_xy(self) -> tuple[float, float]:
        """Pixels per mm across and down the screen."""
        return self.resolution_px[0] / self.screen_mm[0], self.resolution_px[1] / self.screen_mm[1]

    @property
    def pixels_per_mm(self) -> float:
        """Pixels per mm of the view (the mean of across and down: pixels are square within 3 %)."""
        x, y = self.pixels_per_mm_xy
        return (x + y) / 2.0

    def transform(self, units: str = "cm") -> ScreenTransform:
        """The world -> canvas mapping for a skill in ``units`` ("cm" for the uArm skills, or "mm")."""
        per_unit = {"cm": MM_PER_CM, "mm": 1.0}
        if units not in per_unit:
            raise ValueError(f"units: expected 'cm' or 'mm', got {units!r}")
        scale = self.pixels_per_mm * per_unit[units]
        width, height = self.canvas_px
        probe = ScreenTransform((0.0, 1.0), (0.0, 1.0), width, height, 0.0, self.action_length, scale,
                                self.base_px, self.heading_deg)
        corners = probe.to_world([[0, 0], [width, 0], [0, height], [width, height]])
        xlim = (float(corners[:, 0].min()), float(corners[:, 0].max()))
        ylim = (float(corners[:, 1].min()), float(corners[:, 1].max()))
        return ScreenTransform(xlim, ylim, width, height, 0.0, self.action_length, scale, self.base_px,
                               self.heading_deg)

    def css(self) -> HTML:
        """A style element pinning the canvases of class ``SCREEN_CLASS`` to the screen's
        bottom-left corner, with room left in the page so nothing scrolls under them."""
        if not self.pinned:
            return HTML("")
        width, height = self.canvas_px
        return HTML(f"<style>.{SCREEN_CLASS} {{position: fixed !important; left: 0; bottom: 0; z-index: 5; "
                    f"width: {width}px !important; height: {height}px !important; margin: 0 !important}} "
                    f"body {{padding-bottom: {height + 8}px !important}}</style>")


def screen_background(view, geometry: ScreenGeometry):
    """A painter for an ``ArmView``'s background on the screen: the workspace outline, the
    red target (dot or line), the base and a 10 cm ruler (to check the true scale)."""
    skill, theme = view.skill, view.theme

    def paint(canvas):
        t = view.transform
        canvas.fill_style = theme.background
        canvas.fill_rect(0, 0, t.width, t.height)
        drawing = skill.drawing()
        for line in drawing.outline:
            canvas.stroke_style = theme.axes
            canvas.line_width = 1.5
            canvas.set_line_dash([6.0, 6.0])
            canvas.stroke_lines(t.to_pixel(line).tolist())
            canvas.set_line_dash([])
        if drawing.base is not None:
            base = t.to_pixel(drawing.base)
            canvas.fill_style = theme.arm
            canvas.fill_circle(float(base[0]), float(base[1]), 10.0)
        # The screen shows the whole glass, beyond the plant's view: the target's shape is
        # asked for over the screen's own extent.
        shape = None if skill.target is None else skill.target.shape(Box(t.xlim, t.ylim))
        canvas.fill_style = theme.target
        canvas.stroke_style = theme.target
        if shape is not None and len(shape.points) >= 2:
            canvas.line_width = 4.0
            canvas.stroke_lines(t.to_pixel(shape.points).tolist())
        elif shape is not None and shape.is_point:
            x, y = t.to_pixel(shape.points[0])
            canvas.fill_circle(float(x), float(y), 10.0)
        # A 10 cm ruler, bottom left: hold a ruler to it to check the screen's calibration.
        length = 10.0 * MM_PER_CM * geometry.pixels_per_mm
        x0, y0 = 20.0, t.height - 24.0
        canvas.stroke_style = theme.text
        canvas.line_width = 2.0
        canvas.stroke_line(x0, y0, x0 + length, y0)
        for x in (x0, x0 + length):
            canvas.stroke_line(x, y0 - 6, x, y0 + 6)
        canvas.fill_style = theme.text
        canvas.font = "14px sans-serif"
        canvas.text_align = "left"
        canvas.text_baseline = "bottom"
        canvas.fill_text("10 cm", x0, y0 - 8)

    return paint


def calibration_painter(view, point_cm=(22.0, 0.0), size_px: float = 40.0):
    """A painter drawing a cross at ``point_cm`` (plant frame): the arm's tool should be over it."""
    point = np.asarray(point_cm, dtype=float)

    def paint(canvas):
        x, y = (float(v) for v in view.transform.to_pixel(point))
        canvas.stroke_style = view.theme.text
        canvas.line_width = 2.0
        canvas.stroke_line(x - size_px, y, x + size_px, y)
        canvas.stroke_line(x, y - size_px, x, y + size_px)
        canvas.stroke_circle(x, y, size_px / 2)

    return paint


def fit_view(view, geometry: ScreenGeometry) -> None:
    """Put an ``ArmView`` on the screen: true-scale transform, canvas size, background, pinning."""
    view.transform = geometry.transform(view.skill.units)
    width, height = geometry.canvas_px
    view.canvas.width, view.canvas.height = width, height
    view.canvas.layout.width = f"{width}px"
    view.canvas.layout.height = f"{height}px"
    keep_canvas_size(view)  # true size: the episode's window-sized canvas rule must not apply
    if geometry.pinned:
        view.canvas.add_class(SCREEN_CLASS)
    view.show(screen_background(view, geometry), "background")
    view.repaint()


def fit_episode(episode, geometry: ScreenGeometry, show_player: bool = True) -> None:
    """Put an ``EpisodeWidget``'s teaching view (and its reproduction player) on the screen.

    The player's canvas takes the teaching canvas's place when the episode finishes (both
    are pinned to the same corner); with ``show_player=False`` it stays hidden (the real
    arm plays the reproduction).
    """
    show_player = as_bool("show_player", show_player)
    fit_view(episode.teaching.view, geometry)
    fit_view(episode.player.view, geometry)
    episode.teaching.scale_label.value = f"<small>Scale: true size ({episode.teaching.view.scale_text})</small>"
    episode.player.layout.display = "none"

    def swap(_result):
        # The episode has put its player in the teaching canvas's place; without the player
        # the screen keeps showing the teaching canvas.
        for widget in (episode.teaching.view.canvas, episode.teaching.view.legend):
            widget.layout.display = "none" if show_player else None
        for widget in (episode.player, episode.player.view.legend):
            widget.layout.display = None if show_player else "none"

    episode.on_finished(swap)
    if episode.phase == "finished":
        swap(None)


__all__ = ["CONTROL_BAND_PX", "PAPER_SCREEN_MM", "PAPER_SCREEN_PX", "SCREEN_CLASS", "ScreenGeometry",
           "ScreenTransform", "calibration_painter", "fit_episode", "fit_view", "screen_background"]
