"""A person's hand on the simulated SO-101: drag the gripper in a top and a side view, or cause a fault.

Teaching the SO-101 by hand needs a hand on the arm. On the real arm it is the person's own; on
the simulated arm this small view stands in for it: the arm seen from above (left: its base at
the bottom, reaching up the view) and from the side (right: reaching to the right, the table at
the bottom). Dragging the gripper (the dot) in the top view moves it across the table, in the
side view forward and up or down (:class:`mt_widgets.hardware.feetech.sim_hand.SimulatedHand`):
only while the servos' torque is off, as a real arm gives way only then.

Three buttons cause what goes wrong on a real arm, to try what the page does then: **Pull the
USB cable** (the port closes), **Loosen a servo's cable** (the elbow's servo stops answering)
and **Block a joint** (the shoulder's servo overloads and drops its torque).
"""

from __future__ import annotations

import threading
import time

import numpy as np
from ipycanvas import Canvas, hold_canvas
from ipywidgets import HTML, Button, HBox, Layout, VBox

from mt_widgets.hardware.feetech import SO101_IDS, SimulatedBus
from mt_widgets.hardware.feetech.sim_hand import SimulatedHand

#: The view: two square panels (top, side) of PANEL_PX, PX_PER_M, the base's pixel in each.
PANEL_PX = 180
WIDTH_PX, HEIGHT_PX = 2 * PANEL_PX, PANEL_PX
PX_PER_M = 350.0
TOP_BASE_PX = (90.0, 172.0)
SIDE_BASE_PX = (PANEL_PX + 10.0, 172.0)
#: How close (pixels) to the gripper a press must be to grab it.
GRAB_PX = 25.0
#: The servos the fault buttons reach: the elbow's cable, the shoulder's joint.
LOOSE_SERVO, BLOCKED_SERVO = SO101_IDS["elbow_flex"], SO101_IDS["shoulder_lift"]


def to_view(point) -> tuple[tuple[float, float], tuple[float, float]]:
    """A point (x, y, z) m of the base frame -> its pixel in the top and in the side panel."""
    x, y, z = (float(v) for v in point)
    return ((TOP_BASE_PX[0] - PX_PER_M * y, TOP_BASE_PX[1] - PX_PER_M * x),
            (SIDE_BASE_PX[0] + PX_PER_M * x, SIDE_BASE_PX[1] - PX_PER_M * z))


def from_view(px: float, py: float, point) -> np.ndarray:
    """A pixel of either panel -> the point it shows, the coordinate the panel hides kept from ``point``."""
    x, y, z = (float(v) for v in point)
    if px < PANEL_PX:
        return np.array([(TOP_BASE_PX[1] - py) / PX_PER_M, (TOP_BASE_PX[0] - px) / PX_PER_M, z])
    return np.array([(px - SIDE_BASE_PX[0]) / PX_PER_M, y, (SIDE_BASE_PX[1] - py) / PX_PER_M])


class SimulatedHandView(VBox):
    """Drag the simulated SO-101's gripper; cause its faults.

    Args:
        hand: the ``SimulatedHand`` on the simulated servos.
        title: what the view is (the arm taught, or a leader arm).

    Attributes:
        canvas: the top and side views (mouse and touch drags move the gripper).
        cable_button, loose_button, block_button: the faults.
        note: what the hand can do now.
        dragging: which panel's drag holds the gripper ("top", "side") or None.
        drawn_tool: (3,) m, the gripper point the views show (as of the last ``refresh``).
    """

    def __init__(self, hand: SimulatedHand, title: str = "Your hand on the simulated arm"):
        if not isinstance(hand, SimulatedHand):
            raise TypeError(f"hand: expected a SimulatedHand, got {type(hand).__name__}")
        if not isinstance(title, str):
            raise TypeError(f"title: expected text, got {type(title).__name__}")
        self.hand = hand
        self.bus: SimulatedBus = hand.bus
        self.dragging: str | None = None
        self.drawn_tool = np.full(3, np.nan)
        self._lock = threading.Lock()
        self.canvas = Canvas(width=WIDTH_PX, height=HEIGHT_PX,
                             layout=Layout(width=f"{WIDTH_PX}px", height=f"{HEIGHT_PX}px"))
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
        self.loose_button = Button(description="Loosen a servo's cable", icon="unlink",
                                   tooltip="The elbow's servo stops answering, as when its cable comes loose")
        self.block_button = Button(description="Block a joint", icon="ban",
                                   tooltip="The shoulder's servo is blocked: it overloads and drops its torque")
        self.cable_button.on_click(lambda _: self.pull_cable())
        self.loose_button.on_click(lambda _: self.loosen_cable())
        self.block_button.on_click(lambda _: self.block_joint())
        self.note = HTML("")
        heading = f"<b>{title}</b><br><small>from above (left) and from the side (right): drag the gripper</small>"
        super().__init__([HTML(heading), self.canvas, self.note,
                          HBox([self.cable_button, self.loose_button, self.block_button],
                               layout=Layout(flex_flow="row wrap"))],
                         layout=Layout(padding="4px", border="1px solid #999999", width=f"{WIDTH_PX + 14}px"))
        self.refresh()

    # ------------------------------------------------------------------ faults
    def pull_cable(self) -> None:
        """The port closes; the servos keep their state."""
        self.bus.pull_cable()
        self.cable_button.disabled = True
        self.refresh()

    def loosen_cable(self) -> None:
        """The elbow's servo stops answering."""
        self.bus.silence(LOOSE_SERVO)
        self.loose_button.disabled = True

    def block_joint(self) -> None:
        """The shoulder's servo overloads and drops its torque."""
        self.bus.overload(BLOCKED_SERVO, time.monotonic())
        self.block_button.disabled = True

    # ------------------------------------------------------------------ drawing
    def refresh(self) -> None:
        """Draw the arm as it is now (whoever moved it: the hand, or the arm by itself)."""
        with self._lock:
            q = self.hand.joints()
            points = self.hand.kinematics.chain.frame_origins(q)
            self.drawn_tool = points[-1].copy()
            limp = self.hand.limp
            c = self.canvas
            with hold_canvas():
                c.clear()
                c.fill_style = "#ffffff"
                c.fill_rect(0, 0, WIDTH_PX, HEIGHT_PX)
                c.stroke_style = "#bbbbbb"
                c.line_width = 1
                c.stroke_line(PANEL_PX, 0, PANEL_PX, HEIGHT_PX)
                c.stroke_line(PANEL_PX, SIDE_BASE_PX[1], WIDTH_PX, SIDE_BASE_PX[1])  # the table, side on
                views = [to_view(p) for p in points]
                for panel in (0, 1):
                    c.stroke_style = "#888888"
                    c.line_width = 4
                    for a, b in zip(views[:-1], views[1:]):
                        c.stroke_line(*a[panel], *b[panel])
                    c.fill_style = "#444444"
                    c.fill_circle(*views[0][panel], 5)
                    c.fill_style = "#000000" if limp else "#7f7f7f"
                    c.fill_circle(*views[-1][panel], 7)
                c.fill_style = "#000000"
                c.font = "11px sans-serif"
                x, y, z = points[-1]
                c.fill_text(f"gripper at ({1000 * x:.0f}, {1000 * y:.0f}, {1000 * z:.0f}) mm", 4, 12)
        if self.bus.disconnected:
            self.note.value = "<i>The cable is pulled: the arm no longer hears the computer.</i>"
        elif limp:
            self.note.value = "<i>The torque is off: drag the gripper.</i>"
        else:
            self.note.value = "<i>The servos hold the arm: it does not give way.</i>"

    # ------------------------------------------------------------------ pointer
    def _down(self, px, py) -> None:
        top, side = to_view(self.hand.tool_point())
        grip = top if px < PANEL_PX else side
        near = float(np.hypot(px - grip[0], py - grip[1])) <= GRAB_PX
        self.dragging = ("top" if px < PANEL_PX else "side") if near else None
        if self.dragging:
            self._move(px, py)

    def _move(self, px, py) -> None:
        if self.dragging is None:
            return
        # The panel the drag began in: a pointer sliding over the divide keeps moving the same way.
        px = min(px, PANEL_PX - 1.0) if self.dragging == "top" else max(px, PANEL_PX + 1.0)
        self.hand.move_tool_to(from_view(px, py, self.hand.tool_point()))
        self.refresh()

    def _up(self, px, py) -> None:
        self.dragging = None
        self.refresh()


__all__ = ["SimulatedHandView", "from_view", "to_view"]
