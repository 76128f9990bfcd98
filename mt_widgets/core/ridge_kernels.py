"""Compiled kernels for the learner and machine teaching on small matrices.

For the 5 x 5 problems a lesson solves after every demonstration, numpy's per-call overhead
(tens of microseconds per linalg call) dominates the arithmetic; compiled, one SVD-based fit
plus the optimal actions take a few microseconds, which keeps guidance immediate. Both go
through the SVD so that a rank-deficient Phi (repeated states, too few states, lam = 0) is
handled exactly instead of failing.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def svd_with_rank(Phi):
    """(W, s, V^T, rank) of Phi (N, S): the thin SVD and the number of singular values above
    the rank tolerance, the one definition of rank for the learner and machine teaching."""
    left, singular, right_t = np.linalg.svd(Phi, full_matrices=False)
    n, s = Phi.shape
    tolerance = singular[0] * max(n, s) * 2.220446049250313e-16 if singular.size > 0 else 0.0
    rank = 0
    for value in singular:
        if value > tolerance:
            rank += 1
    return left, singular, right_t, rank


@njit(cache=True)
def ridge_fit(Phi, U, lam):
    """Theta_hat (R, S) = ((Phi^T Phi + lam I)^-1 Phi^T U)^T, minimum-norm where Phi is deficient."""
    left, singular, right_t, rank = svd_with_rank(Phi)
    projected = np.ascontiguousarray(left[:, :rank].T) @ U    # (rank, R)
    for i in range(rank):
        projected[i, :] *= singular[i] / (singular[i] * singular[i] + lam)
    return (np.ascontiguousarray(right_t[:rank].T) @ projected).T.copy()


@njit(cache=True)
def optimal_actions_kernel(Phi, theta, lam):
    """(U_bar (N, R), rank): U_bar = pinv(A) theta^T with A the ridge learner's map."""
    left, singular, right_t, rank = svd_with_rank(Phi)
    projected = np.ascontiguousarray(right_t[:rank]) @ np.ascontiguousarray(theta.T)  # (rank, R)
    for i in range(rank):
        projected[i, :] *= (singular[i] * singular[i] + lam) / singular[i]
    return np.ascontiguousarray(left[:, :rank]) @ projected, rank
