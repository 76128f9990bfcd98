"""Teaching the SO-101 by moving it by hand (kinesthetic teaching), or with a leader arm.

One :class:`HandDemonstration` is one demonstration at one query state (joint angles, rad):

1. :meth:`HandDemonstration.begin`: the arm drives itself to the query state (a goal checked
   by the envelope, like every goal), then the hand's joints are read once as the start. Taught
   on the arm itself, its torque then goes off: the person moves the arm. Taught with a leader
   arm (a second SO-101 bus, LeRobot's ``so101_leader``), the leader's torque goes off and the
   follower keeps holding the query state.
2. :meth:`HandDemonstration.poll`: one SYNC_READ of the hand's joints. The demonstrated tool
   motion is where the tool is now less where it was at the start; with a leader arm, the
   leader's joint motion since the start applied at the query state (so a leader held in any
   pose teaches at the follower's query state). The action is that displacement over
   ``action_length`` (m per unit of action, the plant's drawing's arrow length): the arrow drawn
   from the tool ends where the hand brought it. A displacement longer than ``max_displacement``
   keeps its direction (``limit_step``).
3. :meth:`HandDemonstration.end`: the torque goes on (the arm holds where the hand left it) and
   the arm drives back to the query state, the envelope checking the way.

Every reading is kept in :attr:`HandDemonstration.samples` as it comes: a fault (raised by the
connector in words) loses none of them, and the last action stays the caller's to confirm. An
arm left limp by a fault is safe: it cannot move by itself.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..kinesthetic import limit_step
from .arm import ARM_JOINTS
from .connector import SO101

#: The longest tool displacement a demonstration takes (m): a hand sweeping across the table
#: would ask the arm for more than it can do in one step of teaching.
MAX_DISPLACEMENT_M = 0.15


class HandDemonstration:
    """One demonstration by hand at one query state.

    Args:
        arm: the connected ``SO101`` (the follower: it shows the query state and reproduces).
        query_state: (5,) rad, the arm joints of the query state.
        action_length: m of tool displacement per unit of action (``plant.drawing().action_length``).
        leader: a second connected ``SO101`` whose joints are the hand-held input, or None (the
            arm itself is moved by hand).
        max_displacement: the longest displacement taken (m).
        speed: joint speed (rad/s) of the moves to and back to the query state.

    Attributes:
        samples: [(seconds since begin, (5,) rad of the hand's joints)], every reading.
        start: (5,) rad, the hand's joints at the start.
        released: whether a torque is off (the arm's, or the leader's) for the hand.
    """

    def __init__(self, arm: SO101, query_state, action_length: float, *, leader: SO101 | None = None,
                 max_displacement: float = MAX_DISPLACEMENT_M, speed: float = 0.8):
        if not isinstance(arm, SO101):
            raise TypeError(f"arm: expected a connected SO101, got {type(arm).__name__}")
        if leader is not None and not isinstance(leader, SO101):
            raise TypeError(f"leader: expected a connected SO101 (the leader arm) or None, got {type(leader).__name__}")
        if leader is arm:
            raise ValueError("leader: expected a second arm on its own port, got the follower itself")
        q = np.asarray(query_state, dtype=float)
        if q.shape != (len(ARM_JOINTS),) or not np.all(np.isfinite(q)):
            raise ValueError(f"query_state: expected {len(ARM_JOINTS)} finite joint angles (rad), got {query_state!r}")
        for name, value in (("action_length", action_length), ("max_displacement", max_displacement),
                            ("speed", speed)):
            if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                    and value > 0):
                raise ValueError(f"{name}: expected a positive number, got {value!r}")
        self.arm, self.leader = arm, leader
        self.query_state = q
        self.action_length = float(action_length)
        self.max_displacement = float(max_displacement)
        self.speed = float(speed)
        self.samples: list[tuple[float, np.ndarray]] = []
        self.start: np.ndarray | None = None
        self.released = False
        self._t0 = 0.0
        self._start_tool = arm.kinematics.tool_point(q)

    @property
    def hand(self) -> SO101:
        """The arm whose joints are read: the leader, or the arm itself."""
        return self.leader if self.leader is not None else self.arm

    def _goal(self) -> dict[str, float]:
        return dict(zip(ARM_JOINTS, (float(v) for v in self.query_state)))

    # ------------------------------------------------------------------ the three stages
    def begin(self) -> None:
        """Drive to the query state, read the start, release the hand's joints."""
        self.arm.torque(True)
        self.arm.move_joints(self._goal(), speed=self.speed)
        self.hand.torque(False)
        self._t0 = time.monotonic()
        self.start = self._read()
        if self.leader is None:
            # The arm itself: the tool starts where the servos say it is, not where it was asked to go.
            self._start_tool = self.arm.kinematics.tool_point(self.start)
        self.released = True  # the start is read: what the hand does from now on is the demonstration

    def _read(self) -> np.ndarray:
        q = self.hand.positions()
        joints = np.array([q[j] for j in ARM_JOINTS])
        self.samples.append((time.monotonic() - self._t0, joints))
        return joints

    def poll(self) -> np.ndarray:
        """Read the hand's joints once and return the action so far (3,) (units of the plant's action)."""
        if self.start is None:
            raise RuntimeError("poll: call begin() first")
        self._read()
        return self.action

    @property
    def tool_point(self) -> np.ndarray:
        """(3,) m where the demonstration has brought the tool (at the query state for a leader)."""
        if self.start is None or not self.samples:
            return np.array(self._start_tool)
        latest = self.samples[-1][1]
        if self.leader is None:
            return self.arm.kinematics.tool_point(latest)
        return self.arm.kinematics.tool_point(self.query_state + (latest - self.start))

    @property
    def displacement(self) -> np.ndarray:
        """(3,) m, the tool's displacement since the start, limited to ``max_displacement``."""
        return limit_step(self.tool_point - self._start_tool, self.max_displacement)

    @property
    def action(self) -> np.ndarray:
        """(3,) the demonstrated action: the displacement over ``action_length``."""
        return self.displacement / self.action_length

    def end(self) -> None:
        """Torque on (the arm holds where the hand left it), then back to the query state."""
        if self.leader is None:
            self.arm.torque(True)
        self.released = False
        self.arm.move_joints(self._goal(), speed=self.speed)


__all__ = ["MAX_DISPLACEMENT_M", "HandDemonstration"]
