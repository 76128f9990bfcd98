"""Layouts and styles shared by the widgets that never change theirs: one model each per kernel.

ipywidgets gives every widget a ``Layout`` of its own and most widgets a style of their own:
each a widget model that the kernel opens with its whole state, the server relays, and the page
builds before it can draw. A first teaching episode opened 121 models, 48 of them layouts and 23
styles, nearly all left as they were made. On a class hub in a lecture's first minute, or a
kiosk's first view, that is kernel, server and browser time for nothing
(``benchmarks/bench_hub.py``, ``benchmarks/bench_kiosk.py``).

The package's own views therefore build their inner parts (texts, boxes, buttons, canvas layers)
with ``plain``, ``shared_layout`` and ``shared_style``: widgets with the same CSS share one layout,
and widgets of a class share one default style. A widget the package hands out (an
``EpisodeWidget``, a ``TeachingCanvas``, a ``ReproductionPlayer``, a legend) keeps its own, as does
any part whose layout a view changes (a button it hides).

A shared layout or style is frozen: setting one of its traits raises ``TypeError``, since the
change would restyle every widget sharing it (a display of "none" hides them all). Give such a
widget its own: ``widget.layout = Layout(...)``.

Shared ones belong to no view: ``tree.widget_tree`` never yields them, so retiring a view
(``animation.retire``) leaves them open for the next. They are made per kernel, when first asked
for in that kernel's process (a kernel forked from a template, ``mt_widgets/kernels/template.py``,
makes its own: a model opened before the fork has no page).
"""

from __future__ import annotations

import os

from ipycanvas import Canvas, MultiCanvas
from ipycanvas.canvas import _CanvasBase
from ipywidgets import Layout, Widget

__all__ = ["is_shared", "layered_canvas", "plain", "shared_layout", "shared_style"]


class _Frozen:
    """A widget whose synced traits cannot be set after it is made (the shared ones)."""

    _frozen = False

    def __setattr__(self, name, value):
        if self._frozen and not name.startswith("_") and name in self.keys:
            raise TypeError(f"{name}: this {type(self).__mro__[2].__name__} is shared by many widgets "
                            f"(mt_widgets/widgets/looks.py) and cannot change; give the widget its own "
                            f"(widget.layout = Layout(...)) before changing it")
        super().__setattr__(name, value)


_FROZEN_CLASSES: dict[type, type] = {}
#: The shared widgets of this process: (class, values) -> widget. Keyed by process too: a forked
#: kernel must not use a model its template opened.
_SHARED: dict[tuple, Widget] = {}
_SHARED_PID = [os.getpid()]


def _frozen_class(cls: type) -> type:
    if cls not in _FROZEN_CLASSES:
        _FROZEN_CLASSES[cls] = type(f"Shared{cls.__name__}", (_Frozen, cls), {"__module__": __name__})
    return _FROZEN_CLASSES[cls]


def _shared(cls: type, values: dict) -> Widget:
    if _SHARED_PID[0] != os.getpid():
        _SHARED.clear()
        _SHARED_PID[0] = os.getpid()
    for name, value in values.items():
        if not isinstance(value, str):
            raise TypeError(f"{name}: expected a CSS value as a str, got {type(value).__name__}")
    key = (cls, tuple(sorted(values.items())))
    widget = _SHARED.get(key)
    if widget is None or widget.comm is None:   # closed meanwhile (Widget.close_all): a new one
        widget = _frozen_class(cls)(**values)
        widget._frozen = True
        _SHARED[key] = widget
    return widget


def shared_layout(**css: str) -> Layout:
    """The kernel's one frozen ``Layout`` with these CSS values (none: ipywidgets' defaults)."""
    return _shared(Layout, css)


def shared_style(style_class: type, **values: str) -> Widget:
    """The kernel's one frozen style of ``style_class`` (``ButtonStyle``, ``HTMLStyle``, ...) with these values."""
    if not (isinstance(style_class, type) and issubclass(style_class, Widget)):
        raise TypeError(f"style_class: expected an ipywidgets style class, got {style_class!r}")
    return _shared(style_class, values)


_STYLE_CLASSES: dict[type, type | None] = {}


def _style_class(widget_class: type) -> type | None:
    if widget_class not in _STYLE_CLASSES:
        trait = widget_class.class_traits().get("style")
        _STYLE_CLASSES[widget_class] = getattr(trait, "klass", None)
    return _STYLE_CLASSES[widget_class]


def plain(widget_class: type, *args, **kwargs) -> Widget:
    """A ``widget_class`` widget with the kernel's shared default layout and style, unless given.

    For a part of a view whose layout and style never change; ``layout`` or ``style`` given (a
    ``Layout``, a dict, ``shared_layout(...)``) are used as they are.
    """
    if not (isinstance(widget_class, type) and issubclass(widget_class, Widget)):
        raise TypeError(f"widget_class: expected an ipywidgets widget class, got {widget_class!r}")
    if "layout" in widget_class.class_traits():
        kwargs.setdefault("layout", shared_layout())
    style_class = _style_class(widget_class)
    if style_class is not None:
        kwargs.setdefault("style", shared_style(style_class))
    return widget_class(*args, **kwargs)


def is_shared(widget) -> bool:
    """Whether ``widget`` is a shared layout or style (no view's to close)."""
    return isinstance(widget, _Frozen)


class _LayeredCanvas(MultiCanvas):
    """ipycanvas' MultiCanvas whose layers are born at its size with the shared plain layout.

    MultiCanvas makes each layer at ipycanvas' default size with a layout of its own, then resizes
    it: a layout model and two messages a layer for nothing.
    """

    def __init__(self, layers: int, width: int, height: int, **kwargs):
        canvases = [Canvas(width=width, height=height, layout=shared_layout()) for _ in range(layers)]
        # MultiCanvas.__init__ makes its layers itself; the rest of it is this line and the next.
        _CanvasBase.__init__(self, _canvases=canvases, width=width, height=height, **kwargs)
        self.on_msg(self._canvases[-1]._handle_frontend_event)   # the top layer receives the events


def layered_canvas(layers: int, width: int, height: int, **kwargs) -> MultiCanvas:
    """A ``MultiCanvas`` of ``layers`` layers of ``width`` x ``height`` pixels (the top one gets the events)."""
    for name, value in (("layers", layers), ("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name}: expected a positive int, got {value!r}")
    return _LayeredCanvas(layers, width, height, **kwargs)
