"""A learner that is not linear in the demonstrated actions: a small neural network (numpy).

One hidden layer of tanh units, trained on the demonstrations by full-batch Adam for a fixed
number of steps from a fixed, seeded initialisation, with weight decay. The fit is therefore a
deterministic, smooth function of the demonstrated actions, but not a linear one (the inputs and
actions are standardised, and the training is nonlinear): there is no smoother operator, and
machine teaching for it is approximate (``learner_teaching.approximate_teaching``).

``fit_batch`` trains B networks on B action sets at the same query inputs in one pass of numpy
operations: approximate machine teaching differentiates the fit by finite differences, one
network per perturbed action, at the cost of about one fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .learner import Learner, check_demonstrations, check_inputs
from .validation import as_count, as_float_array, as_positive


@dataclass(frozen=True)
class NetworkBatch:
    """B trained networks (each weight with a leading axis B) and the standardisation they were
    trained with (inputs: ``centre``, ``scale``; actions: ``u_centre`` (B, R), ``u_scale`` (B,))."""

    centre: np.ndarray
    scale: np.ndarray
    u_centre: np.ndarray
    u_scale: np.ndarray
    W1: np.ndarray
    b1: np.ndarray
    W2: np.ndarray
    b2: np.ndarray

    def predict(self, X_star) -> np.ndarray:
        """(B, M, R) the B networks' actions at inputs X_star (M, D)."""
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, len(self.centre)))
        Z = (X_star - self.centre) / self.scale
        out = np.tanh(Z @ self.W1 + self.b1[:, None, :]) @ self.W2 + self.b2[:, None, :]
        return out * self.u_scale[:, None, None] + self.u_centre[:, None, :]


@dataclass(frozen=True)
class NetworkPolicy:
    """One trained network's policy (``fit``): ``networks`` holds it as a batch of one."""

    networks: NetworkBatch

    def predict(self, X_star) -> np.ndarray:
        """(M, R) the network's actions at inputs X_star (M, D)."""
        return self.networks.predict(X_star)[0]


class NeuralNetworkLearner(Learner):
    """A one-hidden-layer tanh network ``u = W2 tanh(W1 z + b1) + b2`` on standardised inputs z.

    Args:
        hidden: hidden units.
        steps: Adam steps per fit.
        learning_rate: Adam's step size (> 0).
        weight_decay: the L2 penalty on W1 and W2 (> 0; it keeps the fit unique and smooth).
        seed: the initialisation's seed (the fit is deterministic).
        inputs: "task" (the default), "state" or "features".
    """

    name = "neural-network"
    policy_type = NetworkPolicy

    def __init__(self, hidden: int = 16, steps: int = 150, learning_rate: float = 0.05, weight_decay: float = 1e-3,
                 seed: int = 0, inputs: str = "task"):
        self.hidden, self.steps, self.learning_rate = hidden, steps, learning_rate
        self.weight_decay, self.seed, self.inputs = weight_decay, seed, inputs

    def check_params(self) -> None:
        as_count("hidden", self.hidden)
        as_count("steps", self.steps)
        as_positive("learning_rate", self.learning_rate)
        as_positive("weight_decay", self.weight_decay)
        as_count("seed", self.seed, minimum=0)
        check_inputs(self.inputs)

    def fit(self, X, U) -> NetworkPolicy:
        """Learns from inputs X (N, D) and actions U (N, R); returns the trained ``NetworkPolicy``."""
        X, U = check_demonstrations(X, U)
        return NetworkPolicy(self.fit_batch(X, U[None]))

    def fit_batch(self, X, U_batch) -> NetworkBatch:
        """Trains B networks at the same inputs X (N, D) on actions U_batch (B, N, R)."""
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        U_batch = as_float_array("U_batch", U_batch, ndim=3, shape=(X.shape[0], None))
        centre, scale = X.mean(axis=0), X.std(axis=0)
        # A constant input (the uArm's zero velocity in task space) carries nothing: scale 1.
        scale = np.where(scale > 1e-12 * (1.0 + np.abs(centre)), scale, 1.0)
        Z = (X - centre) / scale
        u_centre = U_batch.mean(axis=1, keepdims=True)                              # (B, 1, R)
        u_scale = np.sqrt(np.mean((U_batch - u_centre) ** 2, axis=(1, 2), keepdims=True))
        u_scale = np.where(u_scale > 0, u_scale, 1.0)
        Y = (U_batch - u_centre) / u_scale
        B, N, R = U_batch.shape
        D, H = X.shape[1], self.hidden
        rng = np.random.default_rng(self.seed)
        params = [np.repeat(p[None], B, axis=0) for p in
                  (rng.normal(0.0, 1.0 / np.sqrt(D), (D, H)), np.zeros(H), rng.normal(0.0, 1.0 / np.sqrt(H), (H, R)),
                   np.zeros(R))]
        moments = [np.zeros_like(p) for p in params]
        squares = [np.zeros_like(p) for p in params]
        beta1, beta2, eps = 0.9, 0.999, 1e-8
        for step in range(1, self.steps + 1):
            W1, b1, W2, b2 = params
            hidden = np.tanh(Z @ W1 + b1[:, None, :])                               # (B, N, H)
            error = (hidden @ W2 + b2[:, None, :] - Y) * (2.0 / (N * R))            # d loss / d output
            back = (error @ W2.transpose(0, 2, 1)) * (1.0 - hidden * hidden)        # (B, N, H)
            grads = [np.einsum("nd,bnh->bdh", Z, back) + 2.0 * self.weight_decay * W1, back.sum(axis=1),
                     hidden.transpose(0, 2, 1) @ error + 2.0 * self.weight_decay * W2, error.sum(axis=1)]
            for i, grad in enumerate(grads):
                moments[i] = beta1 * moments[i] + (1 - beta1) * grad
                squares[i] = beta2 * squares[i] + (1 - beta2) * grad * grad
                params[i] = params[i] - self.learning_rate * (moments[i] / (1 - beta1**step)) / (
                    np.sqrt(squares[i] / (1 - beta2**step)) + eps)
        return NetworkBatch(centre, scale, u_centre[:, 0, :], u_scale[:, 0, 0], *params)

    def predict_batch(self, fitted, X_star) -> np.ndarray:
        """(B, M, R) the actions of B networks from ``fit_batch`` at inputs X_star (M, D)."""
        if not isinstance(fitted, NetworkBatch):
            raise TypeError(f"fitted: expected a NetworkBatch (what fit_batch returns), got {type(fitted).__name__}")
        return fitted.predict(X_star)
