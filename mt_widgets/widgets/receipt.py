"""Receipts from the page: the browser says it has drawn every canvas command sent before a point.

ipycanvas' front end runs every canvas command of a page through ONE promise chain (its
``CanvasManagerModel``, ``src/widget.ts``): a message's commands start only once every earlier
message's are done, ``canvas.sleep`` included. After each message, a canvas model with
``sync_image_data`` sends its picture back to the kernel (``syncViews`` then ``syncImageData``).

So a receipt is a one-pixel canvas with ``sync_image_data``, never shown: the kernel paints receipt
number n into its pixel (the colour is the number), and when the page sends that picture back,
every command queued before it has been drawn. A close decided on the kernel's estimate alone
(``animation._Queue``) is wrong for a browser that lags behind it (a phone, a loaded machine), and a
command left for a closed canvas stops the page's whole chain ("widget model not found").

The receipt canvas is made once per kernel, the first time a receipt is asked for. Receipts are
sent only once a page has the canvas (its ``client_ready``); every page that (re)creates it (a
reload) gets a fresh receipt covering all those still awaited, since what the old page held is gone.
With no page (closed, or never opened) nothing answers: callers keep a fallback timeout.

Several pages can show one kernel's widgets at once (one notebook open in two JupyterLab tabs, or
a second window; ``pages.py``): every page runs its own command chain, at its own pace, and every page
sends its own picture back. A receipt is drawn only once EVERY page known to show the widgets has
answered it: closing on the first answer (the fast tab's) would leave the slow tab's queued commands
pointing at a closed canvas, and stop its drawing. A page is known from its first canvas model, not
from the receipt canvas: a lagging tab may make its receipt canvas only after the fast tab has already
answered. A page that is gone (a tab closed, or reloaded: its session never speaks again) cannot say
so; it is dropped when a caller's fallback comes without its answer (``give_up``), so it holds later
closes back at most once.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable

from ipycanvas import Canvas
from ipywidgets.widgets.trait_types import bytes_serialization
from traitlets import Bytes

from .looks import shared_layout
from .pages import PAGES, Pages, current_page
from .redraw import drawing_batch

#: Receipt numbers live in one pixel's 24 colour bits; they wrap around (never near in one session).
_NUMBERS = 1 << 24


def number_colour(number: int) -> str:
    """The CSS colour that encodes receipt ``number`` (its 24 low bits) in a pixel."""
    n = number % _NUMBERS
    return f"rgb({n >> 16 & 255}, {n >> 8 & 255}, {n & 255})"


def png_number(png: bytes) -> int | None:
    """The receipt number in the first pixel of a PNG sent by the page (8-bit RGB or RGBA), else None.

    A one-row, one-pixel image is stored unchanged by every PNG filter (each predicts from
    pixels left of or above it, which are zero), so no filter needs undoing.
    """
    if not png or png[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    pos, header, data = 8, None, b""
    while pos + 8 <= len(png):
        length, kind = struct.unpack(">I4s", png[pos:pos + 8])
        body = png[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = body
        elif kind == b"IDAT":
            data += body
        elif kind == b"IEND":
            break
        pos += 12 + length
    if header is None or len(header) < 10:
        return None
    width, height, depth, colour_type = struct.unpack(">IIBB", header[:10])
    if width != 1 or height != 1 or depth != 8 or colour_type not in (2, 6):
        return None
    try:
        raw = zlib.decompress(data)
    except zlib.error:
        return None
    if len(raw) < 4:
        return None
    return raw[1] << 16 | raw[2] << 8 | raw[3]


class ReceiptCanvas(Canvas):
    """The one-pixel canvas whose picture each page sends back, heard once per page.

    ipywidgets echoes a state sent by one page to every other page (``echo_update``). Echoed, the
    fast tab's picture of receipt n would reach the slow tab's model first, and the slow tab's own
    picture of n, equal to it, would then be no change and never be sent. So this picture is not
    echoed. And two pages' pictures of one receipt are equal bytes, which a trait's observer hears
    once: every picture is read where the page's message arrives (``set_state``), with the page it
    came from.
    """

    image_data = Bytes(default_value=None, allow_none=True, read_only=True).tag(
        sync=True, echo_update=False, **bytes_serialization)

    def __init__(self, on_picture: Callable[[bytes], None], **kwargs):
        super().__init__(**kwargs)
        self._on_picture = on_picture

    def set_state(self, sync_data):
        super().set_state(sync_data)
        picture = sync_data.get("image_data")
        if picture is not None:
            self._on_picture(bytes(picture))


class Receipts:
    """The kernel's receipt canvas and the receipts awaited (one instance per kernel: ``RECEIPTS``)."""

    def __init__(self, pages: Pages = PAGES):
        self.canvas = None
        #: The last receipt number sent (or to be sent once a page has the canvas).
        self.issued = 0
        #: The highest receipt number that every page has answered.
        self.drawn = 0
        #: Whether some page has the receipt canvas (said client_ready).
        self.page_ready = False
        #: The pages known to show the widgets, and the highest receipt number each has answered.
        self.pages = pages
        self.answers: dict[str | None, int] = {}
        self._waiting: list[tuple[int, Callable[[int], None]]] = []

    def _ensure_canvas(self) -> None:
        if self.canvas is not None:
            return
        # Not shown anywhere: its model exists in every page all the same (the widget manager
        # makes a model for every comm), and the command chain runs for it.
        self.canvas = ReceiptCanvas(self._on_picture, width=1, height=1, sync_image_data=True,
                                    layout=shared_layout())
        self.canvas.on_client_ready(self._on_page)

    def request(self, on_drawn: Callable[[int], None]) -> int:
        """Asks the page for a receipt behind everything sent so far; ``on_drawn(n)`` is called once,
        with the number of the receipt that answered (n >= the number returned here)."""
        self._ensure_canvas()
        self.issued += 1
        self._waiting.append((self.issued, on_drawn))
        if self.page_ready:
            self._send(self.issued)
        return self.issued

    def _send(self, number: int) -> None:
        with drawing_batch():
            self.canvas.fill_style = number_colour(number)
            self.canvas.fill_rect(0, 0, 1, 1)

    def _on_page(self) -> None:
        # A page (a first one, or one reloaded: what the old one held is gone) has the receipt
        # canvas: one receipt, sent now, stands for every one awaited.
        # Only its answer counts: an older page's answer says nothing of what this one holds (a
        # retired canvas it repainted on arrival, say).
        self.page_ready = True
        self.pages.seen(current_page())
        if self._waiting:
            self.issued += 1
            self._waiting = [(self.issued, callback) for _, callback in self._waiting]
            self._send(self.issued)

    def _on_picture(self, picture: bytes) -> None:
        number = png_number(picture)
        if number is not None:
            self.answered(number, current_page())

    def answered(self, number: int, page: str | None = None) -> None:
        """``page`` has drawn receipt ``number`` (24 bits): everything queued before it is drawn there.
        Callbacks run once every known page has drawn their receipt."""
        # The full number: the latest issued one with these 24 bits.
        full = self.issued - ((self.issued - number) % _NUMBERS)
        # A page taken as gone that answers is known again.
        self.pages.seen(page)
        self.answers[page] = max(self.answers.get(page, 0), full)
        self._release()

    def give_up(self, number: int) -> None:
        """A caller's fallback came before receipt ``number`` was drawn everywhere: the pages that have
        not answered it are taken as gone (a tab closed or reloaded never answers again), so they hold
        no later close back. A page that speaks again is known again."""
        for page in self.pages.live:
            if self.answers.get(page, 0) < number:
                self.pages.gone(page)
        self._release()

    def _release(self) -> None:
        live = self.pages.live
        if not live:
            return
        everywhere = min(self.answers.get(page, 0) for page in live)
        if everywhere <= self.drawn:
            return
        self.drawn = everywhere
        ready = [(n, callback) for n, callback in self._waiting if n <= everywhere]
        self._waiting = [(n, callback) for n, callback in self._waiting if n > everywhere]
        for _, callback in ready:
            callback(everywhere)

    def forget(self, on_drawn: Callable[[int], None]) -> None:
        """Stops awaiting a receipt for ``on_drawn`` (its caller closed by its fallback)."""
        self._waiting = [(n, callback) for n, callback in self._waiting if callback != on_drawn]


#: The kernel's receipts.
RECEIPTS = Receipts()
