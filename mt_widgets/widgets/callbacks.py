"""Callbacks whose errors reach the caller.

ipywidgets' ``CallbackDispatcher`` catches every exception a callback raises and only prints
it. Where a callback records data (the study log writes a demonstration), the widget must
know that it failed, so that it neither shows guidance for nor counts a demonstration that
is not on disk: ``Callbacks`` calls each callback in order and lets the first error through.
"""

from __future__ import annotations

from collections.abc import Callable

from mt_widgets.core.validation import as_bool


class Callbacks:
    """An ordered set of callbacks; calling it calls each, and an exception stops it and propagates.

    The same registration call as ipywidgets' ``CallbackDispatcher``, so widgets keep their
    ``on_...(callback, remove=False)`` methods.
    """

    def __init__(self):
        self.callbacks: list[Callable] = []

    def register_callback(self, callback: Callable, remove: bool = False) -> None:
        """Adds ``callback`` (once), or removes it with ``remove=True``."""
        if not callable(callback):
            raise ValueError(f"callback: expected a callable, got {type(callback).__name__}")
        if as_bool("remove", remove):
            if callback in self.callbacks:
                self.callbacks.remove(callback)
        elif callback not in self.callbacks:
            self.callbacks.append(callback)

    def __call__(self, *args, **kwargs) -> None:
        # A copy: a callback may (un)register others while it runs.
        for callback in list(self.callbacks):
            callback(*args, **kwargs)

    def __len__(self) -> int:
        return len(self.callbacks)
