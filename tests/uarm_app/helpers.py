"""Helpers for the uArm app tests: simulated arms, the G-code lines they received."""

from __future__ import annotations

import re

# The simulated-arm helpers of the connector's tests, shared rather than copied (re-exported).
from hardware.helpers import InThread, arm_is_moving, device_of, sim_url, wait_until
from hardware.helpers import sent_lines as received

_MOVE = re.compile(r"^#\d+ (G0|G1|G2204|G2201|G2205) (.*)$")


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


__all__ = ["InThread", "arm_is_moving", "device_of", "is_move", "is_stop", "moves", "parse_fields", "received",
           "sim_url", "wait_until"]
