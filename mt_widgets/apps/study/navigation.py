"""The page's address: send the participant on (a completion URL), or record where they are.

A Voila page runs no code sent from the kernel, and ipywidgets have no navigation widget: the one
browser action the study pages need is this widget's front end (an anywidget ES module,
``navigation.js`` beside this file). It acts once each time the widget is shown (also when a page
shows it again), so a page shows it only when the address is to change.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import urlencode

import anywidget
import traitlets
from ipywidgets import Layout


class PageAddress(anywidget.AnyWidget):
    """A hidden widget that, once shown, changes the page's address (``go_to``, ``set_address_query``)."""

    _esm = Path(__file__).parent / "navigation.js"
    #: "go": the page goes to ``address`` (a URL); "query": ``address`` (``?...``) replaces the
    #: page's query, without navigating.
    action = traitlets.Enum(("go", "query"), default_value="go").tag(sync=True)
    address = traitlets.Unicode("").tag(sync=True)
    #: How long the page waits before it goes, in milliseconds.
    delay_ms = traitlets.Int(0, min=0).tag(sync=True)

    def __init__(self, action: str, address: str, delay_ms: int = 0):
        super().__init__(action=action, address=address, delay_ms=delay_ms, layout=Layout(display="none"))


def go_to(url: str, delay_s: float = 0.0) -> PageAddress:
    """A widget that, once shown, sends the page to ``url`` after ``delay_s`` seconds."""
    return PageAddress("go", url, max(0, round(delay_s * 1000)))


def set_address_query(parameters: dict) -> PageAddress:
    """A widget that, once shown, puts ``parameters`` in the page's address (no navigation):
    a reload then asks the server for the same page with them (a participant resumed)."""
    return PageAddress("query", "?" + urlencode(parameters))
