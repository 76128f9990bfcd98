"""Animation playing: frames plus ``canvas.sleep`` sent in short chunks the browser plays by itself.

A Python loop with ``time.sleep`` would send one message per frame, block the kernel and
drop frames; ipycanvas can instead queue frames in a ``hold_canvas`` batch, and the front
end's canvas manager plays them, awaiting each ``sleep`` (docs/design.md, "Widgets").

That manager has ONE queue for every canvas of the page, and it cannot be told to skip
what it holds: a 10 s reproduction sent as one message delays every other canvas's drawing
by up to 10 s, and a command for a canvas closed meanwhile ("widget model not found") stops
the manager for good (its promise chain stays rejected: every canvas of the page stays
blank). So an animation is sent in chunks of ``CHUNK_S`` seconds of frames, each a little
before the browser needs it (``AHEAD_S``), from the kernel's event loop; ``Animation.cancel``
stops sending, so whatever replaces an animation waits at most about half a second, and
``retire`` closes a replaced view only once the page says it has drawn everything sent before
(a receipt, ``receipt.py``; the kernel's own estimate of playback is wrong for a browser that lags
behind it, a phone or a loaded machine). Without a
running event loop (a script, kernel-free tests: no browser to pace) the whole animation
goes as one message, as before.

The kernel cannot know when playback ends; the layer's final content is recorded so a
new browser view shows the last frame.
"""

from __future__ import annotations

import asyncio
import ctypes
import functools
import gc
import time
import weakref
from collections.abc import Callable

import numpy as np
from IPython import get_ipython

from .receipt import RECEIPTS
from .redraw import drawing_batch
from .tree import widget_tree

DEFAULT_FPS = 60.0
#: Seconds of frames in one message.
CHUNK_S = 0.2
#: How far ahead of the browser's playback the next chunk is sent (seconds).
AHEAD_S = 0.2
#: Extra seconds before a retired widget is closed, for messages in flight.
CLOSE_MARGIN_S = 2.0
#: Seconds after which a retired widget is closed though no page answered its receipt (no page, or
#: one closed meanwhile): nothing leaks. Never before the estimate of playback plus CLOSE_MARGIN_S.
CLOSE_FALLBACK_S = 60.0


def kernel_loop():
    """The running event loop of the IPython kernel this runs in (it paces animations), else None.

    Only a kernel's: another library's loop running in the same thread (Playwright's sync API
    keeps one) has no browser view of these widgets to pace for.
    """
    shell = get_ipython()
    if shell is None or getattr(shell, "kernel", None) is None:
        return None
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        pass
    try:
        loop = asyncio.get_event_loop_policy().get_event_loop()
    except RuntimeError:
        return None
    return loop if loop.is_running() else None


class _Queue:
    """An estimate of when the browser's (single) canvas queue has played what was sent."""

    free_at = 0.0

    @classmethod
    def add(cls, seconds: float) -> float:
        """Records ``seconds`` of playback sent now; returns when it will have played."""
        cls.free_at = max(cls.free_at, time.monotonic()) + seconds
        return cls.free_at

    @classmethod
    def drained_in(cls) -> float:
        return max(0.0, cls.free_at - time.monotonic())


#: layer canvas -> the animation playing on it (weakly: a closed view takes its entry with it).
_PLAYING: weakref.WeakKeyDictionary[object, Animation] = weakref.WeakKeyDictionary()
#: layer canvas -> the last receipt number issued when its latest chunk was sent: a receipt with a
#: higher number was queued behind that chunk.
_SENT_BEFORE_RECEIPT: weakref.WeakKeyDictionary[object, int] = weakref.WeakKeyDictionary()


class Animation:
    """An animation being sent to the browser chunk by chunk (see the module's docstring).

    Built and started by ``play_frames``; ``cancel`` stops it, ``done`` says whether every
    frame (and the final picture) has been sent.
    """

    def __init__(self, canvas, n_frames: int, setup, draw_frame, final, then, fps: float):
        self.canvas, self.n_frames, self.fps = canvas, n_frames, fps
        self._setup, self._draw_frame, self._final, self._then = setup, draw_frame, final, then
        self._next = 0
        self._handle = None
        self._loop = None
        self.done = False
        self.cancelled = False

    @property
    def _chunk(self) -> int:
        return max(1, int(round(CHUNK_S * self.fps)))

    def _send(self, stop: int) -> None:
        """Sends frames ``self._next`` to ``stop`` (and the final picture after the last) in one message."""
        canvas, delay_ms = self.canvas, round(1000.0 / self.fps, 2)
        start = self._next
        with drawing_batch():
            if start == 0:
                canvas.clear()
            # Styles are set again in every chunk: something else may have drawn on the layer between.
            self._setup(canvas)
            for index in range(start, stop):
                if index:
                    canvas.clear()
                self._draw_frame(canvas, index)
                if index < self.n_frames - 1:
                    canvas.sleep(delay_ms)
            if stop == self.n_frames:
                canvas.clear()
                self._final(canvas)
                if self._then is not None:
                    self._then()
        self._next = stop
        self.done = stop == self.n_frames
        _SENT_BEFORE_RECEIPT[canvas] = RECEIPTS.issued
        self._sent_until = _Queue.add((stop - start) / self.fps)

    def start(self) -> Animation:
        self._loop = kernel_loop()
        if self._loop is None:  # nobody to pace for: everything at once
            self._send(self.n_frames)
            return self
        self._send(min(self.n_frames, self._chunk))
        self._schedule()
        return self

    def _schedule(self) -> None:
        if self.done or self.cancelled:
            return
        delay = max(0.0, self._sent_until - time.monotonic() - AHEAD_S)
        self._handle = self._loop.call_later(delay, self._continue)

    def _continue(self) -> None:
        self._handle = None
        if self.done or self.cancelled:
            return
        if getattr(self.canvas, "comm", None) is None:  # the widget was closed: nothing to draw on
            self.cancelled = True
            return
        self._send(min(self.n_frames, self._next + self._chunk))
        self._schedule()

    def cancel(self, show_final: bool = False) -> None:
        """Stops sending frames; with ``show_final`` the layer shows the final picture at once."""
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None
        if self.done or self.cancelled:
            return
        self.cancelled = True
        if show_final and getattr(self.canvas, "comm", None) is not None:
            with drawing_batch():
                self.canvas.clear()
                self._final(self.canvas)
                if self._then is not None:
                    self._then()


def stop_animation(canvas, show_final: bool = False) -> None:
    """Stops the animation playing on a layer ``canvas``, if any (see ``Animation.cancel``)."""
    animation = _PLAYING.pop(canvas, None)
    if animation is not None:
        animation.cancel(show_final=show_final)


def _canvases(widget):
    """Every ipycanvas layer in a widget tree (MultiCanvas layers included)."""
    seen = set()
    stack = [widget]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        yield node
        stack.extend(getattr(node, "children", ()) or ())
        stack.extend(getattr(node, "_canvases", ()) or ())


def stop_animations(widget) -> None:
    """Stops every animation playing on any canvas in ``widget``'s tree (its view is being replaced)."""
    for node in _canvases(widget):
        stop_animation(node)


def retire(widget, keep=None, shown_only: bool = False) -> None:
    """Takes a widget tree off the page for good: stops its animations now, and closes every widget
    it owns (``tree.widget_tree``: layouts, styles and off-page parts included) once the page says it
    has drawn everything sent to them (a receipt, ``receipt.py``): closing earlier would leave queued
    commands pointing at a closed canvas, which stops ipycanvas' drawing for the whole page.

    Without a page to answer (none open, or closed meanwhile) the close comes at ``CLOSE_FALLBACK_S``
    (never before the kernel's estimate of playback plus ``CLOSE_MARGIN_S``); without a kernel, at once.
    In a kernel, the closes of a turn of its loop are followed by one full collection and a heap
    trim (``_collect_soon``), which free the closed widgets' memory.

    Args:
        widget: the view leaving the page.
        keep: the page that stays, or None: a widget it shows when the close comes (a part the page
            moved into its new view) stays open.
        shown_only: close only what ``widget`` shows (children, layouts, styles), never what its
            attributes hold: for a screen of text and buttons, whose attributes may reach the page.
    """
    if not isinstance(shown_only, bool):
        raise TypeError(f"shown_only: expected a bool, got {type(shown_only).__name__}")
    canvases = list(_canvases(widget))
    for node in canvases:
        stop_animation(node)

    def close():
        # Walked here, not when the view leaves: the walk costs tens of milliseconds that the page's
        # answer to the click that replaced the view should not wait for.
        kept = {id(node) for node in widget_tree(keep, shown_only=True)} if keep is not None else set()
        for node in list(widget_tree(widget, shown_only=shown_only)):
            if id(node) not in kept:
                node.close()

    loop = kernel_loop()
    if loop is None:
        close()
        return
    _Closing(canvases, close, loop).start()


class _Closing:
    """One retired view waiting for the page's receipt (or the fallback) before it is closed."""

    def __init__(self, canvases, close: Callable[[], None], loop):
        self.canvases, self._close, self._loop = canvases, close, loop
        self._fallback = None
        self._receipt = 0
        self.closed = False

    def start(self) -> None:
        self._fallback = self._loop.call_later(max(CLOSE_FALLBACK_S, _Queue.drained_in() + CLOSE_MARGIN_S),
                                               self._timed_out)
        self._receipt = RECEIPTS.request(self._on_drawn)

    def _still_sending(self, number: int) -> bool:
        """Whether a canvas of the view got a chunk after receipt ``number`` was queued, or will get more."""
        for canvas in self.canvases:
            playing = _PLAYING.get(canvas)
            if playing is not None and not (playing.done or playing.cancelled):
                return True
            if _SENT_BEFORE_RECEIPT.get(canvas, -1) >= number:
                return True
        return False

    def _on_drawn(self, number: int) -> None:
        if self.closed:
            return
        if self._still_sending(number):
            # Drawn up to a point this view's canvases have gone past: ask again, behind what came since.
            self._receipt = RECEIPTS.request(self._on_drawn)
            return
        self._finish()

    def _timed_out(self) -> None:
        self._finish()
        # The pages that never answered are gone (closed, reloaded): they hold no later close back.
        RECEIPTS.give_up(self._receipt)

    def _finish(self) -> None:
        if self.closed:
            return
        self.closed = True
        if self._fallback is not None:
            self._fallback.cancel()
        RECEIPTS.forget(self._on_drawn)
        self._close()
        try:
            _collect_soon(self._loop)
        except RuntimeError:  # the loop closed meanwhile (the kernel is ending): nothing to free for
            pass


# A closed view is garbage in reference cycles (traitlets' observers, its comms' callbacks, its
# canvases' handlers): only a full collection frees it. Python runs one only once the objects that
# outlived younger collections since the last exceed a quarter of all long-lived ones, and a class
# kernel holds about 290,000 of those (what the template imported; ``gc.freeze`` does not take them
# out of that count): the first came after about thirty episodes, a lesson's kernel had climbed from
# 103 to 133 MiB PSS, and glibc kept the freed heap afterwards. Collected after the closes it stays
# within 7 % (benchmarks/bench_lesson_kernel.py). A collection takes 10-30 ms in a kernel forked from
# the template (its frozen objects are not visited) and up to about 100 ms in one started the usual
# way; an animation playing meanwhile is held back only by one longer than AHEAD_S, since its chunks
# go that early. Waiting until no animation played was tried: back-to-back episodes always have one,
# and the kernel grew as before. A notebook holding millions of objects makes each collection long:
# then they come less often (``COLLECTION_SHARE``).
#: At most this share of the kernel's time goes to the collections after closes.
COLLECTION_SHARE = 0.02
#: The loop and the timer of the collection to come, if one is.
_COLLECTION: dict = {}
#: When the last collection ended and what it took (time.monotonic, seconds).
_LAST_COLLECTION = [0.0, 0.0]


def _collect_soon(loop) -> None:
    """One full collection (and the heap trimmed) on ``loop`` after the views closed this turn, or
    later if the last one was recent for what it took."""
    if _COLLECTION.get("loop") is loop:
        return  # one is coming on this loop (a timer left on another, closed, loop does not count)
    ended, took = _LAST_COLLECTION
    wait = max(0.0, ended + took / COLLECTION_SHARE - time.monotonic())
    _COLLECTION.update(loop=loop, timer=loop.call_later(wait, _collect))


def _collect() -> None:
    _COLLECTION.clear()
    started = time.monotonic()
    gc.collect()
    trim = _malloc_trim()
    if trim is not None:
        trim(0)  # glibc keeps freed heap at the top of its arenas unless told: about 1.5 ms
    ended = time.monotonic()
    _LAST_COLLECTION[:] = [ended, ended - started]


@functools.cache
def _malloc_trim():
    """glibc's ``malloc_trim``, or None (another C library: nothing to give back this way)."""
    try:
        return ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError, TypeError):  # TypeError: Windows has no CDLL(None)
        return None


def set_style_now(canvas, name: str, value) -> None:
    """Send a canvas style (e.g. ``"fill_style"``) without the traitlets machinery.

    Setting ``canvas.fill_style`` validates the colour through traitlets and notifies
    observers: about 80 microseconds, half the encoding time of a 600-frame animation
    when done twice a frame. The command sent is the same one ipycanvas sends (its
    private ``ATTRS`` / ``COMMANDS`` tables, pinned to ipycanvas < 0.15); the Python-side
    trait is not updated, so callers set a style this way only inside frames and always
    set it before use.
    """
    from ipycanvas.canvas import COMMANDS

    canvas._canvas_manager.send_command(canvas, [COMMANDS["set"], [canvas.ATTRS[name], value]])


def frame_times(start: float, end: float, fps: float = DEFAULT_FPS) -> np.ndarray:
    """Times (F,) in seconds of the frames from ``start`` to ``end`` inclusive at ``fps``."""
    if not fps > 0:
        raise ValueError(f"fps: expected a positive number of frames per second, got {fps!r}")
    if not end >= start:
        raise ValueError(f"start, end: expected start <= end, got {start}, {end}")
    count = int(np.floor((end - start) * fps + 1e-9)) + 1
    times = start + np.arange(count) / fps
    if times[-1] < end - 1e-9:
        times = np.append(times, end)
    return times


def sample_at(times: np.ndarray, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Values (T, D) sampled at times ``at`` (F,) by linear interpolation -> (F, D).

    The simulated arm is recorded at 1 kHz, so this is a subsample; the uArm moves in
    steps of half a second, and interpolating shows the straight move between them.
    """
    times = np.asarray(times, dtype=float)
    values = np.asarray(values, dtype=float)
    if values.ndim != 2 or values.shape[0] != times.shape[0]:
        raise ValueError(f"values: expected shape ({times.shape[0]}, D), got {values.shape}")
    if len(times) == 1:
        return np.repeat(values, len(at), axis=0)
    return np.stack([np.interp(at, times, values[:, d]) for d in range(values.shape[1])], axis=-1)


def play_frames(view, layer: str, n_frames: int, setup: Callable[[object], None],
                draw_frame: Callable[[object, int], None], final: Callable[[object], None],
                fps: float = DEFAULT_FPS, then: Callable[[], None] | None = None) -> Animation:
    """Play an animation of ``n_frames`` frames on one layer of an ``ArmView``.

    The frames go in chunks paced by the kernel's event loop (one message without one); an
    animation already playing on the layer is stopped first.

    Args:
        view: The ``ArmView`` to draw on.
        layer: The layer name (normally "robot").
        n_frames: Number of frames (>= 1).
        setup: ``setup(canvas)`` sets styles that stay fixed for the whole animation (sent
            with every chunk).
        draw_frame: ``draw_frame(canvas, i)`` draws frame i on a cleared layer.
        final: ``final(canvas)`` paints what the layer shows after playback; it is
            recorded for new views and must draw the same as the last frame (or more).
        fps: Frames per second of playback.
        then: Drawn right after the final picture, in the same message (e.g. another layer
            that changes when the motion ends); also when the animation is stopped early
            with ``show_final``.

    Returns:
        The ``Animation`` (``cancel()`` stops it).
    """
    if n_frames < 1:
        raise ValueError(f"n_frames: expected at least 1 frame, got {n_frames}")
    if not fps > 0:
        raise ValueError(f"fps: expected a positive number of frames per second, got {fps!r}")
    canvas = view.layer(layer)
    stop_animation(canvas)
    animation = Animation(canvas, n_frames, setup, draw_frame, final, then, float(fps))
    _PLAYING[canvas] = animation
    animation.start()
    view.remember(final, layer)
    return animation
