"""A person's hand on the simulated arm: drag the arm's tip with the mouse, or pull its cable.

Teaching by hand needs a hand on the arm. With the real Swift Pro it is the person's own;
with the simulated arm (``uarm-sim://``) this small view stands in for it: the arm seen from
above (its base at the bottom, reaching up), the safe workspace outlined, the tool as a dot.
Dragging the dot moves the simulated arm's tip as a hand would
(``SimulatedSwiftPro.hand_move``): only while its steppers are released, and never past
its joint limits. **Pull the USB cable** closes the simulated port, as pulling the real
cable does, to try what the app does then.
"""

from __future__ import annotations

import math
import threading
import time

from ipycanvas import Canvas, hold_canvas
from ipywidgets import HTML, Button, Layout, VBox

from mt_widgets.hardware import TEACHING_MAX_YAW_DEG, TEACHING_RADIUS_MM, SimulatedSwiftPro

#: Size of the view (pixels), its scale and where the arm's base is drawn.
WIDTH_PX, HEIGHT_PX = 280, 190
PX_PER_MM = 0.5
BASE_PX = (140.0, 182.0)
#: How close (pixels) to the tool a press must be to grab it.
GRAB_PX = 25.0
#: The view floats at the top right of the window: the true-scale screen canvas is pinned
#: to the bottom of the window (``uarm_screen``) and would cover it in the page's flow.
BOX_CLASS = "mt-simulated-hand-box"
_CSS = (f"<style>.{BOX_CLASS} {{ position: fixed; top: 6px; right: 6px; z-index: 30; background: #ffffff; "
        f"border: 1px solid #999999; box-shadow: 0 2px 6px rgba(0,0,0,0.25); }}</style>")


def arm_to_view(x_mm: float, y_mm: float) -> tuple[float, float]:
    """Arm (x forward, y left) in mm -> view pixel (x right, y down)."""
    return BASE_PX[0] - PX_PER_MM * y_mm, BASE_PX[1] - PX_PER_MM * x_mm


def view_to_arm(px: float, py: float) -> tuple[float, float]:
    """View pixel -> arm (x, y) in mm."""
    return (BASE_PX[1] - py) / PX_PER_MM, (BASE_PX[0] - px) / PX_PER_MM


class SimulatedHand(VBox):
    """Drag the simulated arm's tip; pull its cable.

    Args:
        device: the ``SimulatedSwiftPro`` (``mt_widgets.hardware.bridge.simulated_device``).
        floating: float at the top right of the window (for a page whose screen canvas is
            pinned to the bottom); False leaves it in the page's flow (a notebook).

    Attributes:
        canvas: the top view (mouse and touch drags move the tip).
        cable_button: pulls the simulated USB cable.
        note: what the hand can do now.
        dragging: whether the tip is held.
    """

    def __init__(self, device: SimulatedSwiftPro, floating: bool = True):
        if not isinstance(floating, bool):
            raise TypeError(f"floating: expected True or False, got {type(floating).__name__}")
        if not isinstance(device, SimulatedSwiftPro):
            raise TypeError(f"device: expected a SimulatedSwiftPro, got {type(device).__name__}")
        self.device = device
        self.dragging = False
        self._lock = threading.Lock()
        self.canvas = Canvas(width=WIDTH_PX, height=HEIGHT_PX, layout=Layout(width=f"{WIDTH_PX}px",
                                                                             height=f"{HEIGHT_PX}px"))
        self.canvas.add_class("mt-simulated-hand")
        self.canvas.on_mouse_down(self._down)
        self.canvas.on_mouse_move(self._move)
        self.canvas.on_mouse_up(self._up)
        self.canvas.on_mouse_out(self._up)
        self.canvas.on_touch_start(lambda touches: touches and self._down(*touches[0]))
        self.canvas.on_touch_move(lambda touches: touches and self._move(*touches[0]))
        self.canvas.on_touch_end(lambda touches: self._up(0, 0))
        self.cable_button = Button(description="Pull the USB cable", icon="plug",
                                   tooltip="Close the simulated arm's port, as pulling its cable does")
        self.cable_button.on_click(lambda _: self.pull_cable())
        self.note = HTML("")
        title = "<b>Your hand on the simulated arm</b><br><small>seen from above: drag the tip</small>"
        super().__init__([HTML((_CSS if floating else "") + title), self.canvas, self.note, self.cable_button],
                         layout=Layout(padding="4px", width=f"{WIDTH_PX + 12}px"))
        self.add_class(BOX_CLASS)
        self.refresh()

    def pull_cable(self) -> None:
        """Pull the simulated cable: the port closes; the arm keeps its state."""
        self.device.pull_cable()
        self.cable_button.disabled = True
        self.cable_button.description = "Cable pulled"
        self.refresh()

    def refresh(self) -> None:
        """Draw the arm as it is now."""
        with self._lock:
            x, y, _ = self.device.position_at(time.monotonic())
            released = self.device.steppers_released()
            c = self.canvas
            with hold_canvas():
                c.clear()
                c.fill_style = "#ffffff"
                c.fill_rect(0, 0, WIDTH_PX, HEIGHT_PX)
                self._sector()
                bx, by = BASE_PX
                tx, ty = arm_to_view(x, y)
                c.stroke_style = "#888888"
                c.line_width = 4
                c.stroke_line(bx, by, tx, ty)
                c.fill_style = "#444444"
                c.fill_circle(bx, by, 6)
                c.fill_style = "#000000" if released else "#7f7f7f"
                c.fill_circle(tx, ty, 7)
                c.fill_style = "#000000"
                c.font = "12px sans-serif"
                c.fill_text(f"tip at x = {x:.0f} mm, y = {y:.0f} mm", 6, 14)
        if self.device.disconnected:
            self.note.value = "<i>The cable is pulled: the arm no longer hears the computer.</i>"
        elif released:
            self.note.value = "<i>The arm is released: drag its tip.</i>"
        else:
            self.note.value = "<i>The motors hold the arm: it does not give way.</i>"

    def _sector(self) -> None:
        c = self.canvas
        r0, r1 = TEACHING_RADIUS_MM
        c.stroke_style = "#56b4e9"
        c.line_width = 1
        c.begin_path()
        steps = 24
        yaw = math.radians(TEACHING_MAX_YAW_DEG)
        points = [(r1 * math.cos(a), r1 * math.sin(a)) for a in
                  (-yaw + 2 * yaw * k / steps for k in range(steps + 1))]
        points += [(r0 * math.cos(a), r0 * math.sin(a)) for a in
                   (yaw - 2 * yaw * k / steps for k in range(steps + 1))]
        first = arm_to_view(*points[0])
        c.move_to(*first)
        for p in points[1:]:
            c.line_to(*arm_to_view(*p))
        c.close_path()
        c.stroke()

    # ------------------------------------------------------------------ mouse
    def _down(self, px, py) -> None:
        x, y, _ = self.device.position_at(time.monotonic())
        tx, ty = arm_to_view(x, y)
        self.dragging = math.hypot(px - tx, py - ty) <= GRAB_PX
        if self.dragging:
            self._move(px, py)

    def _move(self, px, py) -> None:
        if not self.dragging:
            return
        now = time.monotonic()
        x, y = view_to_arm(px, py)
        z = self.device.position_at(now)[2]
        self.device.hand_move((x, y, z), now, 0.03)  # a hand is quick, not instant
        self.refresh()

    def _up(self, px, py) -> None:
        self.dragging = False
        self.refresh()


__all__ = ["SimulatedHand", "arm_to_view", "view_to_arm"]
