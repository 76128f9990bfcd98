"""The arm view: the workspace, the target and the robot, on layered canvases.

Layers (bottom to top) of the ``MultiCanvas``:

- ``background``: grid, axes in the skill's units, the target, the arrow scale bar. Drawn
  once; it never changes for a skill.
- ``ghost``: faint paths (the target skill's own motion, the learnt path).
- ``robot``: the robot in its current state; the animation layer.
- ``arrows``: action arrows (the user's, the optimal one, the rubber band while dragging).

Each layer keeps the function that paints its current content, so a browser view that
attaches later (Voila, a page reload) gets everything again (see ``redraw.py``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from ipywidgets import Layout

from mt_widgets.core.drawing import PlantDrawing
from mt_widgets.core.validation import as_bool

from .coords import ViewTransform, nice_ticks
from .legend import CanvasLegend
from .looks import layered_canvas
from .redraw import drawing_batch, repaint_on_new_view
from .robots import painter_for
from .theme import get_theme

LAYERS = ("background", "ghost", "robot", "arrows")

# Text sizes in CSS pixels as the user sees them. A canvas shown narrower than its pixel
# width (``css_width``) shrinks its text too: at 360 px for 480 canvas pixels the first
# version's 11 px tick labels read as 8 px, too small for a novice to read the scale.
TICK_FONT_PX = 12.0
LABEL_FONT_PX = 13.0


def default_canvas_size(xlim, ylim, max_width: int = 480, max_height: int = 480, margin: float = 34.0):
    """Canvas (width, height) in pixels that fits the world rectangle's aspect ratio."""
    span_x, span_y = xlim[1] - xlim[0], ylim[1] - ylim[0]
    scale = min((max_width - 2 * margin) / span_x, (max_height - 2 * margin) / span_y)
    return int(round(span_x * scale + 2 * margin)), int(round(span_y * scale + 2 * margin))


def _text_scale(css_width: str | None, width: int) -> float:
    """Canvas pixels per CSS pixel when the width is given in pixels (e.g. "360px"), else 1.

    A relative width ("100%") is unknown until the page lays it out; such canvases are
    usually shown near their own size, so their text is drawn at its nominal size.
    """
    if css_width and css_width.strip().endswith("px"):
        try:
            shown = float(css_width.strip()[:-2])
        except ValueError:
            raise ValueError(f"css_width: expected e.g. '360px' or '100%', got {css_width!r}") from None
        if shown > 0:
            # Capped so that a very small view does not get labels wider than its margins.
            return min(max(width / shown, 1.0), 1.5)
    return 1.0


class ArmView:
    """A skill's workspace on a layered canvas, with a robot drawn in any state.

    Args:
        skill: A ``mt_widgets.core.Skill``: what is drawn comes from ``skill.drawing()`` (view,
            units, base, outline, arrow scale), ``skill.sketch(state)`` and ``skill.target_shape()``.
        width: Canvas width in pixels (default: fitted to the workspace's aspect ratio).
        height: Canvas height in pixels (default: fitted to the workspace's aspect ratio).
        theme: A ``Theme`` or a theme name (default Okabe-Ito).
        action_length: World units of arrow per action unit (default: the plant's drawing's).
        css_width: CSS width of the canvas element (e.g. "100%"); the canvas is then
            stretched by the browser and pointer events are still mapped to canvas pixels.
        target_label: the word written beside the skill's target, or None for none. "goal" by
            default: "target" also names a study group, which a blinded participant must not see.
    """

    def __init__(self, skill, width: int | None = None, height: int | None = None, theme=None,
                 action_length: float | None = None, css_width: str | None = None, target_label: str | None = "goal"):
        if target_label is not None and not isinstance(target_label, str):
            raise ValueError(f"target_label: expected a short text or None, got {target_label!r}")
        self.target_label = target_label
        self.skill = skill
        self.theme = get_theme(theme)
        self.drawing = skill.drawing()
        if not isinstance(self.drawing, PlantDrawing):
            # A plant in space (the UR5) says SpaceDrawing: this view draws one plane only.
            raise TypeError(f"skill: expected a skill whose plant is drawn in the plane (a PlantDrawing), got "
                            f"{getattr(skill, 'key', skill)!r}, drawn in space ({type(self.drawing).__name__}); "
                            f"its 3-D teaching view is not built yet (docs/guide/industrial-arm.md)")
        box = self.drawing.view
        auto_w, auto_h = default_canvas_size(box.xlim, box.ylim)
        width = auto_w if width is None else int(width)
        height = auto_h if height is None else int(height)
        if action_length is None:
            action_length = self.drawing.action_length
        self.transform = ViewTransform(tuple(box.xlim), tuple(box.ylim), width, height, 34.0,
                                       float(action_length))
        layout = Layout(width=css_width, height="auto") if css_width else Layout()
        self.text_scale = _text_scale(css_width, width)
        self.canvas = layered_canvas(len(LAYERS), width, height, layout=layout)
        self.painter = painter_for(skill)
        self._painters: dict[str, Callable[[object], None]] = {}
        for name in LAYERS:
            layer = self.layer(name)
            repaint_on_new_view(layer, lambda name=name: self._repaint(name))
        #: The legend of the marks this view draws (an HTML widget for the caller to place).
        self.legend = CanvasLegend(self.theme, self.drawing, skill.target, target_label,
                                   marks=("target", "base", "links", "outline", "robot", "velocity"))
        # No wider than the canvas: its entries wrap under it instead of widening the column
        # they share (a stretched canvas would follow the legend's width).
        self.legend.layout.max_width = css_width if css_width and css_width.strip().endswith("px") else f"{width}px"
        self.show(self.draw_background, "background")

    # -- layers -----------------------------------------------------------------------------------
    def layer(self, name: str):
        """The ipycanvas ``Canvas`` of a layer: one of ``LAYERS``."""
        if name not in LAYERS:
            raise ValueError(f"name: expected one of {LAYERS}, got {name!r}")
        return self.canvas[LAYERS.index(name)]

    def show(self, paint: Callable[[object], None] | None, name: str) -> None:
        """Replace a layer's content: clear it and run ``paint(layer)`` in one message.

        ``paint`` is kept and re-run when a new browser view attaches. ``None`` leaves the
        layer empty.
        """
        self._painters[name] = paint
        self._repaint(name)

    def remember(self, paint: Callable[[object], None] | None, name: str) -> None:
        """Record what a layer shows without drawing it (the caller has just drawn it,
        e.g. the last frame of an animation)."""
        self._painters[name] = paint

    def _repaint(self, name: str) -> None:
        layer = self.layer(name)
        paint = self._painters.get(name)
        with drawing_batch():
            layer.clear()
            if paint is not None:
                paint(layer)

    def repaint(self) -> None:
        """Redraw every layer from the recorded painters (one message)."""
        with drawing_batch():
            for name in LAYERS:
                self._repaint(name)

    # -- what the background shows ---------------------------------------------------------------------
    def draw_background(self, canvas) -> None:
        """Grid, axes with tick labels in ``skill.units``, the target and the arrow scale bar."""
        t, theme = self.transform, self.theme
        canvas.fill_style = theme.background
        canvas.fill_rect(0, 0, t.width, t.height)
        (x0, x1), (y0, y1) = t.xlim, t.ylim
        xs, ys = nice_ticks(x0, x1), nice_ticks(y0, y1)
        canvas.stroke_style = theme.grid
        canvas.line_width = 1.0
        for x in xs:
            (a, b), (c, d) = t.to_pixel([[x, y0], [x, y1]])
            canvas.stroke_line(a, b, c, d)
        for y in ys:
            (a, b), (c, d) = t.to_pixel([[x0, y], [x1, y]])
            canvas.stroke_line(a, b, c, d)
        canvas.stroke_style = theme.axes
        (a, b), (c, d) = t.to_pixel([[x0, y0], [x1, y1]])
        canvas.stroke_rect(a, d, c - a, b - d)
        canvas.fill_style = theme.text
        canvas.font = self._font(TICK_FONT_PX)
        canvas.text_align = "center"
        canvas.text_baseline = "top"
        for x in xs:
            px, py = t.to_pixel([x, y0])
            canvas.fill_text(f"{x:g}", px, py + 4)
        canvas.text_align = "right"
        canvas.text_baseline = "middle"
        for y in ys:
            px, py = t.to_pixel([x0, y])
            # 5 px clear of the plot's left edge, beside the uArm's base dot (radius 4) at y = 0,
            # and still inside the 34 px margin for "-0.5" in 16 px text (a CSS-scaled canvas).
            canvas.fill_text(f"{y:g}", px - 5, py)
        canvas.text_align = "left"
        canvas.text_baseline = "top"
        canvas.fill_text(f"positions in {self.drawing.units}", 4, 4)
        self._draw_workspace_outline(canvas)
        self._draw_target(canvas)
        self._draw_scale_bar(canvas)

    def _font(self, css_px: float) -> str:
        return f"{round(css_px * self.text_scale)}px sans-serif"

    def _draw_workspace_outline(self, canvas) -> None:
        outline = self.drawing.outline
        t = self.transform
        if outline:
            # Where the plant can be (the uArm's reachable sector), so the user sees where states
            # and motions can be.
            canvas.stroke_style = self.theme.axes
            canvas.line_width = 1.0
            canvas.set_line_dash([3.0, 3.0])
            for line in outline:
                pixels = np.round(t.to_pixel(line), 1).tolist()
                canvas.begin_path()
                canvas.move_to(*pixels[0])
                for point in pixels[1:]:
                    canvas.line_to(*point)
                canvas.stroke()
            canvas.set_line_dash([])
        self.painter.draw_base(canvas, t, self.theme)

    def _draw_target(self, canvas) -> None:
        shape = self.skill.target_shape()
        if shape is None:
            return
        t, theme = self.transform, self.theme
        canvas.stroke_style = theme.target
        canvas.fill_style = theme.target
        canvas.line_width = 2.5
        label_at = t.to_pixel(shape.label_at)
        if shape.is_point:
            x, y = t.to_pixel(shape.points[0])
            canvas.fill_circle(float(x), float(y), 7.0)
        elif len(shape.points) >= 2:
            pixels = t.to_pixel(shape.points)
            if len(pixels) == 2:
                (a, b), (c, d) = pixels
                canvas.stroke_line(float(a), float(b), float(c), float(d))
            else:
                canvas.stroke_lines(np.round(pixels, 1).tolist())
        if self.target_label:
            canvas.font = self._font(LABEL_FONT_PX)
            canvas.text_align = "left"
            canvas.text_baseline = "bottom"
            canvas.fill_text(self.target_label, float(label_at[0]) + 9, float(label_at[1]) - 6)

    def _draw_scale_bar(self, canvas) -> None:
        t = self.transform
        step = t.nice_action_step()
        length = step * t.pixels_per_action
        # Top right, above the plot area: clear of the tick labels along the bottom.
        x, y = t.width - 12 - length, 22
        canvas.stroke_style = self.theme.text
        canvas.line_width = 2.0
        canvas.stroke_line(x, y, x + length, y)
        canvas.stroke_line(x, y - 4, x, y + 4)
        canvas.stroke_line(x + length, y - 4, x + length, y + 4)
        canvas.fill_style = self.theme.text
        canvas.font = self._font(TICK_FONT_PX)
        canvas.text_align = "right"
        canvas.text_baseline = "bottom"
        canvas.fill_text(f"arrows: {step:g} {self.drawing.action_units}", t.width - 12, y - 5)

    @property
    def scale_text(self) -> str:
        """The arrow scale in words, e.g. "1 N = 42 px (0.0238 N per pixel)"."""
        per_pixel = 1.0 / self.transform.pixels_per_action
        units = self.drawing.action_units
        return f"1 {units} = {self.transform.pixels_per_action:.0f} px ({per_pixel:.3g} {units} per pixel)"

    # -- the robot -----------------------------------------------------------------------------------
    def show_state(self, state, show_velocity: bool = True) -> None:
        """Draw the robot in ``state`` (shape (state_dim,)) on the robot layer."""
        state = np.array(state, dtype=float)
        if state.shape != (self.skill.state_dim,):
            raise ValueError(f"state: expected shape ({self.skill.state_dim},), got {state.shape}")
        show_velocity = as_bool("show_velocity", show_velocity)
        self.show(lambda c: self.painter.draw_state(c, self.transform, self.theme, state, show_velocity), "robot")

    def end_effector_pixel(self, state) -> np.ndarray:
        """Pixel (2,) of the end-effector in ``state``."""
        position, _ = self.painter.end_effector(state)
        return self.transform.to_pixel(position)
