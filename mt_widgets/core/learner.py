"""The robot's learner: the interface every learner implements, and the paper's ridge regression.

A learner turns demonstrations, inputs X (N, D) at the query states and actions U (N, R), into a
fitted policy (a ``FittedPolicy``: a small frozen object per learner family, with ``predict``) it
can evaluate at any inputs X* (M, D); a linear learner's (``LinearPolicy``) holds its Theta.
What the inputs are is the learner's ``inputs`` (a constructor argument of every learner): the
skill's features phi(x) (the paper's ridge), the raw state, or the task space (end-effector
position and velocity); ``learner_inputs`` in ``learner_teaching`` builds them from a skill.
A *linear smoother* is a learner whose fitted policy is linear in the demonstrated actions,
``pi_hat(X*) = S(X*) U`` with S depending on the inputs only: for those machine teaching is
least squares in U, exact where the target is representable (``learner_teaching``).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .ridge_kernels import RidgeOperator, batched_ridge_maps, ridge_fit, ridge_operator
from .validation import as_float_array, as_positive

#: The default ridge parameter. The paper gives none. 0.01 is small against the features'
#: scale (positions of order 1 m or 10 cm, the bias 1), so the optimal arrows stay within a
#: few per cent of the target policy's own actions, yet it keeps the fit finite and smooth when
#: a learner meets a degenerate set of demonstrations.
DEFAULT_LAMBDA = 0.01


#: What a learner can learn from: the skill's features phi(x), the raw state, the task space.
INPUT_SPACES = ("features", "state", "task")


def check_inputs(inputs, allowed=INPUT_SPACES) -> str:
    """``inputs`` checked against the spaces a learner accepts (``allowed``), by name."""
    if not isinstance(inputs, str) or inputs not in allowed:
        raise ValueError(f"inputs: expected one of {', '.join(map(repr, allowed))}, got {inputs!r}")
    return inputs


@runtime_checkable
class FittedPolicy(Protocol):
    """What every learner's ``fit`` returns: a fitted policy that predicts actions (M, R) at
    inputs X_star (M, D) in the learner's input space."""

    def predict(self, X_star) -> np.ndarray:
        """The policy's actions (M, R) at inputs X_star (M, D)."""


@dataclass(frozen=True)
class LinearPolicy:
    """A policy linear in its inputs, ``pi(x) = Theta x`` (what ridge learns).

    Attributes:
        theta: (R, S) Theta_hat, on the learner's inputs (the skill's features for the paper's ridge).
    """

    theta: np.ndarray

    def __post_init__(self):
        theta = as_float_array("theta", self.theta, ndim=2).copy()
        theta.setflags(write=False)
        object.__setattr__(self, "theta", theta)

    def predict(self, X_star) -> np.ndarray:
        """Actions ``X* Theta^T`` (M, R) at inputs X_star (M, S)."""
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, self.theta.shape[1]))
        return X_star @ self.theta.T


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

    ``fit`` returns a ``FittedPolicy`` (a frozen object that predicts); ``predict(fitted, X_star)``
    is its ``predict``, checked to be this learner family's policy.

    What a learner can do beyond ``fit`` and ``predict`` it declares by its methods, checked as
    protocols: ``LinearSmoother`` (a ``smoother`` matrix: exact machine teaching),
    ``ParametricSmoother`` (a linear smoother whose policy is a Theta on the skill's features, with
    its operator A: the paper's analysis, ``theta_error``) and ``BatchedFit`` (``fit_batch`` and
    ``predict_batch``: B action sets at the same inputs in one pass).

    Every learner takes ``inputs`` as a constructor argument ("features", "state" or "task"; each
    class states which it accepts and its default). Which of its hyper-parameters a study protocol
    sets is the class's ``protocol_parameters``: (hyper-parameter, ``Protocol`` attribute) pairs.

    Attributes:
        name: the learner's name in protocols and tables ("ridge", "kernel-ridge", ...).
        policy_type: the class of the ``FittedPolicy`` its ``fit`` returns.
    """

    name: str = "learner"
    policy_type: type = object
    protocol_parameters: tuple = ()

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

    @classmethod
    def cannot_represent(cls, skill) -> str | None:
        """Why no policy this learner class can learn is the skill's target (a sentence), or None
        when one is. A learner represents a skill when some fitted policy of its class equals the
        target policy on the skill's states, so that exact teaching can reach zero policy risk.
        The kernel learners and the network represent any smooth target (their policy classes
        grow with the query states); the base class says None."""
        return None

    def fit(self, X, U) -> FittedPolicy:
        """Learns from inputs X (N, D) and actions U (N, R); returns the fitted policy."""
        raise NotImplementedError

    def predict(self, fitted: FittedPolicy, X_star) -> np.ndarray:
        """The fitted policy's actions (M, R) at inputs X_star (M, D): ``fitted.predict(X_star)``."""
        if not isinstance(fitted, self.policy_type):
            raise TypeError(f"fitted: expected a {self.policy_type.__name__} (what {type(self).__name__}.fit "
                            f"returns), got {type(fitted).__name__}")
        return fitted.predict(X_star)


@runtime_checkable
class LinearSmoother(Protocol):
    """A learner whose fitted policy is linear in the demonstrated actions: machine teaching for
    it is exact least squares (``learner_teaching.exact_teaching``)."""

    def smoother(self, X, X_star) -> np.ndarray:
        """S (M, N) with ``predict(fit(X, U), X_star) == S @ U`` for every U; S depends on X only."""


@runtime_checkable
class ParametricSmoother(LinearSmoother, Protocol):
    """A linear smoother whose fitted policy is a ``LinearPolicy``, ``Theta_hat^T = A U``, with A
    (S, N) depending on the inputs only: on the skill's features (``inputs == "features"``) its
    Theta is the skill's, so an episode reports ``theta_error`` and the paper's analysis (rho1 =
    ||A||_2, the bound, each demonstration's term), one by one and batched."""

    def operator(self, X) -> RidgeOperator:
        """A from the SVD of the inputs X (N, S) (``ridge_kernels.RidgeOperator``)."""

    def batched_operators(self, X, theta_t) -> tuple:
        """(A (K, S, N), U_bar (K, N, R), rho1 (K,), rank (K,)) for K input sets X (K, N, S) and
        the target Theta^T (S, R) (``ridge_kernels.batched_ridge_maps``)."""


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


def is_parametric_smoother(learner) -> bool:
    """Whether ``learner`` declares its operator A (``ParametricSmoother``) and learns on the skill's
    features, so that its Theta is comparable with the skill's."""
    return isinstance(learner, ParametricSmoother) and learner.inputs == "features"


def has_batched_fit(learner) -> bool:
    """Whether ``learner`` declares a batched fit (``BatchedFit``)."""
    return isinstance(learner, BatchedFit)


class RidgeLearner(Learner):
    """Ridge regression ``Theta_hat^T = (Phi^T Phi + lam I)^-1 Phi^T U``.

    Args:
        lam: the ridge parameter (>= 0). With 0 and too few or repeated states the minimum-norm
            solution (the limit lam -> 0+) is returned instead of failing. A study protocol's
            ``lambda`` (``protocol_parameters``).
        inputs: "features" (the skill's phi, the paper's, the default), "state" or "task".
    """

    name = "ridge"
    policy_type = LinearPolicy
    protocol_parameters = (("lam", "lam"),)

    def __init__(self, lam: float = DEFAULT_LAMBDA, inputs: str = "features"):
        self.lam = lam
        self.inputs = inputs

    def check_params(self) -> None:
        as_positive("lam", self.lam, allow_zero=True)
        check_inputs(self.inputs)

    @classmethod
    def cannot_represent(cls, skill) -> str | None:
        """Its policy ``Theta x`` is linear in its inputs; a skill with a nonlinear target policy
        (``skill.policy``, the skills of ``nonlinear_skills``) is not linear in the features, the
        state or the task space."""
        if skill.policy is not None:
            return (f"its policies are linear (Theta times its inputs) and skill {skill.key!r} has a nonlinear "
                    f"target policy that no Theta reproduces")
        return None

    def fit(self, Phi, U) -> LinearPolicy:
        """Learns Theta_hat from demonstrations.

        Args:
            Phi: (N, S) inputs (the skill's features) of the demonstrated states.
            U: (N, R) demonstrated actions.

        Returns:
            The ``LinearPolicy`` with Theta_hat (R, S) as ``theta``.
        """
        self.check_params()
        Phi, U = check_demonstrations(Phi, U)
        return LinearPolicy(ridge_fit(np.ascontiguousarray(Phi), np.ascontiguousarray(U), float(self.lam)))

    def smoother(self, X, X_star) -> np.ndarray:
        """S = phi(X*) (Phi^T Phi + lam I)^-1 Phi^T (M, N), minimum-norm where Phi is deficient."""
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, X.shape[1]))
        # The fit of the identity's columns: Theta_hat^T = A I, so S = X* A.
        A_t = ridge_fit(np.ascontiguousarray(X), np.eye(X.shape[0]), float(self.lam))   # (N, S) = A^T
        return X_star @ A_t.T

    def operator(self, X) -> RidgeOperator:
        """A = (Phi^T Phi + lam I)^-1 Phi^T from one SVD of the inputs X (N, S)."""
        self.check_params()
        return ridge_operator(X, self.lam)

    def batched_operators(self, X, theta_t) -> tuple:
        """A, U_bar, rho1 and rank of K input sets X (K, N, S) in one stacked SVD (``batched_ridge_maps``)."""
        self.check_params()
        X = as_float_array("X", X, ndim=3)
        return batched_ridge_maps(np.ascontiguousarray(X), np.ascontiguousarray(theta_t), float(self.lam))
