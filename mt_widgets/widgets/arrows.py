"""Arrow rendering: the one function every view uses to draw an action or a velocity."""

from __future__ import annotations

import math

from .theme import ArrowStyle


def draw_arrow(canvas, start, end, style: ArrowStyle) -> bool:
    """Draw an arrow from pixel ``start`` to pixel ``end`` on an ipycanvas ``Canvas``.

    The head is a filled triangle (always solid, so a dashed arrow still shows its
    direction); arrows shorter than 2 pixels draw only a dot, because a zero action has
    no direction to show.

    Args:
        canvas: The ipycanvas Canvas (one layer) to draw on.
        start: (x, y) pixel of the tail.
        end: (x, y) pixel of the tip.
        style: Colour, width, dash pattern, head length and opacity.

    Returns:
        True if a full arrow was drawn, False if only the dot (arrow too short).
    """
    x0, y0 = float(start[0]), float(start[1])
    x1, y1 = float(end[0]), float(end[1])
    length = math.hypot(x1 - x0, y1 - y0)
    canvas.global_alpha = style.alpha
    canvas.fill_style = style.color
    canvas.stroke_style = style.color
    if length < 2.0:
        canvas.fill_circle(round(x0, 1), round(y0, 1), style.width)
        canvas.global_alpha = 1.0
        return False
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    head = min(style.head, 0.6 * length)
    # The shaft stops at the base of the head so a thick line does not poke through the tip.
    bx, by = x1 - ux * head * 0.9, y1 - uy * head * 0.9
    half = head * 0.45
    # Head: tip plus two corners perpendicular to the shaft.
    left = (x1 - ux * head - uy * half, y1 - uy * head + ux * half)
    right = (x1 - ux * head + uy * half, y1 - uy * head - ux * half)
    canvas.line_cap = "round"
    if style.outline:
        # The outline first, a little wider, dashed like the shaft: the arrow over it keeps a
        # light edge, while an arrow beneath still shows through the dash gaps.
        canvas.stroke_style = style.outline
        canvas.line_width = style.width + 2 * style.outline_width
        canvas.set_line_dash(list(style.dash))
        _shaft(canvas, x0, y0, bx, by)
        canvas.set_line_dash([])
        canvas.line_width = 2 * style.outline_width
        canvas.line_join = "round"
        _head(canvas, (x1, y1), left, right)
        canvas.stroke()
        canvas.stroke_style = style.color
    canvas.line_width = style.width
    canvas.set_line_dash(list(style.dash))
    _shaft(canvas, x0, y0, bx, by)
    canvas.set_line_dash([])
    _head(canvas, (x1, y1), left, right)
    canvas.fill()
    canvas.global_alpha = 1.0
    return True


def _shaft(canvas, x0, y0, x1, y1) -> None:
    canvas.begin_path()
    canvas.move_to(round(x0, 1), round(y0, 1))
    canvas.line_to(round(x1, 1), round(y1, 1))
    canvas.stroke()


def _head(canvas, tip, left, right) -> None:
    """Outline the head's triangle as the current path (the caller fills or strokes it)."""
    canvas.begin_path()
    canvas.move_to(round(tip[0], 1), round(tip[1], 1))
    canvas.line_to(round(left[0], 1), round(left[1], 1))
    canvas.line_to(round(right[0], 1), round(right[1], 1))
    canvas.close_path()


def visible_tip(start, tip, shortest: float):
    """The tip of an arrow from ``start`` drawn at least ``shortest`` pixels long, in its own direction.

    An action of a few pixels (a small optimal action at a coarse scale) would sit under the hand's
    dot; drawn at ``shortest`` it shows which way it points, and the caller says its true size in
    words. An arrow under half a pixel has no direction to show and is left as it is.

    Returns:
        (tip, lengthened): the (x, y) pixel to draw to, and whether it differs from ``tip``.
    """
    x0, y0 = float(start[0]), float(start[1])
    dx, dy = float(tip[0]) - x0, float(tip[1]) - y0
    length = math.hypot(dx, dy)
    if length >= shortest or length < 0.5:
        return (float(tip[0]), float(tip[1])), False
    return (x0 + dx / length * shortest, y0 + dy / length * shortest), True


#: Arrows closer in direction than this (degrees) are drawn side by side, not on top of each other.
ALIGNED_DEG = 10.0


def side_offset(user_style: ArrowStyle, optimal_style: ArrowStyle) -> float:
    """Pixels an aligned optimal arrow is moved sideways: the two shafts' half-widths, its
    outline, and a pixel and a half of daylight between them."""
    return (user_style.width + optimal_style.width) / 2 + optimal_style.outline_width + 1.5


def draw_arrow_pair(canvas, start, user_tip, optimal_tip, user_style: ArrowStyle,
                    optimal_style: ArrowStyle) -> float:
    """Draw the user's arrow and the optimal one from the same pixel ``start``, both visible.

    The optimal arrow is drawn last (dashed and outlined, it shows over the user's), and when
    the two point within ``ALIGNED_DEG`` of each other it is moved sideways by about the two
    shafts' half-widths, so that neither hides the other whichever is shorter: the two read as
    two parallel arrows from the hand.

    Args:
        canvas: the layer to draw on.
        start: (x, y) pixel of both tails (the end-effector).
        user_tip, optimal_tip: (x, y) pixels of the tips; either may be None (not drawn).
        user_style, optimal_style: their styles.

    Returns:
        The sideways offset of the optimal arrow in pixels (0 when not aligned).
    """
    x0, y0 = float(start[0]), float(start[1])
    offset = 0.0
    shift = (0.0, 0.0)
    if user_tip is not None and optimal_tip is not None:
        ux, uy = float(user_tip[0]) - x0, float(user_tip[1]) - y0
        ox, oy = float(optimal_tip[0]) - x0, float(optimal_tip[1]) - y0
        user_length, optimal_length = math.hypot(ux, uy), math.hypot(ox, oy)
        if user_length >= 2.0 and optimal_length >= 2.0:
            cosine = (ux * ox + uy * oy) / (user_length * optimal_length)
            if cosine >= math.cos(math.radians(ALIGNED_DEG)):
                offset = side_offset(user_style, optimal_style)
                # To the left of the optimal arrow's direction, as the screen shows it.
                shift = (oy / optimal_length * offset, -ox / optimal_length * offset)
    if user_tip is not None:
        draw_arrow(canvas, start, user_tip, user_style)
    if optimal_tip is not None:
        draw_arrow(canvas, (x0 + shift[0], y0 + shift[1]),
                   (float(optimal_tip[0]) + shift[0], float(optimal_tip[1]) + shift[1]), optimal_style)
    return offset
