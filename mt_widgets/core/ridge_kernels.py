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

from dataclasses import dataclass

import numpy as np
from numba import njit

from .validation import as_float_array, as_positive

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


@dataclass(frozen=True)
class RidgeOperator:
    """The SVD of Phi and what follows from it for a given lam."""

    left: np.ndarray        # W: (N, k)
    singular: np.ndarray    # s: (k,)
    right_t: np.ndarray     # V^T: (k, S)
    lam: float
    rank: int

    @property
    def n_features(self) -> int:
        return self.right_t.shape[1]

    @property
    def exact(self) -> bool:
        """Can some demonstration on these states teach any Theta exactly?"""
        return self.rank == self.n_features

    @property
    def gains(self) -> np.ndarray:
        """s / (s^2 + lam), zero for directions Phi does not span."""
        kept = np.arange(len(self.singular)) < self.rank
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(kept, ridge_gain(self.singular, self.lam), 0.0)

    def matrix(self) -> np.ndarray:
        """A = (Phi^T Phi + lam I)^-1 Phi^T, (S, N)."""
        return (self.right_t.T * self.gains) @ self.left.T

    def rho1(self) -> float:
        return float(np.max(self.gains)) if self.rank else 0.0


def ridge_operator(Phi, lam: float) -> RidgeOperator:
    """Decomposes the learner's map from actions to parameters for features Phi (N, S)."""
    Phi = as_float_array("Phi", Phi, ndim=2)
    lam = as_positive("lam", lam, allow_zero=True)
    left, singular, right_t, rank = svd_with_rank(np.ascontiguousarray(Phi))
    return RidgeOperator(left, singular, right_t, lam, int(rank))


def batched_ridge_maps(Phi, theta_t, lam):
    """(A (K, S, N), U_bar (K, N, R), rho1 (K,), rank (K,)) for features Phi (K, N, S).

    ``theta_t`` is Theta^T (S, R). numpy decomposes the K matrices in one stacked SVD (numba's
    would need scipy: ``ridge_kernels``), and the rank follows the single learner's rule
    (``ridge_kernels.rank_of``); the compiled ``_maps_from_svd`` builds the maps from it.
    """
    left, singular, right_t = np.linalg.svd(Phi, full_matrices=False)
    ranks = np.asarray(rank_of(singular, Phi.shape[1:]), dtype=np.int64).reshape(len(Phi))
    with np.errstate(divide="ignore", invalid="ignore"):   # a zero singular value is beyond the rank
        gains = ridge_gain(singular, float(lam))
    A, optimal, rho1 = _maps_from_svd(left, gains, right_t, ranks, theta_t)
    return A, optimal, rho1, ranks


@njit(cache=True)
def _maps_from_svd(left, gains, right_t, ranks, theta_t):
    """(A, U_bar, rho1) of ``batched_ridge_maps`` from the K thin SVDs' vectors, the ridge gains of
    their singular values (``ridge_kernels.ridge_gain``) and their ranks."""
    K, N, _ = left.shape
    S = right_t.shape[2]
    R = theta_t.shape[1]
    A = np.zeros((K, S, N))
    optimal = np.zeros((K, N, R))
    rho1 = np.zeros(K)
    for k in range(K):
        for i in range(ranks[k]):
            gain = gains[k, i]
            inverse_gain = 1.0 / gain
            if gain > rho1[k]:
                rho1[k] = gain
            for s in range(S):
                for n in range(N):
                    A[k, s, n] += gain * right_t[k, i, s] * left[k, n, i]
            for r in range(R):
                along = 0.0
                for s in range(S):
                    along += right_t[k, i, s] * theta_t[s, r]
                for n in range(N):
                    optimal[k, n, r] += inverse_gain * left[k, n, i] * along
    return A, optimal, rho1
