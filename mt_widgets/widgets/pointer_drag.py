"""One drag mechanism for the teaching canvases: a mouse, a finger and a pen draw alike.

ipycanvas reports a mouse button's down, moves and up at a canvas pixel, and touches as lists
of (x, y), one per finger on the canvas (a pen arrives as mouse events); ``touch_end`` and
``touch_cancel`` list the fingers still down, so a drag ends where its finger last moved. The
rules every teaching canvas follows (the planar ``TeachingCanvas`` and ``SpaceTeachingCanvas``)
live here once: one finger draws with a larger grab zone than a mouse; a second finger (a pinch)
ends the drag where the first had drawn it; a drag stops the moment the canvas stops accepting
input (locked, or guidance shown); the keys that confirm and clear an arrow. What a press, a move
and a release mean on its canvas (which arrow, which view, an orbit) each canvas says itself.
"""

from __future__ import annotations

from collections.abc import Callable

#: Keys that remove the arrow being drawn.
CLEAR_KEYS = ("Escape", "Backspace", "Delete")
#: Arrow keys and the sign of the step each one takes.
ARROW_KEY_SIGNS = {"ArrowUp": 1.0, "ArrowRight": 1.0, "ArrowDown": -1.0, "ArrowLeft": -1.0}


class PointerDrag:
    """Whether a drag is on, and where its finger last was, for one canvas.

    Args:
        press: ``press(x, y, radius) -> bool``: a button or finger down at canvas pixel (x, y) with
            that grab radius (px); True when it starts a drag.
        move: ``move(pointer)``: the pointer (x, y) moved during the drag.
        release: ``release(pointer)``: the drag ended at the pointer, while the canvas accepts input.
        accepting: ``accepting() -> bool``: whether the drag may go on (a canvas locked mid-drag ends it).
    """

    def __init__(self, press: Callable, move: Callable, release: Callable, accepting: Callable[[], bool]):
        self._press, self._move, self._release, self._accepting = press, move, release, accepting
        self.active = False
        self.last_touch = None

    def connect(self, canvas, mouse_radius: Callable[[], float], touch_radius: Callable[[], float],
                key_down: Callable) -> None:
        """Listens to an ipycanvas ``Canvas``'s mouse, touch and key events (the pointer leaving it ends a drag).

        Args:
            canvas: the canvas whose events come in (a ``MultiCanvas``'s top layer).
            mouse_radius, touch_radius: the grab radius (px) of a mouse and of a finger, read at each press.
            key_down: ``key_down(key, shift_key, ctrl_key, meta_key)``, the canvas's keys.
        """
        canvas.on_mouse_down(lambda x, y: self.mouse_down(x, y, mouse_radius()))
        canvas.on_mouse_move(self.mouse_move)
        canvas.on_mouse_up(self.mouse_up)
        canvas.on_mouse_out(self.mouse_up)
        canvas.on_key_down(key_down)
        canvas.on_touch_start(lambda points: self.touch_start(points, touch_radius()))
        canvas.on_touch_move(self.touch_move)
        canvas.on_touch_end(self.touch_end)
        canvas.on_touch_cancel(self.touch_end)

    def cancel(self) -> None:
        """Ends the drag without a release (Escape mid-drag, a lock): the pointer still moving draws nothing."""
        self.active = False
        self.last_touch = None

    def mouse_down(self, x, y, radius: float) -> None:
        self.active = bool(self._press(x, y, radius))

    def mouse_move(self, x, y) -> None:
        # Called for every pointer move over the canvas: return at once unless dragging.
        if not self.active:
            return
        if not self._accepting():   # locked or done since the press: the drag is over
            self.active = False
            return
        self._move((x, y))

    def mouse_up(self, x, y) -> None:
        if not self.active:
            return
        self.active = False
        if self._accepting():
            self._release((x, y))

    def touch_start(self, points, radius: float) -> None:
        if len(points) == 1 and not self.active:
            self.last_touch = points[0]
            self.mouse_down(*points[0], radius)
        elif len(points) > 1 and self.active:
            # A second finger (a pinch): the arrow stays where the first finger had drawn it.
            self.end_touch()

    def touch_move(self, points) -> None:
        if len(points) == 1 and self.active:
            self.last_touch = points[0]
            self.mouse_move(*points[0])

    def touch_end(self, points) -> None:
        if not points:
            self.end_touch()

    def end_touch(self) -> None:
        if self.active and self.last_touch is not None:
            self.mouse_up(*self.last_touch)
        self.cancel()


def confirm_or_clear(key: str, has_arrow: bool, confirm: Callable[[], object], clear: Callable[[], object]) -> bool:
    """Enter confirms a drawn arrow, Escape, Backspace and Delete clear it; True when ``key`` was one of them."""
    if key == "Enter" and has_arrow:
        confirm()
        return True
    if key in CLEAR_KEYS:
        clear()
        return True
    return False
