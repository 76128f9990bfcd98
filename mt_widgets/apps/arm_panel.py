"""What a participant sees of a physical arm beside the episode: where it is, Stop, messages.

One panel for every arm a study app drives (the uArm's ``uarm_study``, the SO-101's
``so101_study``): the Stop button halts the arm at once, Resume lets it move again, "Teach by
hand" releases it for a demonstration by hand, and the message line says what the arm is doing
or what went wrong, in words.
"""

from __future__ import annotations

import html

from ipywidgets import HTML, Button, HBox, Label, Layout, VBox


class ArmPanel(VBox):
    """What the participant sees of the arm: where it is, a Stop button, messages.

    Attributes:
        position_label: ``"arm at x = 200.0 mm, y = 0.0 mm"`` after every move.
        stop_button: halts the arm immediately.
        resume_button: shown after a stop; lets the arm move again.
        hand_button: "Teach by hand": releases the arm for a demonstration by hand.
        message: what the arm is doing, or what went wrong.
    """

    def __init__(self, port_text: str):
        self.position_label = Label("arm position unknown")
        self.stop_button = Button(description="Stop the arm", button_style="danger", icon="stop",
                                  layout=Layout(width="200px", height="48px"))
        self.resume_button = Button(description="Resume arm", icon="play", layout=Layout(display="none"))
        self.hand_button = Button(description="Teach by hand (H)", icon="hand-paper-o",
                                  tooltip="Release the arm and move its tip to show the step (key: H)",
                                  layout=Layout(display="none", width="200px", height="48px"))
        self.message = HTML("")
        self.port = HTML(f"<small>{html.escape(port_text)}</small>")
        super().__init__([HBox([self.stop_button, self.resume_button, self.hand_button, self.position_label],
                               layout=Layout(align_items="center")), self.message, self.port],
                         layout=Layout(padding="2px"))

    def say(self, text: str, error: bool = False) -> None:
        colour = "#b00020" if error else "#333333"
        weight = "bold" if error else "normal"
        self.message.value = (f"<div style='color:{colour};font-weight:{weight};max-width:900px'>"
                              f"{html.escape(text)}</div>")

    def show_position(self, *coordinates_mm: float) -> None:
        """The tool's position (x, y[, z]) in mm."""
        names = ("x", "y", "z")[:len(coordinates_mm)]
        self.position_label.value = "arm at " + ", ".join(f"{n} = {v:.1f} mm" for n, v in zip(names, coordinates_mm))


__all__ = ["ArmPanel"]
