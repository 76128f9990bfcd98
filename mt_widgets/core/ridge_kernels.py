"""The SVD-based kernels of the learner and machine teaching on small matrices.

Both go through the SVD so that a rank-deficient Phi (repeated states, too few states,
lam = 0) is handled exactly instead of failing. The SVD is numpy's (LAPACK through numpy), not
numba's: numba's ``np.linalg`` needs scipy's LAPACK bindings at run time, and the core install
(numpy and numba only) must run the science without scipy (docs/guide/install.md gives the
measurements behind this choice). The arithmetic around the SVD is a few small products, for
which numpy's per-call cost is a microsecond or two: one fit plus the optimal actions of a
5 x 5 problem stay in tens of microseconds (benchmarks/bench_core.py, target below 100 us).
"""

from __future__ import annotations

import numpy as np

_EPSILON = float(np.finfo(np.float64).eps)


def rank_of(singular, shape) -> np.ndarray | int:
    """The number of singular values above the rank tolerance, the one definition of rank for the
    learner and machine teaching: ``max(N, S) * eps * s_max`` (numpy's ``matrix_rank`` rule).

    ``singular`` is (..., k), sorted in decreasing order as the SVD returns it; ``shape`` the
    (N, S) of each decomposed matrix. A stack of spectra gives an integer array of ranks.
    """
    singular = np.asarray(singular)
    if singular.shape[-1] == 0:
        return np.zeros(singular.shape[:-1], dtype=np.int64) if singular.ndim > 1 else 0
    tolerance = singular[..., :1] * (max(shape) * _EPSILON)
    ranks = np.count_nonzero(singular > tolerance, axis=-1)
    return ranks if singular.ndim > 1 else int(ranks)


def svd_with_rank(Phi):
    """(W, s, V^T, rank) of Phi (N, S): the thin SVD and the number of singular values above
    the rank tolerance (``rank_of``)."""
    left, singular, right_t = np.linalg.svd(Phi, full_matrices=False)
    return left, singular, right_t, rank_of(singular, Phi.shape)


def ridge_gain(singular, lam):
    """s / (s^2 + lam): the ridge learner's gain along each singular direction of Phi, the one place
    the formula is written (the fit, machine teaching, rho1 and the batched maps all take it)."""
    return singular / (singular * singular + lam)


def ridge_fit(Phi, U, lam):
    """Theta_hat (R, S) = ((Phi^T Phi + lam I)^-1 Phi^T U)^T, minimum-norm where Phi is deficient."""
    left, singular, right_t, rank = svd_with_rank(Phi)
    singular = singular[:rank]
    projected = (left[:, :rank].T @ U) * ridge_gain(singular, lam)[:, None]   # (rank, R)
    return (right_t[:rank].T @ projected).T.copy()


def optimal_actions_kernel(Phi, theta, lam):
    """(U_bar (N, R), rank): U_bar = pinv(A) theta^T with A the ridge learner's map."""
    left, singular, right_t, rank = svd_with_rank(Phi)
    singular = singular[:rank]
    projected = (right_t[:rank] @ theta.T) / ridge_gain(singular, lam)[:, None]  # (rank, R)
    return left[:, :rank] @ projected, rank
