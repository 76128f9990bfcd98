"""The UR5's reproduction stepped by pinocchio from Python: the independent reference.

The same URDF loaded by pinocchio (``pin.buildModelFromUrdf``), the same controller written
here again with pinocchio's quantities (its tool Jacobian, ``crba``, ``computeGeneralizedGravity``)
and numpy's solver, the same hold-and-RK4 scheme at 1 kHz with pinocchio's articulated-body
algorithm (``aba``) as the dynamics. ``tests/core/test_serial_chain.py`` checks the compiled
rollout against it; ``benchmarks/bench_ur5.py`` times it. Needs the ``test`` or ``bench`` extra.
"""

from __future__ import annotations

import numpy as np
import pinocchio

from .urdf import EXAMPLE_ROBOT_DATA, example_robot_data_urdf


class PinocchioUR5:
    """pinocchio's model of the UR5 and a Python stepper of the tool-velocity controller.

    Args:
        plant: the ``UR5Plant`` whose controller settings (gain, damping, conveyor) to copy.
    """

    def __init__(self, plant):
        self.plant = plant
        self.model = pinocchio.buildModelFromUrdf(str(example_robot_data_urdf("ur5")))
        self.data = self.model.createData()
        self.tool = self.model.getFrameId(EXAMPLE_ROBOT_DATA["ur5"][1])

    def tool_point(self, q) -> np.ndarray:
        pinocchio.forwardKinematics(self.model, self.data, q)
        pinocchio.updateFramePlacements(self.model, self.data)
        return self.data.oMf[self.tool].translation.copy()

    def torque(self, q, qd, velocity) -> np.ndarray:
        """The controller's held torque, from pinocchio's J, M and g."""
        model, data, plant = self.model, self.data, self.plant
        pinocchio.computeJointJacobians(model, data, q)
        pinocchio.updateFramePlacements(model, data)
        J = pinocchio.getFrameJacobian(model, data, self.tool, pinocchio.LOCAL_WORLD_ALIGNED)[:3]
        mass = pinocchio.crba(model, data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        gravity = pinocchio.computeGeneralizedGravity(model, data, q)
        reference = J.T @ np.linalg.solve(J @ J.T + plant.damping**2 * np.eye(3), velocity)
        over = np.abs(reference) / model.velocityLimit
        if over.max() > 1.0:
            reference = reference / over.max()
        tau = gravity + mass @ (plant.velocity_gain * (reference - qd))
        return np.clip(tau, -model.effortLimit, model.effortLimit)

    def rollout(self, theta, start, duration: float) -> np.ndarray:
        """The states (T, D) of a 10 s (``duration``) reproduction of the policy theta (3, S) at 1 kHz."""
        plant, model, data = self.plant, self.model, self.data
        n = model.nv
        dt = 1.0 / plant.control_rate
        n_steps = int(round(duration * plant.control_rate))
        speed = plant.conveyor.speed if plant.conveyor is not None else None
        x = np.array(start, dtype=float)
        states = np.empty((n_steps + 1, len(x)))

        def derivative(state, tau):
            acceleration = pinocchio.aba(model, data, state[:n], state[n:2 * n], tau)
            parts = [state[n:2 * n], acceleration] + ([[speed]] if speed is not None else [])
            return np.concatenate(parts)

        for k in range(n_steps + 1):
            states[k] = x
            if k == n_steps:
                break
            q, qd = x[:n], x[n:2 * n]
            features = np.concatenate([self.tool_point(q), x[2 * n:], [1.0]])
            tau = self.torque(q, qd, theta @ features)
            k1 = derivative(x, tau)
            k2 = derivative(x + 0.5 * dt * k1, tau)
            k3 = derivative(x + 0.5 * dt * k2, tau)
            k4 = derivative(x + dt * k3, tau)
            x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        return states
