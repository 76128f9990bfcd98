"""Helpers for the uArm app tests: simulated arms, the G-code lines they received."""

from __future__ import annotations

import re

# The simulated-arm helpers of the connector's tests, shared rather than copied (re-exported).
from hardware.helpers import InThread, arm_is_moving, device_of, sim_url, wait_until
from hardware.helpers import sent_lines as received
from protocols import phase, protocol_toml

#: A protocol of one uArm episode (tests/uarm_app/test_app.py, test_hand.py).
ONE_EPISODE = protocol_toml("one-uarm-episode", [phase("P1", "uarm-point", instructions="Skill 1.")], assignment_seed=3)


def _click(app, description):
    """Clicks the study page's button ``description`` (fails naming what the page holds instead)."""
    from ipywidgets import Button

    buttons = [w for w in app.body.children if isinstance(w, Button) and w.description == description]
    assert buttons, f"no {description!r} button among {[type(w).__name__ for w in app.body.children]}"
    buttons[0].click()


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
    return re.match(r"^#\d+ (S1100|S1000 V0|M2000)\b", line) is not None


__all__ = ["ONE_EPISODE", "InThread", "_click", "arm_is_moving", "device_of", "is_move", "is_stop", "moves",
           "parse_fields", "received", "sim_url", "wait_until"]
