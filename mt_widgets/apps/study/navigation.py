"""The page's address: send the participant on (a completion URL), or record where they are.

A Voila page runs no code sent from the kernel, and ipywidgets have no navigation widget; an
HTML widget's markup is inserted as it is, so an image that fails to load (``src="data:,"``)
runs its ``onerror`` handler once, in the page, when the widget is shown (also when a page
shows it again). That is the one browser action the study pages need, kept here.
"""

from __future__ import annotations

import html
import json
from urllib.parse import urlencode

from ipywidgets import HTML, Layout


def _script(code: str) -> HTML:
    handler = html.escape(f"this.remove();{code}", quote=True)
    return HTML(f"<img src='data:,' alt='' style='display:none' onerror=\"{handler}\">",
                layout=Layout(display="none"))


def go_to(url: str, delay_s: float = 0.0) -> HTML:
    """A widget that, once shown, sends the page to ``url`` after ``delay_s`` seconds."""
    return _script(f"setTimeout(function(){{window.location.assign({json.dumps(url)});}}, "
                   f"{max(0, round(delay_s * 1000))});")


def set_address_query(parameters: dict) -> HTML:
    """A widget that, once shown, puts ``parameters`` in the page's address (no navigation):
    a reload then asks the server for the same page with them (a participant resumed)."""
    query = json.dumps("?" + urlencode(parameters))
    return _script(f"history.replaceState(null, '', window.location.pathname + {query});")
