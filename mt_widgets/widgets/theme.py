"""Colours and line styles of every view, in one place, and their names for the texts people read.

The default theme uses the Okabe-Ito palette (Okabe & Ito 2008, "Color Universal Design"),
which stays distinguishable under the common colour-vision deficiencies, and it never relies
on colour alone: the optimal (guidance) arrow is dashed and the user's arrow solid. Every text
that names a colour ("the red-orange point marked goal") takes the name from the theme in use
(``Theme.color_name``), so words and picture never disagree. The
paper's screens used two greens (dark: the user's action, light: the guidance on the
simulator; swapped on the uArm screen); those are kept as the ``"paper"`` and ``"paper-uarm"``
themes for replications.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

OKABE_ITO = {
    "black": "#000000",
    "orange": "#E69F00",
    "sky_blue": "#56B4E9",
    "bluish_green": "#009E73",
    "yellow": "#F0E442",
    "blue": "#0072B2",
    "vermillion": "#D55E00",
    "reddish_purple": "#CC79A7",
}


#: Names people use for the colours of the shipped themes (upper-case hex -> name). A theme may
#: add its own in ``Theme.color_names``; a colour without a name is left out of texts.
COLOR_NAMES = {
    "#000000": "black", "#E69F00": "orange", "#56B4E9": "sky-blue", "#009E73": "green", "#F0E442": "yellow",
    "#0072B2": "blue", "#D55E00": "red-orange", "#CC79A7": "pink", "#FF0000": "red", "#FFD700": "yellow",
    "#006400": "dark green", "#7CFC00": "light green", "#1F4FD8": "blue", "#4D4D4D": "grey",
}


@dataclass(frozen=True)
class ArrowStyle:
    """How one kind of arrow looks.

    Args:
        color: CSS colour.
        width: Shaft width in pixels.
        dash: Canvas line-dash pattern in pixels; empty for a solid line.
        head: Length of the arrow head in pixels.
        alpha: Opacity in [0, 1].
        outline: CSS colour of a thin outline around shaft and head, or None: it keeps an
            arrow drawn over another one of a similar colour readable.
        outline_width: Outline width in pixels on each side.
    """

    color: str
    width: float = 3.0
    dash: tuple[float, ...] = ()
    head: float = 12.0
    alpha: float = 1.0
    outline: str | None = None
    outline_width: float = 1.5


@dataclass(frozen=True)
class Theme:
    """Everything a view needs to know about colours."""

    name: str
    background: str = "#FFFFFF"
    grid: str = "#E6E6E6"
    axes: str = "#7F7F7F"
    text: str = "#222222"
    arm: str = "#4D4D4D"
    end_effector: str = OKABE_ITO["yellow"]
    end_effector_outline: str = "#000000"
    state_dot: str = "#000000"
    target: str = OKABE_ITO["vermillion"]
    ghost: str = OKABE_ITO["reddish_purple"]
    ghost_alpha: float = 0.35
    trail: str = OKABE_ITO["sky_blue"]
    diverged: str = OKABE_ITO["vermillion"]
    user_arrow: ArrowStyle = field(default_factory=lambda: ArrowStyle(OKABE_ITO["blue"], 3.5))
    optimal_arrow: ArrowStyle = field(
        default_factory=lambda: ArrowStyle(OKABE_ITO["orange"], 3.5, dash=(9.0, 5.0), outline="#FFFFFF"))
    rubber_band: ArrowStyle = field(
        default_factory=lambda: ArrowStyle(OKABE_ITO["blue"], 2.5, alpha=0.6))
    # Green and thin: told apart from the user's thick blue arrow by hue, width and head size.
    velocity_arrow: ArrowStyle = field(
        default_factory=lambda: ArrowStyle(OKABE_ITO["bluish_green"], 2.0, head=8.0))
    legend_user: str = "your action (solid)"
    legend_optimal: str = "optimal action (dashed)"
    #: Extra colour names of this theme: ("#RRGGBB", "name") pairs (a tuple keeps the theme hashable).
    color_names: tuple[tuple[str, str], ...] = ()

    def color_name(self, role: str) -> str | None:
        """The name of the colour a mark is drawn in ("red-orange"), or None when it has none.

        Args:
            role: a colour field of the theme ("target", "end_effector", "state_dot", ...) or an
                arrow style ("user_arrow", "optimal_arrow", "velocity_arrow").
        """
        value = getattr(self, role, None)
        if isinstance(value, ArrowStyle):
            value = value.color
        if not isinstance(value, str) or not value.startswith("#"):
            raise ValueError(f"role: expected a colour of the theme (e.g. 'target', 'user_arrow'), got {role!r}")
        own = {color.upper(): name for color, name in self.color_names}
        return own.get(value.upper(), COLOR_NAMES.get(value.upper()))

    def target_words(self, target, label: str | None = "goal") -> str:
        """A target in words as drawn in this theme: "the red-orange point marked goal"."""
        return target.describe(self.color_name("target"), label)

    def marker_words(self, drawing) -> str:
        """The robot's end-effector marker in words ("the yellow dot"), from a ``PlantDrawing``."""
        color = self.color_name("end_effector" if drawing.marker == "hand" else "state_dot")
        return f"the {color + ' ' if color else ''}dot"


DEFAULT_THEME = Theme(name="okabe-ito")

PAPER_THEME = replace(
    DEFAULT_THEME,
    name="paper",
    end_effector="#FFD700",
    velocity_arrow=ArrowStyle("#1F4FD8", 2.0, head=9.0),
    user_arrow=ArrowStyle("#006400", 3.5),
    optimal_arrow=ArrowStyle("#7CFC00", 3.5),
    rubber_band=ArrowStyle("#006400", 2.5, alpha=0.6),
    target="#FF0000",
    legend_user="your action (dark green)",
    legend_optimal="optimal action (light green)",
)

PAPER_UARM_THEME = replace(
    PAPER_THEME,
    name="paper-uarm",
    user_arrow=ArrowStyle("#7CFC00", 3.5),
    optimal_arrow=ArrowStyle("#006400", 3.5),
    rubber_band=ArrowStyle("#7CFC00", 2.5, alpha=0.6),
    legend_user="your action (light green)",
    legend_optimal="optimal action (dark green)",
)

THEMES = {theme.name: theme for theme in (DEFAULT_THEME, PAPER_THEME, PAPER_UARM_THEME)}


def fill_words(text: str, **words: str) -> str:
    """``text`` with each ``{name}`` of ``words`` replaced, e.g. ``{target}`` by ``theme.target_words``.

    Only the given names are replaced (plain ``str.replace``, not ``str.format``): a protocol's
    text may hold other braces, and a text without the placeholder is returned as it is.
    """
    for name, value in words.items():
        text = text.replace("{" + name + "}", value)
    return text


def get_theme(theme: Theme | str | None) -> Theme:
    """A Theme from a Theme, a theme name (``"okabe-ito"``, ``"paper"``, ``"paper-uarm"``) or None."""
    if theme is None:
        return DEFAULT_THEME
    if isinstance(theme, Theme):
        return theme
    if isinstance(theme, str) and theme in THEMES:
        return THEMES[theme]
    raise ValueError(f"theme: expected a Theme or one of {sorted(THEMES)}, got {theme!r}")
