"""Kernel learners: kernel ridge regression and a Gaussian process's posterior mean (RBF kernels).

Both are linear smoothers: the fitted policy at inputs X* is ``k(X*, X) (K + lam I)^-1 U``
(kernel ridge), ``s2 k(X*, X) (s2 K + n2 I)^-1 U`` (the GP's posterior mean with signal variance
s2, noise variance n2 and a zero prior mean), so its smoother operator S(X*) depends on the query
inputs X only and machine teaching for them is exact least squares (``learner_teaching``).

The regularised Gram matrix is decomposed once, ``K = V diag(e) V^T``: its inverse is
``V diag(1 / (e + lam)) V^T``. A system that is singular to working precision (repeated query
states with a vanishing lam) raises ``SingularFitError`` rather than returning NaN or noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .learner import Learner, check_demonstrations, check_inputs
from .validation import as_float_array, as_positive


class SingularFitError(ValueError):
    """The learner's linear system is singular to working precision: no fit exists to return."""


def rbf_kernel(A, B, length_scale: float) -> np.ndarray:
    """k(a, b) = exp(-||a - b||^2 / (2 l^2)) for rows of A (M, D) and B (N, D) -> (M, N)."""
    squared = (np.sum(A * A, axis=1)[:, None] + np.sum(B * B, axis=1)[None, :] - 2.0 * A @ B.T)
    return np.exp(-np.maximum(squared, 0.0) / (2.0 * length_scale * length_scale))


@dataclass(frozen=True)
class KernelPolicy:
    """A kernel learner's fitted policy ``pi(x*) = k(x*, X) w``.

    Attributes:
        kernel: the learner as it was fitted (an unfitted twin: later ``set_params`` leave it).
        X: (N, D) the query inputs.
        weights: (N, R) the weights w of the query inputs.
    """

    kernel: Learner
    X: np.ndarray
    weights: np.ndarray

    def predict(self, X_star) -> np.ndarray:
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, self.X.shape[1]))
        return self.kernel._gram(X_star, self.X) @ self.weights


class _RBFSmoother(Learner):
    """The shared machinery: an RBF Gram matrix, its regularised inverse, the smoother."""

    def check_params(self) -> None:
        as_positive("length_scale", self.length_scale)
        check_inputs(self.inputs)
        as_positive("linear_weight", self.linear_weight, allow_zero=True)

    def _kernel(self, A, B) -> np.ndarray:
        """The RBF, plus ``linear_weight (1 + a.b)`` when asked: the linear part on task-space inputs
        is the paper's features (position, velocity, a bias). It does not make the learner learn a
        linear skill as ridge does: the RBF part adds bumps at the query states, so at the paper's
        5 or 3 query states MT leaves a risk far above ridge's (docs/guide/learners.md)."""
        gram = rbf_kernel(A, B, self.length_scale)
        return gram + self.linear_weight * (1.0 + A @ B.T) if self.linear_weight else gram

    def _gram(self, A, B) -> np.ndarray:
        raise NotImplementedError

    def _regulariser(self) -> float:
        raise NotImplementedError

    def _inverse(self, X) -> np.ndarray:
        """(G + r I)^-1 for the Gram matrix G of the query inputs, refused when singular."""
        self.check_params()
        gram = self._gram(X, X)
        values, vectors = np.linalg.eigh(gram)
        shifted = np.maximum(values, 0.0) + self._regulariser()   # G is PSD: negative values are round-off
        if shifted.min() <= shifted.max() * len(X) * np.finfo(float).eps:
            raise SingularFitError(
                f"{self!r}: the fit is singular: the regularised Gram matrix of the {len(X)} query states has "
                f"condition number {shifted.max() / max(shifted.min(), 1e-300):.3g} (repeated or nearly repeated "
                f"states with a regularisation this small); use distinct query states or a larger regularisation")
        return (vectors / shifted) @ vectors.T

    policy_type = KernelPolicy

    def fit(self, X, U) -> KernelPolicy:
        """Learns from inputs X (N, D) and actions U (N, R); returns the ``KernelPolicy``."""
        X, U = check_demonstrations(X, U)
        weights = self._inverse(X) @ U   # _inverse checks the hyper-parameters
        return KernelPolicy(self.clone(), X, weights)

    def smoother(self, X, X_star) -> np.ndarray:
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, X.shape[1]))
        return self._gram(X_star, X) @ self._inverse(X)


class KernelRidgeLearner(_RBFSmoother):
    """Kernel ridge regression with an RBF kernel: ``pi_hat(X*) = k(X*, X) (K + lam I)^-1 U``.

    Args:
        length_scale: the kernel width l (> 0), in the units of the inputs (m, cm, rad).
        lam: the regularisation (> 0).
        inputs: "task" (end-effector position and velocity, the default), "state" or "features".
        linear_weight: c >= 0 adds ``c (1 + x.x')`` to the kernel (a linear part; 0: the RBF alone,
            scikit-learn's ``KernelRidge(kernel="rbf")``).
    """

    name = "kernel-ridge"

    def __init__(self, length_scale: float, lam: float = 1e-3, inputs: str = "task", linear_weight: float = 1.0):
        self.length_scale, self.lam, self.inputs, self.linear_weight = length_scale, lam, inputs, linear_weight

    def check_params(self) -> None:
        super().check_params()
        as_positive("lam", self.lam)

    def _gram(self, A, B):
        return self._kernel(A, B)

    def _regulariser(self):
        return self.lam


class GaussianProcessLearner(_RBFSmoother):
    """A Gaussian process with an RBF covariance ``s2 k(x, x')`` and a zero prior mean; the
    policy is its posterior mean ``s2 k(X*, X) (s2 K + n2 I)^-1 U`` (one GP per action component).

    Args:
        length_scale: the kernel width l (> 0), in the units of the inputs.
        noise_variance: n2 (> 0), the variance of a demonstrated action's noise.
        signal_variance: s2 (> 0), the prior variance of an action.
        inputs: "task" (the default), "state" or "features".
        linear_weight: c >= 0 adds ``c (1 + x.x')`` to the covariance (a linear prior trend; 0: the
            RBF alone).
    """

    name = "gaussian-process"

    def __init__(self, length_scale: float, noise_variance: float = 1e-4, signal_variance: float = 1.0,
                 inputs: str = "task", linear_weight: float = 1.0):
        self.length_scale, self.noise_variance, self.signal_variance = length_scale, noise_variance, signal_variance
        self.inputs, self.linear_weight = inputs, linear_weight

    def check_params(self) -> None:
        super().check_params()
        as_positive("noise_variance", self.noise_variance)
        as_positive("signal_variance", self.signal_variance)

    def _gram(self, A, B):
        return self.signal_variance * self._kernel(A, B)

    def _regulariser(self):
        return self.noise_variance

    def posterior_variance(self, X, X_star) -> np.ndarray:
        """The posterior variance of the policy (M,) at X_star, the same for every action component."""
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, X.shape[1]))
        cross = self._gram(X_star, X)
        # The prior variance at x* is the covariance's own diagonal s2 k(x*, x*), which the linear
        # part raises to s2 (1 + c (1 + |x*|^2)): the RBF's 1 alone is right only for c = 0.
        prior = self.signal_variance * (1.0 + self.linear_weight * (1.0 + np.sum(X_star * X_star, axis=1)))
        explained = np.einsum("mn,nk,mk->m", cross, self._inverse(X), cross)
        # Exactly, explained <= prior; what exceeds it is round-off of a variance near zero.
        return np.maximum(prior - explained, 0.0)
