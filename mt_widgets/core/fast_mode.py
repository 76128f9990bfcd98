"""The one switch that shortens long work when notebooks run under test.

Set ``MT_WIDGETS_FAST=1`` (the test command does) and notebooks use fewer participants,
shorter reproductions and fewer simulated studies. Cells are never skipped: every cell runs,
on smaller inputs.
"""

from __future__ import annotations

import os

ENVIRONMENT_VARIABLE = "MT_WIDGETS_FAST"


def running_under_test() -> bool:
    """True when ``MT_WIDGETS_FAST`` is set to anything but "", "0", "false" or "no"."""
    return os.environ.get(ENVIRONMENT_VARIABLE, "").strip().lower() not in ("", "0", "false", "no")
