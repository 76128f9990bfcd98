"""Guidance in words and a legend: how the user's arrow differs from the optimal one.

The optimal arrows themselves come from ``mt_widgets.core.optimal_actions`` and the
comparison from ``mt_widgets.core.action_difference``; this module only phrases them.
"""

from __future__ import annotations

import math

import numpy as np
from ipywidgets import HTML
from ipywidgets.widgets.widget_string import HTMLStyle

from mt_widgets.core import action_difference
from mt_widgets.core.validation import as_bool

from .looks import shared_style
from .theme import ArrowStyle, Theme


def _legend_line(style: ArrowStyle) -> str:
    dash = " ".join(f"{d:g}" for d in style.dash) if style.dash else "none"
    return (f"<svg width='46' height='12' style='vertical-align:middle'><line x1='2' y1='6' x2='36' y2='6' "
            f"stroke='{style.color}' stroke-width='{style.width}' stroke-dasharray='{dash}'/>"
            f"<polygon points='44,6 34,1 34,11' fill='{style.color}'/></svg>")


def legend_html(theme: Theme) -> str:
    """The two arrows' legend: colour and line style side by side with their meaning."""
    return (f"{_legend_line(theme.user_arrow)} {theme.legend_user} &nbsp; "
            f"{_legend_line(theme.optimal_arrow)} {theme.legend_optimal}")


def explain_difference(action, optimal, units: str) -> str:
    """One or two sentences on how ``action`` (2,) differs from ``optimal`` (2,), in ``units``."""
    action = np.asarray(action, dtype=float)
    optimal = np.asarray(optimal, dtype=float)
    size, best = float(np.hypot(*action)), float(np.hypot(*optimal))
    if best < 1e-9:
        return (f"Here the best action is (almost) no push at all; yours is {size:.2f} {units}. "
                f"Aim for a shorter arrow.")
    difference = action_difference(action, optimal)
    angle = difference.angle_deg
    if size < 1e-9:
        direction = "You gave no push."
    elif abs(angle) < 5:
        # Said as the angle off, never "within 0 degrees": below half a degree it rounds to 0.
        off = abs(angle)
        direction = ("Direction: good (less than 1&deg; off)." if off < 0.5
                     else f"Direction: good ({off:.0f}&deg; off).")
    else:
        turn = "clockwise" if angle > 0 else "anticlockwise"
        direction = f"Direction: {abs(angle):.0f}&deg; off; turn your arrow {turn}."
    ratio = difference.magnitude_ratio
    if math.isfinite(ratio) and abs(ratio - 1.0) <= 0.1:
        magnitude = f"Size: good ({size:.2f} vs {best:.2f} {units})."
    else:
        word = "too long" if ratio > 1 else "too short"
        magnitude = (f"Size: {size:.2f} {units}, the optimal is {best:.2f} {units} "
                     f"({abs(ratio - 1.0) * 100:.0f}% {word}).")
    return f"{direction} {magnitude} Off by |u &minus; u&#772;| = {difference.error:.2f} {units}."


class GuidancePanel(HTML):
    """Shows the explanation in words after each demonstration (when guidance is on)."""

    def __init__(self, theme: Theme, units: str):
        self.theme = theme
        self.units = units
        super().__init__(value="", style=shared_style(HTMLStyle))   # a layout of its own, the shared style

    def show(self, action, optimal, exact: bool = True, legend: bool = True) -> None:
        """Explain the difference between ``action`` and ``optimal`` (both (2,)); ``legend``: with the
        two arrows' legend (when the arrows are drawn too)."""
        note = "" if as_bool("exact", exact) else ("<br><small>With fewer query states than features no "
                                                   "demonstration teaches the "
                                 "skill exactly; the optimal arrow is the least-error one.</small>")
        self.value = (f"<div>{legend_html(self.theme) if as_bool('legend', legend) else ''}</div>"
                      f"<div style='margin-top:4px'>{explain_difference(action, optimal, self.units)}</div>{note}")

    def hide(self) -> None:
        self.value = ""
