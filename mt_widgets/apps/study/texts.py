"""What the participant reads: protocol texts as HTML, answers' problems in plain words, and the
guidance arrow named in the colours it is drawn in."""

from __future__ import annotations

import html
import math

from mt_widgets.widgets import get_theme
from mt_widgets.widgets.legend import legend_entries
from mt_widgets.widgets.theme import fill_words


def paragraphs(text: str) -> str:
    """Protocol text (paragraphs separated by blank lines) as escaped HTML paragraphs."""
    blocks = [" ".join(block.split()) for block in text.strip().split("\n\n") if block.strip()]
    return "".join(f"<p style='max-width:760px;font-size:1.1em;line-height:1.45'>{html.escape(b)}</p>"
                   for b in blocks)


def protocol_text(protocol, theme, text: str, skill: str | None) -> str:
    """Protocol text as HTML, its "{goal}" in the words of what the canvas draws (the skill's
    target in this theme's colours); texts outside a phase name the first phase's target."""
    target = protocol.skills[skill or protocol.phases[0].skill].target
    goal = get_theme(theme).target_words(target, "goal") if target is not None else "the goal"
    return paragraphs(fill_words(text, goal=goal))


def _number(value: float) -> str:
    return f"{value:g}"


def answer_problem(item, answer) -> str | None:
    """What is wrong with ``answer`` to ``item`` in a participant's words, or None if it is fine.

    ``Item.check`` (mt_widgets/study/steps.py) decides; this only says it for a person
    ("Please type your age as a whole number from 18 to 120"), never in the code's words.
    """
    try:
        item.check(answer)
        return None
    except ValueError:
        pass
    prompt = f"\u201c{item.prompt}\u201d"
    if answer is None or (isinstance(answer, str) and not answer.strip()):
        return f"Please choose an answer to {prompt}." if item.kind in ("likert", "choice") else \
            f"Please answer {prompt}."
    if item.kind in ("likert", "choice"):
        return f"Please choose one of the answers offered for {prompt}."
    if item.kind == "number":
        whole = "a whole number" if item.integer else "a number"
        if item.minimum is not None and item.maximum is not None:
            wanted = f"{whole} from {_number(item.minimum)} to {_number(item.maximum)}"
        elif item.minimum is not None:
            wanted = f"{whole} of at least {_number(item.minimum)}"
        elif item.maximum is not None:
            wanted = f"{whole} of at most {_number(item.maximum)}"
        else:
            wanted = whole
        try:
            value = float(str(answer).strip())
            shown = _number(value) if math.isfinite(value) else str(answer).strip()
        except ValueError:
            shown = str(answer).strip()
        return f"For {prompt}, please type {wanted} in digits (you typed {shown[:40]!r})."
    return (f"Your answer to {prompt} is too long: please keep it to {item.max_length} characters "
            f"(it has {len(str(answer))}).")


def guidance_arrow_words(theme) -> str:
    """HTML naming the guidance arrow as drawn in ``theme`` (picture, colour, dash).

    Shown to a participant only where that arrow appears (a guided episode, once it is drawn):
    it says what the mark is, not how the participant's arrow differs from it.
    """
    theme = get_theme(theme)
    style = theme.optimal_arrow
    colour = theme.color_name("optimal_arrow")
    kind = " ".join(word for word in ("dashed" if style.dash else "", colour or "") if word)
    picture = legend_entries(theme, None, marks=("optimal_arrow",))[0][1]
    return (f"<div class='mt-guidance-arrow-note' style='max-width:400px;margin:6px 0'>{picture}"
            f"<div>The {html.escape(kind + ' ' if kind else '')}arrow shows the optimal action in this "
            f"situation, beside the arrow you drew.</div></div>")
