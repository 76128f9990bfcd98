"""A progress line for long in-silico runs, printed to stderr.

No widget here: the in-silico layer runs in scripts, tests and worker processes alike. A
notebook sees the same line under its cell.
"""

from __future__ import annotations

import sys
import time

from mt_widgets.core.validation import as_bool


class Progress:
    """A text progress line: "description done/total (elapsed s)", a few times a second at most.

    Args:
        total: steps in all.
        description: a short label.
        enabled: False makes every call a no-op.
    """

    def __init__(self, total: int, description: str = "", enabled: bool = True):
        self.total, self.description, self.enabled = max(int(total), 1), description, as_bool("enabled", enabled)
        self.done, self._started, self._last_print = 0, time.perf_counter(), 0.0

    def update(self, steps: int = 1) -> None:
        if not self.enabled:
            return
        self.done = min(self.done + steps, self.total)
        now = time.perf_counter()
        # At most a few lines a second, and always the last one.
        if now - self._last_print > 0.5 or self.done == self.total:
            self._last_print = now
            elapsed = now - self._started
            print(f"\r{self.description} {self.done}/{self.total} ({elapsed:.1f} s)", end="", file=sys.stderr,
                  flush=True)
            if self.done == self.total:
                print(file=sys.stderr)
