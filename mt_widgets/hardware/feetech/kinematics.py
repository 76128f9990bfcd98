"""The one place the SO-101's connector uses a kinematic model: the tool point and the links'
points over the table, and the joint angles that put the tool point at a target.

The model is a serial chain of the five arm joints to the gripper frame
(:class:`mt_widgets.core.serial_chain.SerialChain`, built from the SO-101's URDF by whoever
makes the connector); this adapter uses only its ``joint_names``, ``lower``/``upper``,
``frame_origins``, ``forward_kinematics`` and ``jacobian``, so a change of the chain's engine
touches this file alone.
"""

from __future__ import annotations

import numpy as np

from .arm import ARM_JOINTS


class ArmKinematics:
    """The SO-101 arm's points in the base frame (m), from its five joint angles (rad).

    Args:
        chain: a serial chain whose joints are, in order, the SO-101's arm joints.
    """

    def __init__(self, chain):
        names = tuple(getattr(chain, "joint_names", ()))
        if names != ARM_JOINTS:
            raise ValueError(f"chain: expected the SO-101's joints {ARM_JOINTS} to the gripper frame, got {names}")
        self.chain = chain

    @property
    def limits(self) -> dict[str, tuple[float, float]]:
        """The URDF's joint limits (rad)."""
        return {name: (float(lo), float(hi)) for name, lo, hi in zip(ARM_JOINTS, self.chain.lower, self.chain.upper)}

    def points(self, q) -> np.ndarray:
        """The links' points that may touch the table, from the shoulder lift to the tool point:
        (..., 5) rad -> (..., 6, 3) m (the base and the shoulder pan sit on the table)."""
        return self.chain.frame_origins(np.asarray(q, dtype=float))[..., 2:, :]

    def tool_point(self, q) -> np.ndarray:
        """The gripper frame's origin: (..., 5) rad -> (..., 3) m."""
        return self.chain.forward_kinematics(np.asarray(q, dtype=float))

    def solve(self, target, start, tolerance: float = 1e-4, iterations: int = 200) -> np.ndarray | None:
        """Joint angles near ``start`` that put the tool point at ``target`` (m), within the
        URDF's limits and ``tolerance`` (m); None if none is found (out of reach).

        Damped least squares from ``start``, the wrist roll kept where it is (it does not move
        the tool point much and the gripper's orientation is the user's)."""
        q = np.array(start, dtype=float)
        target = np.asarray(target, dtype=float)
        lower, upper = np.asarray(self.chain.lower), np.asarray(self.chain.upper)
        for _ in range(iterations):
            error = target - self.tool_point(q)
            if np.linalg.norm(error) < tolerance:
                return q
            J = self.chain.jacobian(q)[:, :4]
            step = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(3), error)
            q[:4] = np.clip(q[:4] + step, lower[:4], upper[:4])
        return q if np.linalg.norm(target - self.tool_point(q)) < tolerance else None
