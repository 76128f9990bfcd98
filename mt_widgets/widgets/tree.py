"""The widgets a view owns: what must close with it when it leaves the page for good.

A view's widgets are not all in its ``children``: every widget has a ``layout`` and most a
``style`` (widgets too, each a model in the kernel and in the browser), a MultiCanvas holds its
layers, and a view built of parts keeps some off the page (``EpisodeWidget`` moves its teaching
canvas's pieces to its stage; the ``TeachingCanvas`` box that held them stays an attribute).
So the tree follows a widget's trait values and attributes, and through this package's own
view helpers (an arm view holds its canvas and legend), but never a callback (a callback's
owner, a page or an app, is not the view's), never a trait's class-wide default, and never a
layout or style shared by many widgets (``looks.py``).
"""

from __future__ import annotations

from collections.abc import Iterator

from ipywidgets import Widget

from .looks import is_shared

#: Objects whose attributes are followed besides widgets: this package's view helpers.
_VIEW_MODULES = ("mt_widgets.widgets.",)


def _followed(value) -> bool:
    if is_shared(value):
        return False
    return isinstance(value, (Widget, list, tuple, dict)) or type(value).__module__.startswith(_VIEW_MODULES)


def _own_trait_values(widget: Widget):
    """The widget's trait values (children, layout, style, layers) but a trait's class-wide default:
    one object every instance shares (ipycanvas' canvas manager, a widget of its own behind every
    canvas of the page) is nobody's to close."""
    defaults = _class_defaults(type(widget))
    for name, value in getattr(widget, "_trait_values", {}).items():
        if value is not defaults.get(name, _NONE):
            yield value


_NONE = object()
_DEFAULTS: dict[type, dict] = {}


def _class_defaults(cls: type) -> dict:
    """Each trait's class-wide default value, once per class (``traits()`` is slow)."""
    if cls not in _DEFAULTS:
        _DEFAULTS[cls] = {name: trait.default_value for name, trait in cls.class_traits().items()}
    return _DEFAULTS[cls]


def widget_tree(widget: Widget, shown_only: bool = False) -> Iterator[Widget]:
    """Every widget ``widget`` owns, itself first (each once).

    ``shown_only``: only what it shows (its widget traits: children, layout, style, layers),
    not the parts its attributes hold off the page.
    """
    seen: set[int] = set()
    stack = [widget]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, Widget):
            yield node
            values = list(_own_trait_values(node))
            if not shown_only:   # its attributes, but traitlets' own records (the traits are above)
                values += [value for name, value in vars(node).items() if not name.startswith("_trait")]
        elif isinstance(node, dict):
            values = list(node.values())
        elif isinstance(node, (list, tuple)):
            values = list(node)
        elif shown_only:
            continue
        else:
            values = list(getattr(node, "__dict__", {}).values())
        stack.extend(value for value in values if _followed(value))
