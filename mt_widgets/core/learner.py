"""The robot's learner: the interface every learner implements, and the paper's ridge regression.

A learner turns demonstrations, inputs X (N, D) at the query states and actions U (N, R), into a
fitted policy it can evaluate at any inputs X* (M, D). What the inputs are is the learner's
``inputs``: the skill's features phi(x) (the paper's ridge), the raw state, or the task space
(end-effector position and velocity); ``learner_inputs`` in ``learner_teaching`` builds them from
a skill. A *linear smoother* is a learner whose fitted policy is linear in the demonstrated
actions, ``pi_hat(X*) = S(X*) U`` with S depending on the inputs only: for those machine teaching
is least squares in U, exact where the target is representable (``learner_teaching``).
"""

from __future__ import annotations

import inspect
from typing import Protocol, runtime_checkable

import numpy as np

from .ridge_kernels import ridge_fit
from .validation import as_float_array, as_positive

#: The default ridge parameter. The paper gives none. 0.01 is small against the features'
#: scale (positions of order 1 m or 10 cm, the bias 1), so the optimal arrows stay within a
#: few per cent of the target policy's own actions, yet it keeps the fit finite and smooth when
#: a learner meets a degenerate set of demonstrations.
DEFAULT_LAMBDA = 0.01


def check_demonstrations(Phi, U):
    """Validates a feature matrix Phi (N, S) and actions U (N, R) with matching N."""
    Phi = as_float_array("Phi", Phi, ndim=2)
    U = as_float_array("U", U, ndim=2)
    if Phi.shape[0] != U.shape[0]:
        raise ValueError(f"U: expected one action per row of Phi ({Phi.shape[0]} rows), got {U.shape[0]} rows")
    if Phi.shape[0] == 0:
        raise ValueError("Phi: expected at least one demonstration, got 0 rows")
    if Phi.shape[1] == 0:
        raise ValueError("Phi: expected at least one feature per row, got shape (N, 0)")
    return Phi, U


class Learner:
    """What every learner offers (a base class; subclasses implement ``fit`` and ``predict``).

    In scikit-learn's conventions: the constructor only stores its hyper-parameters, under their
    own names; ``fit`` (and every method that uses them) checks them first, so a learner changed by
    ``set_params`` is checked as one built with the new values; ``get_params`` lists them (read
    from the constructor's signature), and ``clone`` builds an unfitted twin.

    What a learner can do beyond ``fit`` and ``predict`` it declares by its methods, checked as
    protocols: ``LinearSmoother`` (a ``smoother`` matrix: exact machine teaching) and ``BatchedFit``
    (``fit_batch`` and ``predict_batch``: B action sets at the same inputs in one pass).

    Attributes:
        name: the learner's name in protocols and tables ("ridge", "kernel-ridge", ...).
        inputs: what it learns from: "features" (the skill's phi), "state" or "task".
    """

    name: str = "learner"
    inputs: str = "features"

    @classmethod
    def _parameter_names(cls) -> list[str]:
        signature = inspect.signature(cls.__init__)
        return [name for name, parameter in signature.parameters.items()
                if name != "self" and parameter.kind not in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD)]

    def get_params(self, deep: bool = True) -> dict:
        """The hyper-parameters, by the constructor's argument names (``deep`` is scikit-learn's
        signature; a learner holds no nested estimators)."""
        return {name: getattr(self, name) for name in self._parameter_names()}

    def set_params(self, **parameters) -> Learner:
        """Sets hyper-parameters by name (checked at the next ``fit``); returns the learner."""
        known = self._parameter_names()
        for name, value in parameters.items():
            if name not in known:
                raise ValueError(f"{name}: expected a hyper-parameter of {type(self).__name__} "
                                 f"({', '.join(known) or 'none'}), got {name!r}")
            setattr(self, name, value)
        return self

    def clone(self) -> Learner:
        """A new, unfitted learner with the same hyper-parameters."""
        return type(self)(**self.get_params())

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={value!r}" for name, value in self.get_params().items())
        return f"{type(self).__name__}({shown})"

    def check_params(self) -> None:
        """Checks the hyper-parameters, raising an error that names the one that is wrong."""

    def fit(self, X, U):
        """Learns from inputs X (N, D) and actions U (N, R); returns what ``predict`` takes."""
        raise NotImplementedError

    def predict(self, fitted, X_star) -> np.ndarray:
        """The fitted policy's actions (M, R) at inputs X_star (M, D)."""
        raise NotImplementedError


@runtime_checkable
class LinearSmoother(Protocol):
    """A learner whose fitted policy is linear in the demonstrated actions: machine teaching for
    it is exact least squares (``learner_teaching.exact_teaching``)."""

    def smoother(self, X, X_star) -> np.ndarray:
        """S (M, N) with ``predict(fit(X, U), X_star) == S @ U`` for every U; S depends on X only."""


@runtime_checkable
class BatchedFit(Protocol):
    """A learner that fits B action sets at the same inputs in one pass."""

    def fit_batch(self, X, U_batch):
        """Fits at inputs X (N, D) each of the B action sets U_batch (B, N, R)."""

    def predict_batch(self, fitted, X_star) -> np.ndarray:
        """(B, M, R): the B fitted policies at inputs X_star (M, D)."""


def is_linear_smoother(learner) -> bool:
    """Whether ``learner`` declares a smoother matrix (``LinearSmoother``)."""
    return isinstance(learner, LinearSmoother)


def has_batched_fit(learner) -> bool:
    """Whether ``learner`` declares a batched fit (``BatchedFit``)."""
    return isinstance(learner, BatchedFit)


class RidgeLearner(Learner):
    """Ridge regression ``Theta_hat^T = (Phi^T Phi + lam I)^-1 Phi^T U``.

    Args:
        lam: the ridge parameter (>= 0). With 0 and too few or repeated states the minimum-norm
            solution (the limit lam -> 0+) is returned instead of failing.
    """

    name = "ridge"
    inputs = "features"

    def __init__(self, lam: float = DEFAULT_LAMBDA):
        self.lam = lam

    def check_params(self) -> None:
        as_positive("lam", self.lam, allow_zero=True)

    def fit(self, Phi, U) -> np.ndarray:
        """Learns Theta_hat from demonstrations.

        Args:
            Phi: (N, S) features of the demonstrated states.
            U: (N, R) demonstrated actions.

        Returns:
            Theta_hat: (R, S).
        """
        self.check_params()
        Phi, U = check_demonstrations(Phi, U)
        return ridge_fit(np.ascontiguousarray(Phi), np.ascontiguousarray(U), float(self.lam))

    def predict(self, fitted, X_star) -> np.ndarray:
        """Actions ``phi(X*) Theta_hat^T`` (M, R) of the learnt Theta_hat (R, S) at features X_star (M, S)."""
        theta_hat = as_float_array("fitted", fitted, ndim=2)
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, theta_hat.shape[1]))
        return X_star @ theta_hat.T

    def smoother(self, X, X_star) -> np.ndarray:
        """S = phi(X*) (Phi^T Phi + lam I)^-1 Phi^T (M, N), minimum-norm where Phi is deficient."""
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, X.shape[1]))
        # The fit of the identity's columns: Theta_hat^T = A I, so S = X* A.
        A_t = ridge_fit(np.ascontiguousarray(X), np.eye(X.shape[0]), float(self.lam))   # (N, S) = A^T
        return X_star @ A_t.T
