"""Buttons that act once: a double click, or a press while the first is being handled, does nothing.

A browser sends each click of a double click as its own message, and both reach the kernel
before the first one's ``disabled = True`` reaches the page; a handler that does not look
would run the step's action twice (the second time on the next step, which the session
refuses). So every study button belongs to a ``Choice``: the buttons of one screen, of which
the first press is the answer and every later press is ignored (``reopen`` offers them again,
e.g. after a form said what to fix).
"""

from __future__ import annotations

from collections.abc import Callable

from ipywidgets import Button, Layout

from mt_widgets.widgets.animation import kernel_loop


class Choice:
    """The buttons of one screen; the first press of any of them runs its action, alone."""

    def __init__(self):
        self.buttons: list[Button] = []
        #: True once a button was pressed (until ``reopen``).
        self.made = False

    def button(self, description: str, action: Callable[[], None], style: str = "primary") -> Button:
        # align_self: a button keeps its own width in the page's column instead of spanning it.
        button = Button(description=description, button_style=style,
                        layout=Layout(width="auto", min_width="160px", align_self="flex-start"))

        def pressed(_):
            if self.made or button.disabled:
                return
            self.made = True
            for each in self.buttons:
                each.disabled = True
            action()

        button.on_click(pressed)
        self.buttons.append(button)
        return button

    def reopen(self) -> None:
        """Offers the buttons again (the action did not move the page on)."""
        self.made = False
        for each in self.buttons:
            each.disabled = False


def step_button(description: str, action: Callable[[], None], style: str = "primary") -> Button:
    """A button of its own ``Choice``: it acts on its first press only."""
    return Choice().button(description, action, style)


def enable_after(button: Button, seconds: float) -> None:
    """Enables ``button`` once ``seconds`` (a reproduction playing) and a margin have passed.

    The participant watches the whole reproduction (it is the study's feedback), and the
    browser's canvas manager plays an animation's frames in order, so a new episode's drawing
    is never queued behind the old one's frames while its view is replaced. Without the
    kernel's event loop (code driving the app, kernel-free tests) it is enabled at once.
    """
    button.disabled = True
    loop = kernel_loop()
    if loop is None or seconds <= 0:
        button.disabled = False
        return
    loop.call_later(seconds + 0.75, lambda: setattr(button, "disabled", False))
