"""Teaching by moving the arm by hand (kinesthetic teaching) on the Swift Pro.

One :class:`HandMove` is one demonstration at one query state:

1. :meth:`HandMove.begin`: the arm goes to the query state under its own power (a known
   pose, inside the envelope), ``@3`` position reports start, and the steppers are released
   through the firmware's detach (M2019): the person can now move the tip.
2. :meth:`HandMove.poll`: the demonstrated action is the measured displacement of the tip
   since the release, read from the position reports (both firmwares read the joint sensors
   for them, docs/uarm-protocol.md "The command table"), in the plant's frame (cm), limited
   to the plant's step limit as a reproduction step is (``limit_step``).
3. :meth:`HandMove.end`: the steppers are attached again, the firmware re-reads where the
   arm is (3.x needs a command for it, ``Dialect.refresh_position``), the reports stop, and
   the arm is brought back to the known pose, the query state, before anything else moves
   it: an arm the hand left outside the envelope comes in with ``UArmBridge.home_if_outside``
   (slowly, every leg checked), then travels to the state. Nothing here commands a point
   outside the envelope: every move goes through the connector's checks.

A failure (a pulled cable, an error reply) leaves the arm released, which is safe: a limp
arm cannot move by itself. Confirmed demonstrations are the caller's (the study runner logs
them before the arm does anything), so none is lost.
"""

from __future__ import annotations

import math

import numpy as np

from mt_widgets.core import SKILLS

from .bridge import UArmBridge, arm_to_plant_cm
from .errors import SwiftProDisconnected, SwiftProTimeout

#: Seconds between ``@3`` reports during a hand move (20 a second: a smooth arrow).
REPORT_INTERVAL_S = 0.05


def limit_step(displacement_cm, max_step_cm: float) -> np.ndarray:
    """Scale a displacement (any number of coordinates) down to at most ``max_step_cm`` long
    (the plant's step limit), keeping its direction, as ``UArmPlant.step`` limits an action."""
    d = np.asarray(displacement_cm, dtype=float).reshape(-1)
    length = float(np.linalg.norm(d))
    if length > max_step_cm > 0:
        d = d * (max_step_cm / length)
    return d


class HandMove:
    """One kinesthetic demonstration at one query state.

    Args:
        bridge: the ``UArmBridge`` of the connected arm.
        state_cm: the query state (r1, r2) in cm: where the hand move starts and where the
            arm returns.
        max_step_cm: the step limit on the demonstrated action (default: the uArm plant's,
            5 cm).
        report_interval_s: seconds between position reports.

    Attributes:
        start_mm: the measured tool position when the steppers were released.
        latest_mm: the latest measured tool position.
        reports: how many position reports came in.
        released: whether the steppers are released now.
    """

    def __init__(self, bridge: UArmBridge, state_cm, *, max_step_cm: float | None = None,
                 report_interval_s: float = REPORT_INTERVAL_S):
        if not isinstance(bridge, UArmBridge):
            raise TypeError(f"bridge: expected a UArmBridge, got {type(bridge).__name__}")
        state = np.asarray(state_cm, dtype=float)
        if state.shape != (2,) or not np.all(np.isfinite(state)):
            raise ValueError(f"state_cm: expected a finite (r1, r2) in cm, got {state_cm!r}")
        plant_step = SKILLS["uarm-point"].plant.max_step_cm
        self.max_step_cm = float(plant_step if max_step_cm is None else max_step_cm)
        if not (math.isfinite(self.max_step_cm) and self.max_step_cm > 0):
            raise ValueError(f"max_step_cm: expected a positive number of cm, got {max_step_cm!r}")
        self.bridge = bridge
        self.arm = bridge.arm
        self.state_cm = state
        self.report_interval_s = float(report_interval_s)
        self.start_mm: tuple[float, float, float] | None = None
        self.latest_mm: tuple[float, float, float] | None = None
        self.reports = 0
        self.released = False

    # ------------------------------------------------------------------ the three stages
    def begin(self) -> None:
        """Go to the query state, start the position reports, release the steppers."""
        self.bridge.return_to(self.state_cm)
        self.arm.set_position_reports(self.report_interval_s)
        self.arm.drain_events()
        self.start_mm = self.arm.position()  # at rest, powered: the position is exact
        self.latest_mm = self.start_mm
        self.arm.detach()
        self.released = True

    def poll(self, timeout: float = 0.1) -> np.ndarray:
        """Take the position reports that came in (waiting up to ``timeout`` s for one) and
        return the demonstrated action so far, (Δr1, Δr2) cm, limited to the step limit.

        Raises:
            SwiftProDisconnected: the connection is gone (a pulled cable).
        """
        if self.start_mm is None:
            raise RuntimeError("poll: call begin() first")
        if not self.arm.connected:
            raise SwiftProDisconnected("the connection to the arm was lost during the hand move")
        try:
            event = self.arm.next_event("@3", timeout=timeout)
        except SwiftProTimeout:
            event = None
        events = [event] if event is not None else []
        events += [e for e in self.arm.drain_events() if e.kind == "@3"]
        for e in events:
            if {"X", "Y", "Z"} <= e.values.keys():
                self.latest_mm = (e.values["X"], e.values["Y"], e.values["Z"])
                self.reports += 1
        if not self.arm.connected:
            raise SwiftProDisconnected("the connection to the arm was lost during the hand move")
        return self.action_cm

    @property
    def displacement_cm(self) -> np.ndarray:
        """The measured displacement of the tip since the release, (Δr1, Δr2) cm, unlimited."""
        if self.start_mm is None or self.latest_mm is None:
            return np.zeros(2)
        return arm_to_plant_cm(self.latest_mm) - arm_to_plant_cm(self.start_mm)

    @property
    def action_cm(self) -> np.ndarray:
        """The demonstrated action: the displacement limited to ``max_step_cm``."""
        return limit_step(self.displacement_cm, self.max_step_cm)

    def end(self) -> None:
        """Attach the steppers, let the firmware re-read the position, stop the reports and
        bring the arm back to the query state (homing first if the hand left it outside)."""
        self.arm.attach()
        self.released = False
        self.arm.set_position_reports(None)
        self.bridge.return_to(self.state_cm)


__all__ = ["REPORT_INTERVAL_S", "HandMove", "limit_step"]
