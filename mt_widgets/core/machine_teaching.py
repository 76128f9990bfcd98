"""Machine teaching for a ridge-regression learner: the optimal demonstration and the risk.

With ``A = (Phi^T Phi + lam I)^-1 Phi^T`` (S x N) the learner returns ``Theta_hat^T = A U``.
The optimal demonstration for the query states is ``U_bar = pinv(A) Theta^T``. With Phi of
full column rank (N >= S) it teaches Theta exactly; it equals the target policy's own
actions ``Phi Theta^T`` plus ``lam Phi (Phi^T Phi)^-1 Theta^T``, which undoes the ridge
shrinkage. When the rank condition fails (rank < S: fewer independent states than features),
no demonstration on these states can teach every Theta exactly and ``U_bar`` is the one with the
least error; ``optimal_actions`` then warns. (That is not the teaching dimension, where the
teacher also picks the states: for ridge regression it is 1.)

Everything is computed from one SVD ``Phi = W diag(s) V^T``: ``A = V diag(s / (s^2 + lam)) W^T``,
``pinv(A) = W diag((s^2 + lam) / s) V^T``, and ``rho1 = ||A||_2 = max s / (s^2 + lam)``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .learner import DEFAULT_LAMBDA, check_demonstrations
from .ridge_kernels import RidgeOperator, optimal_actions_kernel, ridge_gain, ridge_operator
from .validation import as_float_array, as_positive


class UnderdeterminedTeachingWarning(UserWarning):
    """The query states do not span the feature space: exact teaching is impossible."""


def _check_theta(theta, n_features: int) -> np.ndarray:
    theta = as_float_array("theta", theta, ndim=2)
    if theta.shape[1] != n_features:
        raise ValueError(f"theta: expected shape (R, {n_features}) to match the {n_features} features of Phi, "
                         f"got {theta.shape}")
    return theta


def optimal_from(operator: RidgeOperator, theta: np.ndarray) -> np.ndarray:
    """U_bar (N, R) = pinv(A) Theta^T over the directions Phi spans, from Phi's SVD.

    The one formula of the optimal actions for an operator already decomposed (a
    ``TeachingEpisode``'s, ``analyse_demonstrations``'); ``optimal_actions`` is its compiled twin
    for a bare Phi.
    """
    kept = slice(0, operator.rank)
    inverse_gains = 1.0 / ridge_gain(operator.singular[kept], operator.lam)
    return (operator.left[:, kept] * inverse_gains) @ (operator.right_t[kept] @ theta.T)


def optimal_actions(Phi, theta, lam: float = DEFAULT_LAMBDA) -> np.ndarray:
    """The demonstration that teaches ``theta`` to a ridge learner with parameter ``lam``.

    Args:
        Phi: (N, S) features of the query states.
        theta: (R, S) the skill to teach.
        lam: the learner's ridge parameter (>= 0); by default the learner's own default,
            ``DEFAULT_LAMBDA`` (what ``RidgeLearner()`` uses).

    Returns:
        U_bar: (N, R). Learning from it gives back theta exactly when Phi has rank S; below
        that it is the least-error demonstration and an ``UnderdeterminedTeachingWarning`` says so.
    """
    Phi = as_float_array("Phi", Phi, ndim=2)
    lam = as_positive("lam", lam, allow_zero=True)
    theta = _check_theta(theta, Phi.shape[1])
    optimal, rank = optimal_actions_kernel(np.ascontiguousarray(Phi), np.ascontiguousarray(theta), lam)
    if rank < Phi.shape[1]:
        warnings.warn(f"Phi has rank {rank} < {Phi.shape[1]} features: no demonstration on these {Phi.shape[0]} "
                      f"states teaches theta exactly; returning the least-error one",
                      UnderdeterminedTeachingWarning, stacklevel=2)
    return optimal


def teaching_risk(theta_hat, theta) -> float:
    """E = ||vec(Theta_hat) - vec(Theta)||_2, the paper's teaching error."""
    theta = as_float_array("theta", theta, ndim=2)
    theta_hat = as_float_array("theta_hat", theta_hat, ndim=2)
    if theta_hat.shape != theta.shape:
        raise ValueError(f"theta_hat: expected the shape of theta {theta.shape}, got {theta_hat.shape}")
    return float(np.linalg.norm(theta_hat - theta))


@dataclass(frozen=True)
class TeachingAnalysis:
    """Everything the guidance shows about one set of demonstrations.

    Attributes:
        theta_hat: (R, S) what the learner learnt.
        risk: E, the teaching error.
        optimal: (N, R) the optimal actions U_bar.
        rho1: ||A||_2, how much the query states amplify action errors.
        rho2: ||U - U_bar||_F, how far the actions are from the optimal ones.
        contributions: (N,) ||a_n|| ||u_n - u_bar_n||, the size of each demonstration's
            term in Theta_hat^T - Theta^T = sum_n a_n (u_n - u_bar_n)^T + residual.
        residual: ||A U_bar - Theta^T||, the part no demonstration can remove (0 when exact).
        exact: whether the query states allow exact teaching.
    """

    theta_hat: np.ndarray
    risk: float
    optimal: np.ndarray
    rho1: float
    rho2: float
    contributions: np.ndarray
    residual: float
    exact: bool

    @property
    def bound(self) -> float:
        """rho1 * rho2 (+ the residual when the rank condition fails): an upper bound on ``risk``."""
        return self.rho1 * self.rho2 + self.residual


def analyse_demonstrations(Phi, U, theta, lam) -> TeachingAnalysis:
    """Learns from (Phi, U) and measures the result against theta, with one SVD.

    Args:
        Phi: (N, S) features of the query states.
        U: (N, R) demonstrated actions.
        theta: (R, S) the skill being taught.
        lam: the learner's ridge parameter.
    """
    Phi, U = check_demonstrations(Phi, U)
    operator = ridge_operator(Phi, lam)
    theta = _check_theta(theta, operator.n_features)
    if U.shape[1] != theta.shape[0]:
        raise ValueError(f"U: expected {theta.shape[0]} action components per row to match theta, got {U.shape[1]}")
    return analyse_with(operator, U, theta)


def analyse_with(operator: RidgeOperator, U: np.ndarray, theta: np.ndarray) -> TeachingAnalysis:
    """``analyse_demonstrations`` for a Phi already decomposed and checked inputs: U (N, R),
    theta (R, S). A ``TeachingEpisode`` analyses its demonstrations through this, with its own SVD."""
    A = operator.matrix()
    optimal = optimal_from(operator, theta)
    theta_hat = (A @ U).T
    gap = U - optimal
    return TeachingAnalysis(
        theta_hat=theta_hat,
        risk=teaching_risk(theta_hat, theta),
        optimal=optimal,
        rho1=operator.rho1(),
        rho2=float(np.linalg.norm(gap)),
        contributions=np.linalg.norm(A, axis=0) * np.linalg.norm(gap, axis=1),
        residual=float(np.linalg.norm(A @ optimal - theta.T)),
        exact=operator.exact,
    )


@dataclass(frozen=True)
class ActionDifference:
    """How a demonstrated arrow differs from the optimal one, in the terms a teacher thinks in."""

    angle_deg: float          # signed, counter-clockwise from the optimal to the demonstrated arrow
    magnitude_ratio: float    # |u| / |u_bar| (inf when the optimal arrow is zero)
    error: float              # |u - u_bar|


def action_difference(action, optimal) -> ActionDifference:
    """Compares one demonstrated 2-D action with the optimal one."""
    action = as_float_array("action", action, ndim=1, shape=(2,))
    optimal = as_float_array("optimal", optimal, ndim=1, shape=(2,))
    cross = optimal[0] * action[1] - optimal[1] * action[0]
    angle = float(np.degrees(np.arctan2(cross, optimal @ action)))
    size = float(np.linalg.norm(optimal))
    ratio = float(np.linalg.norm(action) / size) if size > 0 else float("inf")
    return ActionDifference(angle, ratio, float(np.linalg.norm(action - optimal)))
