"""When a retired view is closed in a kernel: once the page answers a receipt queued behind
everything sent to it, else at a fallback timeout (never before the kernel's estimate of playback).

Kernel-free: a loop that only records what it is asked to call later, and a page played by hand
(the receipt canvas's client_ready, and the picture it sends back). A real page: tests/browser/test_lagging_page.py.
"""

import io

import pytest
from ipycanvas import Canvas
from ipycanvas.canvas import _CANVAS_MANAGER
from PIL import Image

from mt_widgets.widgets import animation, receipt, redraw
from mt_widgets.widgets.pages import Pages as KnownPages
from mt_widgets.widgets.receipt import Receipts, number_colour, png_number


class RecordingLoop:
    """An event loop that calls nothing by itself: the test calls what is due."""

    def __init__(self):
        self.calls = []

    def call_later(self, delay, callback):
        handle = Handle(delay, callback)
        self.calls.append(handle)
        return handle

    def due(self, up_to):
        """Calls every pending callback due within ``up_to`` seconds (in order of delay)."""
        for handle in sorted(self.calls, key=lambda h: h.delay):
            if handle.delay <= up_to and not handle.cancelled and not handle.called:
                handle.called = True
                handle.callback()


class Handle:
    def __init__(self, delay, callback):
        self.delay, self.callback, self.cancelled, self.called = delay, callback, False, False

    def cancel(self):
        self.cancelled = True


def png(rgb, mode="RGBA") -> bytes:
    buffer = io.BytesIO()
    Image.new(mode, (1, 1), tuple(rgb) + ((255,) if mode == "RGBA" else ())).save(buffer, format="PNG")
    return buffer.getvalue()


def picture_of(number: int, mode="RGBA") -> bytes:
    """The picture a page sends back for receipt ``number``: its colour in one pixel."""
    rgb = [int(v) for v in number_colour(number)[4:-1].split(",")]
    return png(rgb, mode)


@pytest.fixture
def kernel(monkeypatch):
    """A kernel's loop, fresh receipts, and every canvas message sent."""
    loop = RecordingLoop()
    receipts = Receipts(KnownPages())
    sent = []
    monkeypatch.setattr(animation, "kernel_loop", lambda: loop)
    monkeypatch.setattr(animation, "RECEIPTS", receipts)
    monkeypatch.setattr(animation._Queue, "free_at", 0.0)
    # The collection after a close is another timer (test_retire.py tests it): not this loop's business.
    monkeypatch.setattr(animation, "_collect_soon", lambda loop: None)
    monkeypatch.setattr(_CANVAS_MANAGER, "_send_custom", lambda command, buffers=[]: sent.append(command))
    return loop, receipts, sent


def page_opens(receipts):
    receipts.canvas._handle_frontend_event(None, {"event": "client_ready"}, [])


def page_answers(receipts, number):
    receipts.canvas.set_state({"image_data": memoryview(picture_of(number))})


def test_a_receipt_number_survives_the_png_the_page_sends():
    for number in (1, 2, 255, 256, 65_537, (1 << 24) - 1):
        assert png_number(picture_of(number)) == number
        assert png_number(picture_of(number, mode="RGB")) == number
    assert png_number(b"not a png") is None and png_number(None) is None
    big = io.BytesIO()
    Image.new("RGBA", (2, 1)).save(big, format="PNG")
    assert png_number(big.getvalue()) is None


def test_a_retired_canvas_closes_when_the_page_answers_its_receipt_and_not_before(kernel):
    loop, receipts, sent = kernel
    view = Canvas(width=10, height=10)
    animation.retire(view)
    assert view.comm is not None and receipts.issued == 1
    assert not any("rgb(0, 0, 1)" in str(message) for message in sent)  # no page has the canvas yet
    page_opens(receipts)
    # The receipt goes behind what was sent, with its number as the pixel's colour.
    assert "rgb(0, 0, 2)" in str(sent[-1])
    page_answers(receipts, 1)          # answered by a page from before this one: covers nothing here
    assert view.comm is not None
    loop.due(animation.CLOSE_MARGIN_S)  # the kernel's estimate has passed: still open
    assert view.comm is not None
    page_answers(receipts, 2)
    assert view.comm is None
    assert all(handle.cancelled or handle.called for handle in loop.calls)  # the fallback is off


def test_without_an_answer_the_close_comes_at_the_fallback_not_before(kernel):
    loop, receipts, _ = kernel
    animation._Queue.add(90.0)  # the browser was sent 90 s of playback: the fallback waits for it too
    view = Canvas(width=10, height=10)
    animation.retire(view)
    page_opens(receipts)
    (fallback,) = loop.calls
    assert fallback.delay >= 90.0 + animation.CLOSE_MARGIN_S - 0.5
    loop.due(fallback.delay - 1.0)
    assert view.comm is not None
    loop.due(fallback.delay)
    assert view.comm is None and receipts._waiting == []
    page_answers(receipts, receipts.issued)  # a late answer closes nothing twice
    assert view.comm is None


def test_a_reloaded_page_gets_a_fresh_receipt_for_what_the_old_one_never_answered(kernel):
    _, receipts, sent = kernel
    view = Canvas(width=10, height=10)
    animation.retire(view)
    page_opens(receipts)
    page_opens(receipts)  # the page reloads: the old page's receipt 2 will never come
    assert receipts.issued == 3 and "rgb(0, 0, 3)" in str(sent[-1])
    page_answers(receipts, 3)
    assert view.comm is None


class OneLayerView:
    def __init__(self):
        self.canvas = Canvas(width=10, height=10)

    def layer(self, name):
        return self.canvas

    def remember(self, paint, layer):
        pass


def test_a_receipt_does_not_close_a_canvas_that_got_chunks_after_it_was_queued(kernel):
    loop, receipts, _ = kernel
    view = OneLayerView()
    animation.retire(view.canvas)
    page_opens(receipts)
    queued = receipts.issued
    # Something plays on the retired canvas after the receipt was queued (its later chunks unsent).
    playing = animation.play_frames(view, "robot", 60, lambda c: None, lambda c, i: c.fill_rect(i, 0, 1, 1),
                                    lambda c: None, fps=60.0)
    page_answers(receipts, queued)
    assert view.canvas.comm is not None and not playing.done
    assert receipts.issued == queued + 1   # asked again, behind what came since
    for _ in range(20):                    # the rest of the chunks go out
        loop.due(animation.CLOSE_FALLBACK_S - 1.0)  # not the fallback
    assert playing.done
    page_answers(receipts, queued + 1)     # queued before the last chunks: not enough
    assert view.canvas.comm is not None and receipts.issued == queued + 2
    page_answers(receipts, queued + 2)
    assert view.canvas.comm is None


def test_without_a_kernel_retire_still_closes_at_once():
    view = Canvas(width=10, height=10)
    animation.retire(view)
    assert view.comm is None


class Pages:
    """Which page (kernel session) the kernel hears from: the header's session of the message handled."""

    def __init__(self, monkeypatch):
        self.now = None
        monkeypatch.setattr(receipt, "current_page", lambda: self.now)

    def opens(self, receipts, page):
        self.now = page
        page_opens(receipts)

    def answers(self, receipts, page, number):
        self.now = page
        page_answers(receipts, number)


def test_with_two_tabs_a_retired_canvas_closes_only_once_both_have_answered(kernel, monkeypatch):
    # One notebook open in two tabs on one kernel: each tab runs its own command chain at its own pace.
    loop, receipts, _ = kernel
    pages = Pages(monkeypatch)
    view = Canvas(width=10, height=10)
    animation.retire(view)
    pages.opens(receipts, "fast tab")
    pages.opens(receipts, "slow tab")
    number = receipts.issued
    pages.answers(receipts, "fast tab", number)
    assert view.comm is not None      # the slow tab may still hold commands for it
    loop.due(animation.CLOSE_MARGIN_S)
    assert view.comm is not None
    pages.answers(receipts, "slow tab", number)
    assert view.comm is None


def test_a_tab_that_is_gone_holds_one_close_back_to_its_fallback_and_no_later_one(kernel, monkeypatch):
    loop, receipts, _ = kernel
    pages = Pages(monkeypatch)
    first = Canvas(width=10, height=10)
    animation.retire(first)
    pages.opens(receipts, "closed tab")
    pages.opens(receipts, "open tab")
    pages.answers(receipts, "open tab", receipts.issued)
    assert first.comm is not None
    (fallback,) = [handle for handle in loop.calls if not handle.called]
    loop.due(fallback.delay)          # the closed tab never answers: the fallback closes
    assert first.comm is None and receipts.pages.live == ("open tab",)
    second = Canvas(width=10, height=10)
    animation.retire(second)
    pages.answers(receipts, "open tab", receipts.issued)
    assert second.comm is None        # the open tab's answer is enough now
    # A tab thought gone that answers again is waited for again.
    pages.answers(receipts, "closed tab", receipts.issued)
    third = Canvas(width=10, height=10)
    animation.retire(third)
    pages.answers(receipts, "open tab", receipts.issued)
    assert third.comm is not None
    pages.answers(receipts, "closed tab", receipts.issued)
    assert third.comm is None


def test_a_page_picture_is_not_echoed_to_the_other_pages(kernel):
    # Echoed, the fast tab's picture would reach the slow tab's model, and the slow tab's own equal
    # picture would then be no change there: never sent.
    _, receipts, _ = kernel
    animation.retire(Canvas(width=10, height=10))
    sent = []
    receipts.canvas._send = lambda message, buffers=None: sent.append(message)
    page_answers(receipts, receipts.issued)
    assert not [message for message in sent if message.get("method") == "echo_update"], sent


def test_a_tab_known_from_its_views_is_waited_for_before_it_has_made_its_receipt_canvas(kernel, monkeypatch):
    # A lagging tab makes its model of the receipt canvas (made at the first retire) late: after the fast
    # tab has answered. It is known from its models of the views' canvases, made long before.
    loop, receipts, _ = kernel
    pages = Pages(monkeypatch)
    monkeypatch.setattr(redraw, "PAGES", receipts.pages)
    monkeypatch.setattr(redraw, "current_page", lambda: pages.now)
    layer = Canvas(width=10, height=10)
    redraw.repaint_on_new_view(layer, lambda: None)
    for tab in ("fast tab", "slow tab"):
        pages.now = tab
        layer._handle_frontend_event(None, {"event": "client_ready"}, [])
    animation.retire(layer)
    pages.opens(receipts, "fast tab")
    pages.answers(receipts, "fast tab", receipts.issued)
    assert layer.comm is not None
    pages.opens(receipts, "slow tab")   # at last: a fresh receipt, which both tabs answer
    pages.answers(receipts, "fast tab", receipts.issued)
    assert layer.comm is not None
    pages.answers(receipts, "slow tab", receipts.issued)
    assert layer.comm is None
