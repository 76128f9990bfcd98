"""Helpers for the uArm app tests: simulated arms, the G-code lines they received."""

from __future__ import annotations

import re
import time

# Importing the package (for SwiftPro) also registers the uarm-sim:// URL handler.
from mt_widgets.hardware import SwiftPro

_MOVE = re.compile(r"^#\d+ (G0|G1|G2204|G2201|G2205) (.*)$")


def sim_url(**options) -> str:
    """A uarm-sim:// URL: 10 ms boot and moves 100x faster than real unless overridden."""
    merged = {"boot": "0.01", "motion_scale": "0.01", **{k: str(v) for k, v in options.items()}}
    return "uarm-sim://?" + "&".join(f"{k}={v}" for k, v in merged.items())


def device_of(arm: SwiftPro):
    """The simulated arm behind a connected SwiftPro on a uarm-sim:// port."""
    return arm._ser.device


def received(arm: SwiftPro) -> list[str]:
    return list(device_of(arm).received_lines)


def parse_fields(text: str) -> dict[str, float]:
    return {word[0]: float(word[1:]) for word in text.split()}


def moves(lines: list[str]) -> list[dict[str, float]]:
    """The move commands among ``lines``, as {"X": .., "Y": .., "Z": .., "F": ..}."""
    out = []
    for line in lines:
        match = _MOVE.match(line)
        if match:
            out.append({"word": match.group(1), **parse_fields(match.group(2))})
    return out


def is_move(line: str) -> bool:
    return _MOVE.match(line) is not None


def is_stop(line: str) -> bool:
    return re.match(r"^#\d+ (S1100|S1000 V0|G2203)\b", line) is not None


def wait_until(condition, timeout: float = 10.0, what: str = "the condition") -> None:
    """Poll ``condition()`` until true; fail after ``timeout`` s (a guard against hangs only)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} did not happen within {timeout} s")
        time.sleep(0.002)


def arm_is_moving(arm: SwiftPro) -> bool:
    """Whether the simulated arm behind ``arm`` has a move under way now."""
    return device_of(arm).moving_at(time.monotonic())
