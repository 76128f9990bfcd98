"""Who may not start now: an online arrival turned away in words, before anything is recorded.

One decision, taken in two places with the same words: by the server in front of the page
(``deploy/voila/arrival_gate.py``: the participant gets a plain HTML page and no kernel starts)
and by the page itself (``OnlineStudyPage``, when the page is served without that gate). An
arrival is turned away when

- the link does not name a usable participant (no ID, a malformed or over-long one: the
  protocol's ``[online]`` table, ``mt_widgets.study.online``), or
- the server is at its configured capacity and the participant is new (``capacity.py``; an
  enrolled participant always gets their page back).

Either way nothing is written: the study folder is only read. The words end with the protocol's
``return_url`` when it has one (Prolific asks a participant who cannot take part to return their
submission on Prolific, which they do on Prolific's own pages).
"""

from __future__ import annotations

import html
import os
from dataclasses import dataclass
from pathlib import Path

from mt_widgets.study import ParticipantIdError
from mt_widgets.study.online import OnlineSettings, UrlArrival

from .capacity import ACTIVE_S, Capacity

#: The environment variable naming the online page's protocol (notebooks/study_online.ipynb).
PROTOCOL_VARIABLE = "MT_WIDGETS_STUDY_PROTOCOL"
#: The online page's protocol when the variable is unset: the pilot beside the page.
DEFAULT_PROTOCOL = "study_online_pilot.toml"


@dataclass(frozen=True)
class TurnedAway:
    """Why an arrival cannot start now, in words for them.

    Attributes:
        words: what the participant reads (what is wrong, what to do, that nothing was recorded).
        busy: True when the server is at capacity (come back later), False for an unusable link.
        return_url: where they give their place back (the protocol's ``[online].return_url``), or None.
    """

    words: str
    busy: bool
    return_url: str | None = None

    @property
    def retry_after_s(self) -> int | None:
        """Seconds after which a busy server may have room again (None for a bad link)."""
        return round(ACTIVE_S) if self.busy else None


def served_protocol(page_folder) -> str:
    """The protocol the online page serves: ``$MT_WIDGETS_STUDY_PROTOCOL``, else the pilot; a
    relative file name is read beside the page, as the page's kernel (started there) reads it."""
    value = os.environ.get(PROTOCOL_VARIABLE, "").strip() or DEFAULT_PROTOCOL
    beside = Path(page_folder) / value
    return str(beside) if not Path(value).is_absolute() and beside.is_file() else value


def arrival_or_refusal(online: OnlineSettings, log_folder, query: dict,
                       capacity: Capacity) -> tuple[UrlArrival | None, TurnedAway | None]:
    """The participant a link names and may start now, or why not.

    Args:
        online: the protocol's ``[online]`` settings.
        log_folder: the study folder (only read: whether the participant is enrolled, who is active).
        query: the link's parameters, {name: [values]}.
        capacity: the server's configured capacity.

    Returns:
        (arrival, None) when they may start; (None, ``TurnedAway``) when not.
    """
    if not isinstance(online, OnlineSettings):
        raise TypeError(f"online: expected the protocol's OnlineSettings, got {type(online).__name__}")
    if not isinstance(capacity, Capacity):
        raise TypeError(f"capacity: expected a Capacity, got {type(capacity).__name__}")
    try:
        arrival = online.participant_from_url(query)
    except ParticipantIdError as error:
        words = str(error).split(": ", 1)[-1]  # the participant's words; the parameter's name comes first
        return None, TurnedAway(words[:1].upper() + words[1:], False, online.return_url)
    busy = capacity.busy(log_folder, arrival.participant_id)
    if busy is not None:
        return None, TurnedAway(busy, True, online.return_url)
    return arrival, None


def return_link_html(return_url: str | None) -> str:
    """The sentence that offers the pool's page to give the place back ('' without a URL)."""
    if return_url is None:
        return ""
    link = html.escape(return_url, quote=True)
    return (f"<p class='mt-return'>If you cannot take part, please return the study on the website that "
            f"sent you here: <a href='{link}' class='mt-return-link' "
            f"style='color:#0b57d0;text-decoration:underline'>return it here</a>.</p>")


def turned_away_html(turned: TurnedAway) -> str:
    """The words as an HTML fragment (the page's widget and the server's page show the same)."""
    role = "status" if turned.busy else "alert"
    return (f"<div role='{role}' class='mt-turned-away' style='max-width:760px;font-size:1.1em;line-height:1.45'>"
            f"<p>{html.escape(turned.words)}</p>{return_link_html(turned.return_url)}</div>")


def turned_away_page(turned: TurnedAway) -> str:
    """A whole page for a phone or a desktop: the words only, no script, nothing to load."""
    title = "The study is busy" if turned.busy else "This link cannot be used"
    return ("<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>{title}</title></head>"
            "<body style='font-family:system-ui,sans-serif;margin:1.5em;color:#1f1f1f'>"
            f"<main><h1 style='font-size:1.3em'>{title}</h1>{turned_away_html(turned)}</main></body></html>\n")
