"""Property: no sequence of API calls, targets or learnt-skill rollouts makes the connector
send a move outside the safety envelope, or a malformed line. Every line the simulated arm
receives is recorded and checked."""

from __future__ import annotations

import math
import re

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mt_widgets.hardware import SafetyEnvelope, SwiftPro, SwiftProError, UnsafeMoveError

from .helpers import device_of, sim_url

ENVELOPE = SafetyEnvelope()
MOVE = re.compile(r"^#\d+ (G\d+)((?: [A-Z][-+]?\d+(?:\.\d+)?)*)$")

coordinate = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-400, 400),
    st.floats(100, 320),
    st.sampled_from([135.0, 310.0, 134.99999, 310.00001, 40.0, 120.0, 39.99999, 1e-5, -0.0]),
)
speed = st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True), st.floats(0, 150))
action = st.one_of(
    st.tuples(st.just("move"), coordinate, coordinate, st.one_of(st.none(), coordinate), speed),
    st.tuples(st.just("polar"), st.floats(100, 330), st.floats(-80, 80), st.floats(30, 130), speed),
    st.tuples(st.just("skill"), st.lists(st.floats(-1.5, 1.5), min_size=6, max_size=6),
              st.floats(10, 35), st.floats(-20, 20)),
    st.tuples(st.sampled_from(["stop", "position", "detach", "attach", "beep", "reports"])),
)


def check_sent(lines: list[str]) -> int:
    moves = 0
    for line in lines:
        assert len(line) <= 80 and not set(line) & set("?!~@\x18"), line
        assert "e" not in line.lower(), line  # no exponent anywhere
        m = MOVE.match(line)
        if not m:
            continue
        word, params = m.group(1), dict((tok[0], float(tok[1:])) for tok in m.group(2).split())
        if word in ("G0", "G1"):
            moves += 1
            assert {"X", "Y", "Z", "F"} <= params.keys(), line
            assert ENVELOPE.contains(params["X"], params["Y"], params["Z"]), line
            assert 0 < params["F"] <= ENVELOPE.max_speed_mm_s, line
        else:
            assert word not in ("G2201", "G2204", "G2205"), line  # relative/polar moves are never used
    return moves


def rollout_cm(theta: list[float], r1: float, r2: float, steps: int = 15) -> list[tuple[float, float]]:
    """A uArm-style learnt skill r <- r + Theta @ (r1, r2, 1), in cm (docs/design.md, "The uArm skills")."""
    th = np.asarray(theta).reshape(2, 3)
    r = np.array([r1, r2])
    out = []
    for _ in range(steps):
        r = r + th @ np.array([r[0], r[1], 1.0])
        out.append((float(r[0]), float(r[1])))
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(action, max_size=12))
def test_no_sequence_of_calls_sends_a_move_outside_the_envelope(actions):
    with SwiftPro(sim_url(motion_scale=0), timeout=0.5) as arm:
        for act in actions:
            try:
                if act[0] == "move":
                    arm.move_to(act[1], act[2], act[3], speed=act[4])
                elif act[0] == "polar":
                    r, yaw, z, v = act[1:]
                    arm.move_to(r * math.cos(math.radians(yaw)), r * math.sin(math.radians(yaw)), z, speed=v)
                elif act[0] == "skill":
                    for x_cm, y_cm in rollout_cm(*act[1:]):
                        arm.move_to(10 * x_cm, 10 * y_cm)
                elif act[0] == "stop":
                    arm.stop()
                elif act[0] == "position":
                    arm.position()
                elif act[0] == "detach":
                    arm.detach()
                elif act[0] == "attach":
                    arm.attach()
                elif act[0] == "beep":
                    arm.beep()
                else:
                    arm.set_position_reports(0.05)
            except (UnsafeMoveError, SwiftProError):
                pass
        check_sent(device_of(arm).received_lines)


def test_the_checker_catches_a_move_outside_the_envelope():
    # The property above is only as good as its checker: it must reject bad lines.
    assert check_sent(["#1 G1 X200 Y0 Z80 F50"]) == 1
    for bad in ["#2 G1 X100 Y0 Z80 F50", "#3 G1 X200 Y0 Z80 F500", "#4 G2204 X1 Y0 Z0 F10",
                "#5 G1 X200 Y0 Z1e-05 F50"]:
        try:
            check_sent([bad])
        except AssertionError:
            continue
        raise AssertionError(f"checker accepted {bad!r}")
