"""The online study page's arrivals, turned away by the server before any kernel starts.

deploy/voila/voila.py installs this. A request for an online study page (``GATED_PAGES``) whose
link names no usable participant, or that comes from a new participant while the server is at
its configured capacity (mt_widgets/apps/study/arrival.py decides, with the protocol and study
folder the page itself would use), is answered here with a plain page in words: 400 for an
unusable link, 503 with Retry-After while busy. No kernel starts, the preheated spare stays in
its pool for the next participant, and nothing is written. Every other request goes on to
Voila's own handler unchanged; the page's kernel checks the same again (a server run without this
configuration still turns them away, after starting a kernel).

Why a handler and not Voila's ``prelaunch_hook``: Voila 0.5 refuses to start with both
``prelaunch_hook`` and ``preheat_kernel`` (voila/app.py, "incompatible"), and the hook runs
inside the notebook renderer, after the response has begun, with no way to end the request
with a page of its own. Voila 0.5 builds its render route with the class named
``TornadoVoilaHandler`` in ``voila.app`` when the server starts (``Voila.init_handlers``), after
reading this configuration; ``install`` puts the subclass below under that name. pyproject.toml
pins Voila below 0.6, and tests/browser_study/test_arrival_gate.py fails if the gate no longer
answers first.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import tornado.web
import voila.app
from voila.tornado.handler import TornadoVoilaHandler

from mt_widgets.apps.study import default_log_folder
from mt_widgets.apps.study.arrival import arrival_or_refusal, served_protocol, turned_away_page
from mt_widgets.apps.study.capacity import Capacity
from mt_widgets.apps.study.online import parse_query
from mt_widgets.study import ProtocolError, load_protocol

#: The pages whose arrivals the server checks (file names of the served notebooks).
GATED_PAGES = ("study_online.ipynb",)

_log = logging.getLogger("Voila")
_protocols: dict = {}


def _online_settings(protocol: str):
    """The protocol's [online] settings, read again only when its file changed."""
    path = Path(protocol)
    key = (protocol, path.stat().st_mtime_ns if path.is_file() else None)
    if key not in _protocols:
        _protocols.clear()
        _protocols[key] = load_protocol(protocol).online
    return _protocols[key]


class ArrivalGateHandler(TornadoVoilaHandler):
    """Voila's render handler, which first turns away the arrivals an online page would refuse."""

    @tornado.web.authenticated
    async def get(self, path=None):
        notebook = self.notebook_path or path
        if notebook and Path(notebook).name in GATED_PAGES:
            turned = self._turned_away(notebook)
            if turned is not None:
                self.set_status(503 if turned.busy else 400)
                if turned.busy:
                    self.set_header("Retry-After", str(turned.retry_after_s))
                self.set_header("Content-Type", "text/html; charset=UTF-8")
                self.set_header("Cache-Control", "no-store")
                self.finish(turned_away_page(turned))
                return
        await super().get(path)

    def _turned_away(self, notebook: str):
        root = getattr(self.settings.get("voila"), "root_dir", None) or os.getcwd()
        folder = (Path(root) / notebook).parent
        try:
            online = _online_settings(served_protocol(folder))
        except (ProtocolError, OSError, ValueError) as error:
            # The page's kernel shows the protocol's error to the experimenter's log and the page.
            _log.warning("arrival gate: the online page's protocol cannot be read (%s); the page decides", error)
            return None
        if online is None:
            return None
        _, turned = arrival_or_refusal(online, default_log_folder("online"), parse_query(self.request.query),
                                       Capacity.from_environment())
        return turned


def install() -> None:
    """Makes Voila's render route use ``ArrivalGateHandler`` (call before the server starts)."""
    if not issubclass(ArrivalGateHandler, voila.app.TornadoVoilaHandler):
        raise RuntimeError("arrival gate: Voila's render handler is not the one this gate extends "
                           f"({voila.app.TornadoVoilaHandler!r}); check the Voila version pinned in pyproject.toml")
    voila.app.TornadoVoilaHandler = ArrivalGateHandler
