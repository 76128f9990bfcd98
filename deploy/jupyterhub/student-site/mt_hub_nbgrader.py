"""nbgrader's student side (assignment list, fetch, submit, feedback, validate), loaded at first use.

A Jupyter server extension for students' servers on the class hub, in place of nbgrader's own
``assignment_list``, ``validate_assignment`` and ``course_list`` extensions
(``student-config/jupyter_server_config.py`` switches those off and this on). nbgrader's handlers
import all of nbgrader's applications (SQLAlchemy, nbconvert's preprocessors, setuptools): about
35 MiB and a second or two of CPU in every student's server at start, measured on this project's
2-core machine, for an assignment panel a student opens now and then. Here the same URLs are
routed to nbgrader's very handlers, which are imported at the first request to one of them;
a server nobody asks for an assignment never pays.

Routes what nbgrader's two student extensions register (``/assignments``,
``/assignments/<action>``, ``/assignments/validate``, ``/courses``, ``/nbgrader_version``) with the
settings their loaders set (``assignment_list_manager``, ``root_dir``). ``/formgraders`` (the
course list) is the instructors': their servers load nbgrader's extensions as they are.
"""

from __future__ import annotations

import threading

from jupyter_server.utils import url_path_join
from tornado.routing import PathMatches, Router

#: Every path nbgrader's student extensions serve, below the server's base URL.
PATHS = r"(?:assignments|courses|nbgrader_version)(?:/.*)?"


class LazyNbgraderRouter(Router):
    """Finds nbgrader's handler for a request, importing nbgrader's handlers the first time."""

    #: Jupyter's server checks that every handler it is given authenticates each method; this
    #: router is no handler: the check runs on nbgrader's handlers when they are loaded (``_load``).
    SUPPORTED_METHODS = ()

    def __init__(self, serverapp):
        self.serverapp = serverapp
        self._routes = None
        self._loading = threading.Lock()

    def _load(self) -> list:
        from nbgrader.server_extensions.assignment_list import handlers as assignment_list
        from nbgrader.server_extensions.validate_assignment import handlers as validate_assignment

        webapp = self.serverapp.web_app
        # What nbgrader's own loaders set up (nbgrader/server_extensions/*/handlers.py), without
        # adding their handlers a second time.
        manager = assignment_list.AssignmentList(parent=self.serverapp)
        manager.root_dir = self.serverapp.root_dir
        webapp.settings["assignment_list_manager"] = manager
        webapp.settings["root_dir"] = self.serverapp.root_dir
        base_url = webapp.settings["base_url"]
        routes = []
        # validate first: "/assignments/validate" before the "/assignments/<action>" pattern.
        for pattern, handler, *options in [*validate_assignment.default_handlers, *assignment_list.default_handlers]:
            routes.append((PathMatches(url_path_join(base_url, pattern)), handler, options[0] if options else {}))
            check = getattr(webapp, "_check_handler_auth", None)  # jupyter_server >= 2.16
            unauthenticated = check(pattern, handler) if check else []
            if unauthenticated:  # never served: nbgrader's handlers all ask for the user
                raise RuntimeError("nbgrader endpoints without authentication:\n" + "\n".join(unauthenticated))
        self.serverapp.log.info("nbgrader's student handlers loaded at first use")
        return routes

    def find_handler(self, request, **kwargs):
        if self._routes is None:
            with self._loading:
                if self._routes is None:
                    self._routes = self._load()
        for matcher, handler, options in self._routes:
            found = matcher.match(request)
            if found is not None:
                return self.serverapp.web_app.get_handler_delegate(
                    request, handler, options, found.get("path_args", []), found.get("path_kwargs", {}))
        return None  # not one of nbgrader's: the server answers 404


def _jupyter_server_extension_points():
    return [{"module": __name__}]


def _load_jupyter_server_extension(serverapp) -> None:
    base_url = serverapp.web_app.settings["base_url"]
    serverapp.web_app.add_handlers(".*$", [(url_path_join(base_url, PATHS), LazyNbgraderRouter(serverapp))])
