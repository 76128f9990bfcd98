"""Voila's pages in a student's server (``/voila/...``), loaded at first use.

A Jupyter server extension for students' servers on the class hub, in place of Voila's own
``voila.server_extension`` (``student-config/jupyter_server_config.py`` switches that off and this
on). Voila's extension imports Voila, nbconvert's exporters and their templates when the server
starts: about 7 MiB in every student's server, measured on this project's 2-core machine (a
server with and without it), for pages a student opens in some lessons only. Here one route
covers every path Voila's extension serves; at the first request to one of them it runs Voila's
own loader, which adds Voila's very handlers to the server as at start, and from then on this
route steps aside and Voila's handlers answer. Authentication is Voila's own: its handlers are
the same classes with the same decorators; jupyter_server checks them when they are added.
"""

from __future__ import annotations

from jupyter_server.utils import url_path_join
from tornado.routing import Router

#: Every path Voila's extension serves, below the server's base URL (voila/server_extension.py:
#: ``/voila``, ``/voila/render/...``, ``/voila/tree/...``, ``/voila/templates/...``,
#: ``/voila/api/...``, ``/voila/static/...``, ``/voila/labextensions/...``, ``/voila/files/...``).
PATHS = r"voila(?:/.*)?"


class LazyVoilaRouter(Router):
    """Loads Voila's extension at the first request to a Voila path, then lets its handlers answer."""

    #: Jupyter's server checks that every handler it is given authenticates each method; this
    #: router is no handler: the check runs on Voila's handlers when its loader adds them.
    SUPPORTED_METHODS = ()

    def __init__(self, serverapp):
        self.serverapp = serverapp
        self.loaded = False

    def find_handler(self, request, **kwargs):
        if self.loaded:
            return None  # Voila's own handlers, added after this route, answer
        # tornado routes on its one event-loop thread: no other request runs the loader meanwhile.
        from voila.server_extension import _load_jupyter_server_extension

        _load_jupyter_server_extension(self.serverapp)
        self.loaded = True
        self.serverapp.log.info("Voila's handlers loaded at first use")
        # Route this first request again: this router now passes it on to Voila's handlers.
        return self.serverapp.web_app.default_router.find_handler(request, **kwargs)


def _jupyter_server_extension_points():
    return [{"module": __name__}]


def _load_jupyter_server_extension(serverapp) -> None:
    base_url = serverapp.web_app.settings["base_url"]
    serverapp.web_app.add_handlers(".*$", [(url_path_join(base_url, PATHS), LazyVoilaRouter(serverapp))])
