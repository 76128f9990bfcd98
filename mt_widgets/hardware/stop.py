"""The one stop mechanism of the arm, shared by the connector and the bridge.

A :class:`StopSwitch` counts presses (the *generation*) and remembers whether a press has
not been answered by a resume yet (*held*). Whoever drives the arm reads the generation
when a job begins and sends each move only if it has not changed, checked and sent under
the switch's lock (:meth:`StopSwitch.unless_pressed_since`): a press then either finds the
move on the wire (and the connector cuts it) or the move finds the press (and is never
sent). The connector (:class:`mt_widgets.hardware.SwiftPro`) owns one switch; the bridge
(:class:`mt_widgets.hardware.bridge.UArmBridge`) uses the same one, so "stopped until
someone resumes" means the same thing on both.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

from .errors import SwiftProStopped

T = TypeVar("T")


class StopSwitch:
    """Press to stop; release (resume) only if nobody pressed since the resume began."""

    def __init__(self) -> None:
        # The one lock of the switch: a press, the check-and-send of a move and the
        # compare-and-release of a resume exclude each other. Never held while waiting for
        # the arm (only while one short line is written), so a press never waits long.
        self._lock = threading.Lock()
        self._generation = 0
        # Set by every press, cleared by release(); an Event so that a job can read it
        # without the lock (a stale "clear" is caught by the generation at send time).
        self._held = threading.Event()

    @property
    def generation(self) -> int:
        """How many times the switch was pressed."""
        return self._generation

    @property
    def held(self) -> bool:
        """True from a press until a :meth:`release` that saw no press since it began."""
        return self._held.is_set()

    def press(self, while_locked: Callable[[], T] | None = None) -> T | None:
        """Start a new generation and hold the switch.

        Args:
            while_locked: run under the lock right after the count goes up (the connector
                takes the move now on the wire, which the press must cut).

        Returns:
            What ``while_locked`` returned, or None.
        """
        with self._lock:
            self._generation += 1
            self._held.set()
            return while_locked() if while_locked is not None else None

    def check(self, generation: int, what: str) -> None:
        """Raise :class:`SwiftProStopped` if the switch was pressed since ``generation``."""
        if generation != self._generation:
            raise SwiftProStopped(f"{what} was not sent: stop() came before it")

    @contextmanager
    def unless_pressed_since(self, generation: int, what: str) -> Iterator[None]:
        """Hold the lock for the body, which sends ``what``, if no press came since
        ``generation``; raise :class:`SwiftProStopped` (nothing sent) otherwise."""
        with self._lock:
            self.check(generation, what)
            yield

    def release(self, seen: int, while_locked: Callable[[], None] | None = None) -> None:
        """End the hold if no press came since generation ``seen`` (when the resume began).

        Args:
            seen: the generation read when the resume began.
            while_locked: run under the lock just before the hold ends (the connector's
                own un-pause), so that a press cannot fall between the two.

        Raises:
            SwiftProStopped: a press came since ``seen``; the switch stays held.
        """
        with self._lock:
            if self._generation != seen:
                raise SwiftProStopped("resume was cut short by stop(): the arm stays stopped")
            if while_locked is not None:
                while_locked()
            self._held.clear()
