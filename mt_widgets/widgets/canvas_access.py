"""The teaching canvas for fingers, the keyboard and screen readers: what the browser must do.

(The front end names no study word such as "target": a blinded participant's page is checked for
them, tests/study/test_app.py.)

ipycanvas' front end (0.14, ``src/widget.ts``) makes its canvas element focusable and then, on
that element:

- calls ``preventDefault`` on every touch event, so a swipe or a pinch that starts on the
  canvas never scrolls or zooms the page (a phone whose screen is mostly canvas is stuck);
- calls ``preventDefault`` and ``stopPropagation`` on every key, Tab included, so a keyboard
  user who tabs onto the canvas cannot leave it;
- gives the element no text: a screen reader announces an unnamed canvas.

Whether a touch draws or scrolls must be decided when the finger lands (the browser cannot
wait for the kernel). The kernel therefore publishes where a press starts a drag (the hand, and
the tip of an arrow drawn) in ``CanvasDescription``, a hidden widget beside the canvas that also
holds the canvas's text alternative. Its front end (an anywidget ES module,
``canvas_access.js`` beside this file, with its style sheet ``canvas_access.css``) installs
listeners once per page that run before ipycanvas' (capture phase on the document):

- a single finger landing within a grab zone goes on to ipycanvas, whose touch events reach
  the kernel (``TeachingCanvas`` draws from them); any other touch is stopped before ipycanvas
  sees it, so the browser scrolls or zooms as on any page;
- Tab and Shift+Tab on the canvas are stopped before ipycanvas sees them, so focus moves on;
- the canvas element gets ``role="application"`` and the description as its ``aria-label``; the
  description's element is a polite live region, so a change (a new state, an arrow, the
  guidance) is read out.

The canvas element and its description are linked by a class (``CANVAS_CLASS_PREFIX`` and the
description's token) that ``CanvasDescription`` adds to the canvas: the two are separate widgets,
rendered by separate front ends, in whatever order.

A pen or a mouse needs none of this: Chromium sends them as mouse events, which ipycanvas
passes on unchanged. Without the front end (anywidget not loaded) the canvas behaves as
ipycanvas alone does: the mouse and the typed arrow still work.
"""

from __future__ import annotations

import uuid
from pathlib import Path

import anywidget
import traitlets

from .looks import shared_layout

#: The smallest grab zone radius for a finger, in CSS pixels (a 48 px target, above the 44 px
#: that touch guidelines ask for); a larger mouse radius is kept.
FINGER_RADIUS_CSS_PX = 24.0
#: The class prefix naming a described canvas element (the rest is its token).
CANVAS_CLASS_PREFIX = "mt-described-"

_HERE = Path(__file__).parent


class CanvasDescription(anywidget.AnyWidget):
    """The canvas's text alternative and grab zones, for its front end (a hidden widget).

    Args:
        canvas: the ipycanvas ``Canvas`` or ``MultiCanvas`` described; it gets the class that
            links it to this description.
    """

    _esm = _HERE / "canvas_access.js"
    _css = _HERE / "canvas_access.css"
    #: The words a screen reader reads (the canvas's ``aria-label``, and a polite live region).
    text = traitlets.Unicode("").tag(sync=True)
    #: (x, y, mouse radius, touch radius) in canvas pixels, where a press starts a drag.
    grab_zones = traitlets.List(traitlets.List(traitlets.Float())).tag(sync=True)
    #: The class that marks the described canvas element.
    canvas_class = traitlets.Unicode("").tag(sync=True)
    #: The smallest grab zone radius for a finger, in CSS pixels.
    finger_radius_css_px = traitlets.Float(FINGER_RADIUS_CSS_PX).tag(sync=True)

    def __init__(self, canvas):
        #: Links the canvas element and this description on the page.
        self.token = uuid.uuid4().hex[:12]
        canvas.add_class(CANVAS_CLASS_PREFIX + self.token)
        super().__init__(canvas_class=CANVAS_CLASS_PREFIX + self.token, layout=shared_layout())
        self.add_class("mt-visually-hidden")

    def update(self, text: str, grab_zones=()) -> None:
        """Set the words a screen reader reads and where a finger starts a drag (one message, if changed)."""
        zones = [[round(float(v), 1) for v in zone] for zone in grab_zones]
        if text == self.text and zones == self.grab_zones:
            return
        with self.hold_sync():
            self.text, self.grab_zones = text, zones
