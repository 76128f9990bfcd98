"""Every shipped participant text names colours and marks as they are drawn, in every shipped theme.

A text that says "the blue arrow" is true in one theme and false in another (the velocity arrow
is green in the default theme and blue in the paper's; the participant's own arrow is blue in
the default theme): a colour word must name the same mark in every theme, a dot must be the
marker the robot is drawn with, and "thin", "dashed" or "solid" must hold for that arrow in
every theme. The themes' names for their colours come from mt_widgets/widgets/theme.py."""

import re

import pytest

from mt_widgets.study import BUILTIN_PROTOCOLS, load_protocol
from mt_widgets.widgets.theme import COLOR_NAMES, OKABE_ITO, THEMES

ARROWS = ("user_arrow", "optimal_arrow", "velocity_arrow", "rubber_band")
MARKS = ("target", "end_effector", "state_dot", "ghost", "trail", "arm")
#: Every colour word a text could use: the themes' own names, their parts ("dark green" -> green)
#: and the palette's names.
COLOUR_WORDS = sorted({word for name in COLOR_NAMES.values() for word in [name, *name.split()]}
                      | {name.replace("_", " ") for name in OKABE_ITO} | {"gray", "purple", "white"},
                      key=len, reverse=True)
COLOUR = re.compile(r"\b(" + "|".join(re.escape(w) for w in COLOUR_WORDS) + r")\b[\s-]+(\w+)", re.IGNORECASE)


def participant_texts(protocol) -> list[str]:
    texts = []
    for session in protocol.sessions:
        texts += [v for v in (session.texts or {}).values()]
        texts += [phase.instructions for phase in session.phases]
        for step in session.steps:
            texts += [step.title, step.text] + [item.prompt for item in step.items]
    texts += list(protocol.texts.values()) + [protocol.practice.text]
    return [t for t in texts if t]


def marker_role(protocol) -> str:
    drawing = protocol.skill(protocol.phases[0].skill).plant.drawing()
    return "end_effector" if drawing.marker == "hand" else "state_dot"


@pytest.mark.parametrize("name", sorted(BUILTIN_PROTOCOLS))
def test_colour_words_name_the_same_mark_in_every_theme(name):
    protocol = load_protocol(name)
    for text in participant_texts(protocol):
        for match in COLOUR.finditer(text):
            colour, noun = match.group(1).lower(), match.group(2).lower()
            roles = ARROWS if noun.startswith("arrow") else (
                (marker_role(protocol),) if noun in ("dot", "marker") else MARKS)
            drawn = [role for role in roles
                     if all(colour in (theme.color_name(role) or "").split() + [theme.color_name(role)]
                            for theme in THEMES.values())]
            assert drawn, (f"{name}: {match.group(0)!r} in {text.strip()[:80]!r}...: no {noun} is drawn "
                           f"{colour} in every theme ({', '.join(THEMES)})")


@pytest.mark.parametrize("name", sorted(BUILTIN_PROTOCOLS))
def test_arrow_shapes_named_in_texts_hold_in_every_theme(name):
    words = " ".join(participant_texts(load_protocol(name))).lower()
    for theme in THEMES.values():
        if "thin arrow" in words:
            assert theme.velocity_arrow.width < min(theme.user_arrow.width, theme.optimal_arrow.width), theme.name
        if "dashed" in words:
            assert theme.optimal_arrow.dash, f"{theme.name} draws the optimal arrow solid, a text says dashed"
        if "solid" in words:
            assert not theme.user_arrow.dash, theme.name


def test_the_simulation_text_describes_the_velocity_as_drawn():
    text = load_protocol("paper-sim").texts["instructions"]
    assert "blue arrow" not in text and "(the thin arrow)" in text


def test_the_check_would_catch_the_old_blue_arrow():
    old = "how it is moving (the blue arrow)"
    match = COLOUR.search(old)
    assert match and match.group(1) == "blue"
    assert not [role for role in ARROWS if all(t.color_name(role) == "blue" for t in THEMES.values())]
    # ... while a dot drawn black in every theme passes (the uArm's marker).
    assert all(t.color_name("state_dot") == "black" for t in THEMES.values())
