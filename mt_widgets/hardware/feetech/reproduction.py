"""Playing a learnt skill's reproduction on the SO-101, inside its envelope.

The reproduction is a rollout of the learnt policy on the SO-101's kinematic plant: joint
angles over time. :func:`play_on_arm` sends it to the arm as joint moves through waypoints
``every`` seconds apart, each one a goal the envelope checks (range, table along the way,
speed) before a byte is sent, at the speed the rollout moved (within the envelope's). A goal
the envelope refuses ends the play there, with the arm holding at the waypoint before: a
learnt skill that would leave the safe workspace is shown on screen, never done by the arm.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import UnsafeMoveError
from .arm import ARM_JOINTS
from .connector import SO101, SO101Stopped
from .errors import SO101Error

#: Seconds of reproduction between two waypoints sent to the arm.
WAYPOINT_EVERY_S = 0.5
#: The slowest joint speed asked (rad/s): a waypoint the rollout barely moved to is still reached.
MIN_SPEED = 0.1


@dataclass
class PlayReport:
    """What happened when a reproduction was played on the arm.

    Attributes:
        waypoints: how many waypoints the play had.
        reached: how many the arm reached.
        stopped: the play was cut short by the emergency stop.
        error: what went wrong, in words (a fault, a goal the envelope refused), or "".
    """

    waypoints: int
    reached: int = 0
    stopped: bool = False
    error: str = ""

    @property
    def complete(self) -> bool:
        return self.reached == self.waypoints and not self.stopped and not self.error


def waypoints(times, states, every: float = WAYPOINT_EVERY_S) -> tuple[np.ndarray, np.ndarray]:
    """The rollout's samples about ``every`` s apart, the first and the last included.

    Args:
        times: (T,) s; states: (T, >= 5) the plant's states (the first five are the arm joints, rad).

    Returns:
        (K,) s and (K, 5) rad.
    """
    times = np.asarray(times, dtype=float)
    states = np.asarray(states, dtype=float)
    if times.ndim != 1 or states.ndim != 2 or len(times) != len(states) or len(times) == 0 \
            or states.shape[1] < len(ARM_JOINTS):
        raise ValueError(f"times, states: expected (T,) s and (T, >= {len(ARM_JOINTS)}) rad with T > 0, got "
                         f"{times.shape} and {states.shape}")
    if not (isinstance(every, (int, float)) and math.isfinite(every) and every > 0):
        raise ValueError(f"every: expected a positive number of seconds, got {every!r}")
    marks = np.arange(times[0], times[-1], every)
    index = np.unique(np.concatenate([np.searchsorted(times, marks), [len(times) - 1]]))
    return times[index], states[index, :len(ARM_JOINTS)]


def play_on_arm(arm: SO101, times, states, every: float = WAYPOINT_EVERY_S,
                on_waypoint: Callable[[int, np.ndarray], None] | None = None) -> PlayReport:
    """Play a reproduction (``Trajectory.times``, ``Trajectory.states``) on the arm.

    The arm first drives to the rollout's start. Faults and the stop end the play in the report
    (never raised): the arm then holds where it is (the connector's fault handling).

    Args:
        on_waypoint: ``callback(k, q)`` after waypoint k is reached.
    """
    if not isinstance(arm, SO101):
        raise TypeError(f"arm: expected a connected SO101, got {type(arm).__name__}")
    t, q = waypoints(times, states, every)
    report = PlayReport(waypoints=len(t))
    previous_time, previous = None, None
    try:
        arm.torque(True)
        for k, (time_s, goal) in enumerate(zip(t, q)):
            if previous is None:
                speed = 0.5
            else:
                needed = float(np.max(np.abs(goal - previous))) / max(time_s - previous_time, 1e-3)
                speed = min(arm.envelope.max_speed, max(MIN_SPEED, needed))
            arm.move_joints(dict(zip(ARM_JOINTS, (float(v) for v in goal))), speed=speed)
            report.reached = k + 1
            previous_time, previous = time_s, goal
            if on_waypoint is not None:
                on_waypoint(k, goal)
    except SO101Stopped:
        report.stopped = True
    except UnsafeMoveError as error:
        report.error = (f"The robot stopped its reproduction at {previous_time or 0.0:.1f} s: what it learnt would "
                        f"take it out of its safe workspace ({error}).")
    except SO101Error as error:
        report.error = f"The robot arm stopped during the reproduction: {error}"
    return report


__all__ = ["MIN_SPEED", "PlayReport", "WAYPOINT_EVERY_S", "play_on_arm", "waypoints"]
