"""The robot's learner: multi-output ridge regression of a linear policy."""

from __future__ import annotations

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


class RidgeLearner:
    """Ridge regression ``Theta_hat^T = (Phi^T Phi + lam I)^-1 Phi^T U``.

    Args:
        lam: the ridge parameter (>= 0). With 0 and too few or repeated states the minimum-norm
            solution (the limit lam -> 0+) is returned instead of failing.
    """

    def __init__(self, lam: float = DEFAULT_LAMBDA):
        self.lam = as_positive("lam", lam, allow_zero=True)

    def __repr__(self) -> str:
        return f"RidgeLearner(lam={self.lam})"

    def fit(self, Phi, U) -> np.ndarray:
        """Learns Theta_hat from demonstrations.

        Args:
            Phi: (N, S) features of the demonstrated states.
            U: (N, R) demonstrated actions.

        Returns:
            Theta_hat: (R, S).
        """
        Phi, U = check_demonstrations(Phi, U)
        return ridge_fit(np.ascontiguousarray(Phi), np.ascontiguousarray(U), self.lam)
