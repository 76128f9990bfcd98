"""pinocchio on the same URDF: the independent reference of the chain engine's numbers.

``pinocchio_chain`` loads a description's URDF with pinocchio (``pin.buildModelFromUrdf``) and
locks the joints the description locked (``buildReducedModel`` at zero), so both hold the same
chain; ``pinocchio_configuration`` writes a joint vector the way pinocchio stores it (a
continuous joint as its cosine and sine). ``PinocchioArm`` steps a dynamic arm's reproduction:
the same controller written here again with pinocchio's quantities (its tool Jacobian, ``crba``,
``computeGeneralizedGravity``) and numpy's solver, the same hold-and-RK4 scheme at 1 kHz with
pinocchio's articulated-body algorithm (``aba``) as the dynamics. ``tests/core/test_serial_chain.py``
checks the compiled engine against them; ``benchmarks/bench_ur5.py`` times the stepper. Needs
the ``test`` or ``bench`` extra.
"""

from __future__ import annotations

import numpy as np
import pinocchio

from .urdf import read_urdf


def pinocchio_chain(description: dict):
    """(model, data, tool frame id) of pinocchio for a description read by ``read_urdf``."""
    model = pinocchio.buildModelFromUrdf(description["source"])
    locked = [model.getJointId(name) for name in description["locked"]]
    if locked:
        model = pinocchio.buildReducedModel(model, locked, pinocchio.neutral(model))
    return model, model.createData(), model.getFrameId(description["tip"])


def pinocchio_configuration(model, q) -> np.ndarray:
    """pinocchio's configuration vector (nq,) for joint values q (nv,): a continuous joint as (cos, sin)."""
    out = np.empty(model.nq)
    for joint in model.joints[1:]:
        if joint.nq == 2 and joint.nv == 1:
            angle = q[joint.idx_v]
            out[joint.idx_q], out[joint.idx_q + 1] = np.cos(angle), np.sin(angle)
        else:
            out[joint.idx_q:joint.idx_q + joint.nq] = q[joint.idx_v:joint.idx_v + joint.nv]
    return out


class PinocchioArm:
    """pinocchio's model of a dynamic ``ChainPlant``'s arm and a Python stepper of its controller.

    Args:
        plant: the plant whose chain (its URDF: ``plant.chain.source``) and controller settings
            (gain, damping, null-space gain and home, conveyor) to copy.
        description: the chain's description (``read_urdf``); default: the chain's URDF read again
            with the chain's tool frame and locked joints.
    """

    def __init__(self, plant, description: dict | None = None):
        self.plant = plant
        description = description if description is not None else read_urdf(plant.chain.source, plant.chain.tip,
                                                                                 plant.chain.locked)
        self.model, self.data, self.tool = pinocchio_chain(description)

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
        inverse = np.linalg.inv(J @ J.T + plant.damping**2 * np.eye(3))
        reference = J.T @ inverse @ velocity
        if plant.null_gain > 0:
            pull = plant.null_gain * (plant.home - q)
            reference = reference + pull - J.T @ np.linalg.solve(J @ J.T, J @ pull)
        over = np.abs(reference) / model.velocityLimit
        if over.max() > 1.0:
            reference = reference / over.max()
        tau = gravity + mass @ (plant.velocity_gain * (reference - qd))
        return np.clip(tau, -model.effortLimit, model.effortLimit)

    def rollout(self, theta, start, duration: float) -> np.ndarray:
        """The states (T, D) of a ``duration`` s reproduction of the policy theta (3, S) at 1 kHz."""
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
