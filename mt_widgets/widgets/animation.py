"""Animation playing: every frame plus ``canvas.sleep`` in one message, played by the browser.

A Python loop with ``time.sleep`` would send one message per frame, block the kernel and
drop frames; ipycanvas can instead queue all frames in one ``hold_canvas`` batch, and the
front end's canvas manager plays them, awaiting each ``sleep`` (docs/design.md, "Widgets").
The kernel cannot know when playback ends; the layer's final content is recorded so a
new browser view shows the last frame.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .redraw import drawing_batch

DEFAULT_FPS = 60.0


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
                fps: float = DEFAULT_FPS) -> None:
    """Send an animation of ``n_frames`` frames on one layer of an ``ArmView``, in one message.

    Args:
        view: The ``ArmView`` to draw on.
        layer: The layer name (normally "robot").
        n_frames: Number of frames (>= 1).
        setup: ``setup(canvas)`` sets styles that stay fixed for the whole animation (once).
        draw_frame: ``draw_frame(canvas, i)`` draws frame i on a cleared layer.
        final: ``final(canvas)`` paints what the layer shows after playback; it is
            recorded for new views and must draw the same as the last frame (or more).
        fps: Frames per second of playback.
    """
    if n_frames < 1:
        raise ValueError(f"n_frames: expected at least 1 frame, got {n_frames}")
    if not fps > 0:
        raise ValueError(f"fps: expected a positive number of frames per second, got {fps!r}")
    canvas = view.layer(layer)
    delay_ms = round(1000.0 / fps, 2)
    with drawing_batch():
        canvas.clear()
        setup(canvas)
        for index in range(n_frames):
            if index:
                canvas.clear()
            draw_frame(canvas, index)
            if index < n_frames - 1:
                canvas.sleep(delay_ms)
        canvas.clear()
        final(canvas)
    view.remember(final, layer)
