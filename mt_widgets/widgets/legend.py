"""The legend under a canvas: every mark drawn on it, with a small picture and what it means.

Each entry is drawn (as a little SVG) in the colour, width and dash of the theme in use and
named from the plant's drawing and the skill's target, so the legend always matches the
canvas: a novice or a visitor never has to guess what the green arrow or the dashed outline is.
"""

from __future__ import annotations

from ipywidgets import HTML, Layout
from ipywidgets.widgets.widget_string import HTMLStyle

from .looks import shared_style
from .theme import ArrowStyle, Theme

#: Every kind of mark a view may draw, in the order the legend lists them.
MARKS = ("target", "base", "links", "outline", "robot", "velocity", "user_arrow", "optimal_arrow", "ghost",
         "learnt", "diverged")


def _svg(body: str) -> str:
    return f"<svg width='40' height='14' style='vertical-align:middle;flex:none'>{body}</svg>"


def _dash(dash) -> str:
    return " ".join(f"{d:g}" for d in dash) if dash else "none"


def _arrow_svg(style: ArrowStyle) -> str:
    head = min(style.head, 12.0)
    return _svg(f"<line x1='3' y1='7' x2='{38 - head * 0.8:g}' y2='7' stroke='{style.color}' "
                f"stroke-width='{style.width:g}' stroke-dasharray='{_dash(style.dash)}' opacity='{style.alpha:g}'/>"
                f"<polygon points='38,7 {38 - head:g},{7 - head * 0.45:g} {38 - head:g},{7 + head * 0.45:g}' "
                f"fill='{style.color}'/>")


def _line_svg(color: str, width: float, dash=(), opacity: float = 1.0) -> str:
    return _svg(f"<line x1='3' y1='7' x2='37' y2='7' stroke='{color}' stroke-width='{width:g}' "
                f"stroke-dasharray='{_dash(dash)}' opacity='{opacity:g}' stroke-linecap='round'/>")


def _dot_svg(color: str, radius: float, outline: str | None = None) -> str:
    stroke = f" stroke='{outline}' stroke-width='1.5'" if outline else ""
    return _svg(f"<circle cx='20' cy='7' r='{radius:g}' fill='{color}'{stroke}/>")


def _entry(picture: str, words: str) -> str:
    # The words may wrap (a legend is no wider than its canvas); the picture never shrinks.
    return (f"<span class='mt-legend-entry' style='display:inline-flex;align-items:center;gap:4px;"
            f"margin:0 12px 2px 0;max-width:100%'>{picture}<span>{words}</span></span>")


def legend_entries(theme: Theme, drawing, target=None, target_label: str | None = "goal",
                   marks=MARKS) -> list[tuple[str, str]]:
    """(mark, HTML) of each legend entry for ``marks`` (kinds of ``MARKS``), in ``MARKS`` order.

    Args:
        theme: the ``Theme`` the canvas is drawn in.
        drawing: the plant's ``PlantDrawing`` (how its links, base and marker look).
        target: the skill's ``Target`` (its words), or None.
        target_label: the word written beside the target on the canvas.
        marks: which marks the canvas shows.
    """
    unknown = [mark for mark in marks if mark not in MARKS]
    if unknown:
        raise ValueError(f"marks: expected kinds from {MARKS}, got {unknown}")
    entries = []
    for mark in MARKS:
        if mark not in marks:
            continue
        if mark == "target" and target is not None:
            picture = (_dot_svg(theme.target, 5) if target.dimension == 0 else _line_svg(theme.target, 2.5))
            name = f"{target_label}: " if target_label else ""
            entries.append((mark, _entry(picture, f"{name}{target.describe(theme.color_name('target'))} to reach")))
        elif mark == "base" and drawing.base is not None:
            entries.append((mark, _entry(_svg(f"<rect x='12' y='3' width='16' height='9' fill='{theme.arm}'/>"),
                                         "the robot's fixed base")))
        elif mark == "links" and drawing.links == "rigid":
            entries.append((mark, _entry(_line_svg(theme.arm, 7), "the arm (white square: its elbow joint)")))
        elif mark == "links" and drawing.links == "reach":
            entries.append((mark, _entry(_line_svg(theme.axes, 2, (4, 4)), "which way the arm reaches")))
        elif mark == "outline" and drawing.outline:
            entries.append((mark, _entry(_line_svg(theme.axes, 1.5, (3, 3)), "where the arm can reach")))
        elif mark == "robot":
            if drawing.marker == "hand":
                picture, words = _dot_svg(theme.end_effector, 5, theme.end_effector_outline), "the robot's hand"
            else:
                picture, words = _dot_svg(theme.state_dot, 5), "the robot's position"
            entries.append((mark, _entry(picture, f"{words} ({theme.marker_words(drawing)}): drag from it")))
        elif mark == "velocity" and drawing.has_velocity:
            entries.append((mark, _entry(_arrow_svg(theme.velocity_arrow),
                                         f"its velocity ({theme.color_name('velocity_arrow') or 'thin'} arrow)")))
        elif mark == "user_arrow":
            entries.append((mark, _entry(_arrow_svg(theme.user_arrow), theme.legend_user)))
        elif mark == "optimal_arrow":
            entries.append((mark, _entry(_arrow_svg(theme.optimal_arrow), theme.legend_optimal)))
        elif mark == "ghost":
            entries.append((mark, _entry(_line_svg(theme.ghost, 3, (6, 4), max(theme.ghost_alpha, 0.6)),
                                         "the skill's own motion (faint, dashed)")))
        elif mark == "learnt":
            entries.append((mark, _entry(_line_svg(theme.trail, 2), "the path of what the robot learnt")))
        elif mark == "diverged":
            entries.append((mark, _entry(_svg(f"<path d='M14 1 L26 13 M14 13 L26 1' stroke='{theme.diverged}' "
                                              f"stroke-width='3'/>"), "where the learnt skill left its safe range")))
    return entries


class CanvasLegend(HTML):
    """The legend of one canvas; ``show(marks)`` lists the marks the canvas now draws."""

    def __init__(self, theme: Theme, drawing, target=None, target_label: str | None = "goal", marks=()):
        self.theme, self.drawing, self.target, self.target_label = theme, drawing, target, target_label
        self.marks: tuple[str, ...] = ()
        super().__init__(value="", layout=Layout(max_width="100%"), style=shared_style(HTMLStyle))
        self.add_class("mt-canvas-legend")
        self.show(marks)

    def show(self, marks) -> None:
        """List ``marks`` (kinds of ``MARKS``; those this plant does not draw are left out)."""
        entries = legend_entries(self.theme, self.drawing, self.target, self.target_label, tuple(marks))
        self.marks = tuple(mark for mark, _ in entries)
        self.value = ("<div style='display:flex;flex-wrap:wrap;font-size:13px;line-height:1.2'>"
                      + "".join(html for _, html in entries) + "</div>") if entries else ""

    def add(self, *marks: str) -> None:
        self.show(self.marks + marks)

    def remove(self, *marks: str) -> None:
        self.show(tuple(mark for mark in self.marks if mark not in marks))
