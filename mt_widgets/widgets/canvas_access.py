"""The teaching canvas for fingers, the keyboard and screen readers: what the browser must do.

(The script names no study word such as "target": a blinded participant's page is checked for
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
the tip of an arrow drawn) in ``CanvasDescription``, a hidden HTML widget beside the canvas that
also holds the canvas's text alternative. A small script carried by that widget (installed once
per page) listens before ipycanvas does (capture phase on the document):

- a single finger landing within a grab zone goes on to ipycanvas, whose touch events reach
  the kernel (``TeachingCanvas`` draws from them); any other touch is stopped before ipycanvas
  sees it, so the browser scrolls or zooms as on any page;
- Tab and Shift+Tab on the canvas are stopped before ipycanvas sees them, so focus moves on;
- the canvas element gets ``role="application"`` and the description as its ``aria-label``; the
  description's container is a polite live region, so a change (a new state, an arrow, the
  guidance) is read out.

A pen or a mouse needs none of this: Chromium sends them as mouse events, which ipycanvas
passes on unchanged. Without the script (a front end that strips it) the canvas behaves as
ipycanvas alone does: the mouse and the typed arrow still work.
"""

from __future__ import annotations

import html
import uuid

from ipywidgets import HTML

#: The smallest grab zone radius for a finger, in CSS pixels (a 48 px target, above the 44 px
#: that touch guidelines ask for); a larger mouse radius is kept.
FINGER_RADIUS_CSS_PX = 24.0
#: The class prefix naming a described canvas element (the rest is its token).
CANVAS_CLASS_PREFIX = "mt-described-"

_SCRIPT = r"""
(function () {
  if (window.mtWidgetsCanvas) { window.mtWidgetsCanvas.sync(); return; }
  var PREFIX = '@PREFIX@', FINGER = @FINGER@;
  var state = {passing: false};
  window.mtWidgetsCanvas = state;
  function tokenOf(canvas) {
    for (var i = 0; i < canvas.classList.length; i++) {
      var name = canvas.classList[i];
      if (name.indexOf(PREFIX) === 0) { return name.slice(PREFIX.length); }
    }
    return null;
  }
  function ours(e) {
    var node = e.composedPath()[0];
    var canvas = node && node.closest ? node.closest('canvas') : null;
    return canvas && tokenOf(canvas) ? canvas : null;
  }
  function describer(token) { return document.querySelector('[data-mt-describes="' + token + '"]'); }
  function onGrabZone(canvas, touch) {
    var d = describer(tokenOf(canvas));
    var zones = d ? d.getAttribute('data-mt-grab') : '';
    var box = canvas.getBoundingClientRect();
    if (!zones || !box.width) { return false; }
    var scale = canvas.width / box.width;
    var x = (touch.clientX - box.left) * scale, y = (touch.clientY - box.top) * scale;
    return zones.split(';').some(function (zone) {
      var z = zone.split(',').map(Number);
      var r = Math.min(z[3], Math.max(z[2], FINGER * scale));
      return Math.hypot(x - z[0], y - z[1]) <= r;
    });
  }
  document.addEventListener('touchstart', function (e) {
    var canvas = ours(e);
    if (!canvas) { return; }
    if (e.touches.length === 1) { state.passing = onGrabZone(canvas, e.touches[0]); }
    if (!state.passing) { e.stopImmediatePropagation(); }
  }, {capture: true, passive: true});
  ['touchmove', 'touchend', 'touchcancel'].forEach(function (type) {
    document.addEventListener(type, function (e) {
      if (!ours(e)) { return; }
      var passing = state.passing;
      if (e.touches.length === 0) { state.passing = false; }
      if (!passing) { e.stopImmediatePropagation(); }
    }, {capture: true, passive: true});
  });
  document.addEventListener('keydown', function (e) {
    if (e.key === 'Tab' && ours(e)) { e.stopImmediatePropagation(); }
  }, true);
  state.sync = function () {
    document.querySelectorAll('[data-mt-describes]').forEach(function (d) {
      var holder = d.parentElement;
      if (holder && holder.getAttribute('aria-live') !== 'polite') { holder.setAttribute('aria-live', 'polite'); }
      var text = d.textContent;
      document.querySelectorAll('canvas.' + PREFIX + d.getAttribute('data-mt-describes')).forEach(function (c) {
        if (c.getAttribute('aria-label') !== text) {
          c.setAttribute('role', 'application');
          c.setAttribute('aria-roledescription', 'teaching canvas');
          c.setAttribute('aria-label', text);
        }
      });
    });
  };
  new MutationObserver(state.sync).observe(document.body, {childList: true, subtree: true, characterData: true});
  state.sync();
})();
""".replace("@PREFIX@", CANVAS_CLASS_PREFIX).replace("@FINGER@", f"{FINGER_RADIUS_CSS_PX:g}")

#: Visible focus on every control of a page marked ``mt-focus`` (ipywidgets' own is a thin line
#: the colour of a border), drawn inside the control: the widgets' boxes clip what is outside
#: (an outline around the canvas was invisible); and the visually hidden description.
_STYLE = """<style>
.mt-focus :focus-visible {outline: 3px solid #0072B2 !important; outline-offset: -3px !important}
.mt-visually-hidden {position: absolute !important; width: 1px !important; height: 1px !important;
  overflow: hidden !important; clip: rect(0 0 0 0) !important; white-space: nowrap !important; margin: 0 !important}
</style>"""

#: The script rides on an image that cannot load (an HTML widget's ``<script>`` elements do not run).
_LOADER = f'<img alt="" src="data:," style="display:none" onerror="{html.escape(_SCRIPT, quote=True)}">'


class CanvasDescription(HTML):
    """The canvas's text alternative and grab zones, for the script above (a hidden widget).

    Args:
        canvas: the ipycanvas ``Canvas`` or ``MultiCanvas`` described; it gets the class that
            links it to this description.
    """

    def __init__(self, canvas):
        #: Links the canvas element and this description on the page.
        self.token = uuid.uuid4().hex[:12]
        canvas.add_class(CANVAS_CLASS_PREFIX + self.token)
        self.text = ""
        #: (x, y, mouse radius, touch radius) in canvas pixels, where a press starts a drag.
        self.grab_zones: tuple[tuple[float, float, float, float], ...] = ()
        super().__init__(value="")
        self.add_class("mt-visually-hidden")

    def update(self, text: str, grab_zones=()) -> None:
        """Set the words a screen reader reads and where a finger starts a drag (one message, if changed)."""
        zones = tuple(tuple(round(float(v), 1) for v in zone) for zone in grab_zones)
        if text == self.text and zones == self.grab_zones:
            return
        self.text, self.grab_zones = text, zones
        data = ";".join(",".join(f"{v:g}" for v in zone) for zone in zones)
        self.value = (f"{_STYLE}{_LOADER}<div data-mt-describes=\"{self.token}\" data-mt-grab=\"{data}\">"
                      f"{html.escape(text)}</div>")
