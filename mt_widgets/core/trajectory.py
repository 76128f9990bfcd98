"""What a rollout returns: one trajectory, or a batch of them stepped together."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Trajectory:
    """One rollout of a policy on a plant.

    Attributes:
        times: (T,) seconds from the start.
        states: (T, state_dim) plant states (sim: q1, q2, qd1, qd2 in rad, rad/s; uArm: r1, r2 in cm).
        positions: (T, 2) end-effector positions in ``units``.
        velocities: (T, 2) end-effector velocities in ``units`` per second (zero for kinematic plants).
        actions: (T, R) the action applied from each sample on (sim: N; uArm: cm per step).
        diverged: True when the rollout was stopped because the state left its bounds or
            stopped being finite; the arrays then end at the last valid sample.
        diverged_at: the time in seconds at which divergence was detected, or None.
        units: length unit of ``positions`` ("m" or "cm").
        stop_reason: why a stopped rollout stopped, in words ("joint limit", "table",
            "self-collision", "joint speed limit", "diverged"), or "" when it ran to the end or the
            plant gives no reasons.
    """

    times: np.ndarray
    states: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    actions: np.ndarray
    diverged: bool
    diverged_at: float | None
    units: str
    stop_reason: str = ""

    def __len__(self) -> int:
        return len(self.times)

    @property
    def final_position(self) -> np.ndarray:
        return self.positions[-1]


@dataclass(frozen=True)
class TrajectoryBatch:
    """B rollouts stepped together, on one time grid.

    The arrays have a leading batch axis. A rollout that diverged is frozen at its last valid
    sample (its state repeated, its action zero) so the arrays stay finite; ``lengths`` says
    how many samples of each are real and ``batch[i]`` gives the i-th as a ``Trajectory``
    cut to its real samples.
    """

    times: np.ndarray          # (T,)
    states: np.ndarray         # (B, T, state_dim)
    positions: np.ndarray      # (B, T, 2), or (B, T, 3) for an arm in space
    velocities: np.ndarray     # (B, T, 2), or (B, T, 3)
    actions: np.ndarray        # (B, T, R)
    diverged: np.ndarray       # (B,) bool: stopped early (diverged, or a safety stop of the plant)
    diverged_at: np.ndarray    # (B,) seconds, NaN where the rollout did not diverge
    lengths: np.ndarray        # (B,) number of valid samples
    units: str
    stop_reasons: tuple[str, ...] = ()  # (B,) ``Trajectory.stop_reason`` of each, or () for none given

    def __len__(self) -> int:
        return self.states.shape[0]

    def __getitem__(self, index: int) -> Trajectory:
        if not -len(self) <= index < len(self):
            raise IndexError(f"index: expected an integer in [{-len(self)}, {len(self)}), got {index}")
        n = int(self.lengths[index])
        at = float(self.diverged_at[index])
        return Trajectory(self.times[:n], self.states[index, :n], self.positions[index, :n],
                          self.velocities[index, :n], self.actions[index, :n], bool(self.diverged[index]),
                          None if np.isnan(at) else at, self.units,
                          self.stop_reasons[index] if self.stop_reasons else "")

    def __iter__(self):
        return (self[i] for i in range(len(self)))
