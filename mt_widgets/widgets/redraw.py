"""Robust rendering: batches that survive a new browser view (ipycanvas issue #322).

ipycanvas keeps no drawing state on the kernel side: a browser view that attaches later
(Voila renders the page after the kernel ran the notebook; a JupyterLab page reload)
starts blank. Each canvas model then sends ``client_ready``, but the kernel-side canvas
manager still remembers which canvas it last drew on and skips the ``switchCanvas``
command, while the fresh front-end manager has no current canvas, so the redraw fails
(https://github.com/jupyter-widgets-contrib/ipycanvas/issues/322).

The work-around lives here and nowhere else: every batch starts by forgetting the
manager's current canvas, so each message names its canvas, and every layer repaints
itself when its front-end model (re)appears.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import contextmanager

import ipycanvas
from ipycanvas import hold_canvas

from .pages import PAGES, current_page


def _manager():
    # A private name of ipycanvas 0.14 (pinned below 0.15 in pyproject.toml), read at each use: a
    # kernel forked from a template replaces the manager made at import (mt_widgets/kernels/template.py).
    return ipycanvas.canvas._CANVAS_MANAGER


def forget_current_canvas() -> None:
    """Make the next drawing command start with a ``switchCanvas`` (issue #322)."""
    _manager()._current_canvas = None


@contextmanager
def drawing_batch():
    """Like ``hold_canvas()``, but the message is self-contained: it names its canvas first.

    Nested batches join the outer one (as ``hold_canvas`` does), so a view can call
    painters that open their own batch.
    """
    if _manager()._caching:
        yield
        return
    forget_current_canvas()
    with hold_canvas():
        yield


def repaint_on_new_view(layer, paint: Callable[[], None]) -> None:
    """Call ``paint()`` (inside one batch) whenever a browser view of ``layer`` attaches.

    Args:
        layer: An ipycanvas ``Canvas`` (a MultiCanvas layer); its front-end model sends
            ``client_ready`` when it is created in a page.
        paint: Redraws everything the layer should show, from the widget's current state.
    """
    if not hasattr(layer, "on_client_ready"):
        raise TypeError(f"layer: expected an ipycanvas Canvas, got {type(layer).__name__}")

    def _on_client_ready():
        # The page that made this model shows the kernel's widgets: closes of retired views wait for it.
        PAGES.seen(current_page())
        with drawing_batch():
            paint()

    layer.on_client_ready(_on_client_ready)
