"""A robot that learns a reward from demonstrations and executes the policy optimal for it.

After the research line's follow-up, Sun, Zhu and Howard, "Training People to Reward Robots"
(arXiv 2505.10151): reinforcement learning from demonstration (RLfD), taught with 8
demonstrations. Its public text (the abstract and introduction) gives the setting, not the
reward's form nor the optimiser; what follows is this package's assumption, chosen so that the
reward, its learning and its optimal policy are exact and fast (docs/guide/learners.md says what
is reproduced and what is assumed):

- The plant is kinematic in the plane, ``r <- r + u`` (the uArm; inputs are positions r).
- The reward of an action is quadratic: ``R(r, u) = -1/2 (r + u - g)^T W (r + u - g) - 1/2 |u|^2``,
  a cost of the distance to where the skill leads (W symmetric, b = W g; the paper's skills have
  W positive semi-definite) and of the action's size. The action cost's weight is fixed to 1: a reward's scale cannot be
  told from demonstrations, and fixing it rules out the trivial zero reward.
- Learning the reward is inverse optimal control by the optimality condition: a demonstration
  is optimal when ``dR/du = 0``, i.e. ``W (r_n + u_n) - b + u_n = 0``, linear in (W, b); the
  learner takes the least-squares (W, b) over the demonstrations, with a small ridge ``lam``,
  and raises W's eigenvalues to at least ``MIN_EIGENVALUE`` = -1/2, so that the reward is concave
  in the action (``W + I`` at least ``I / 2``) and has one best action. The floor lies below the
  eigenvalue 0 of a singular W (the line skill), so the fit is smooth around every skill whose W
  is positive semi-definite and machine teaching reaches machine precision there.
- The robot executes the policy optimal for the learnt reward, ``u(r) = (W + I)^-1 (b - W r)``.

The learnt reward depends on the demonstrated actions through the design of the least squares
(``r_n + u_n``): the learner is not linear in the actions, and machine teaching for it is
approximate (``learner_teaching.approximate_teaching``). The paper's point-reaching and
line-reaching uArm skills are in its policy class (W = 0.25 I, and W = 0.25 n n^T), so the
target is representable; with 8 query states MT teaches each to machine precision (risk below
1e-9) in 100 of 100 random query sets (tests/core/test_reward_learner.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kernel_learners import SingularFitError
from .learner import Learner, check_demonstrations, check_inputs
from .plants import KinematicPlant
from .validation import as_float_array, as_positive

#: The least eigenvalue the learnt W may have. The policy needs only ``W + I`` positive definite
#: (the reward concave in the action, so its maximiser is unique); the floor keeps it at least
#: ``I / 2``. It is not 0: a skill whose W is singular (the line, W = 0.25 n n^T) sits on the
#: floor's edge with 0, where the clip ``max(w, 0)`` made the fit non-smooth in the demonstrated
#: actions, and machine teaching stopped between 1e-12 and 5e-6 in 44 of 100 query sets of 8.
MIN_EIGENVALUE = -0.5


@dataclass(frozen=True)
class RewardPolicies:
    """B learnt quadratic rewards, W (B, 2, 2) and b (B, 2), and the optimal actions for each."""

    W: np.ndarray
    b: np.ndarray

    def predict(self, X_star) -> np.ndarray:
        """(B, M, 2): the optimal actions ``(W + I)^-1 (b - W r)`` of each reward at positions X_star (M, 2)."""
        X_star = as_float_array("X_star", X_star, ndim=2, shape=(None, 2))
        system = self.W + np.eye(2)
        if np.any(np.linalg.cond(system) > 1e12):
            raise SingularFitError("fitted: the learnt reward has no unique best action (W + I is singular)")
        right = self.b[:, :, None] - np.swapaxes(X_star @ self.W, 1, 2)       # (B, 2, M)
        return np.swapaxes(np.linalg.solve(system, right), 1, 2)


@dataclass(frozen=True)
class RewardPolicy:
    """One learnt reward (W (2, 2), b (2,)) and its optimal policy (what ``RewardLearner.fit`` returns)."""

    W: np.ndarray
    b: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "W", as_float_array("W", self.W, ndim=2, shape=(2, 2)))
        object.__setattr__(self, "b", as_float_array("b", self.b, ndim=1, shape=(2,)))

    def predict(self, X_star) -> np.ndarray:
        """The optimal actions ``(W + I)^-1 (b - W r)`` (M, 2) at positions X_star (M, 2)."""
        return RewardPolicies(self.W[None], self.b[None]).predict(X_star)[0]

    def reward(self, X, U) -> np.ndarray:
        """The learnt reward R(r, u) (N,) of actions U at positions X; its goal is ``pinv(W) b``."""
        X = as_float_array("X", X, ndim=2, shape=(None, 2))
        U = as_float_array("U", U, ndim=2, shape=X.shape)
        reached = X + U
        # -1/2 (y - g)^T W (y - g) up to a constant: -1/2 y^T W y + b^T y.
        return -0.5 * np.einsum("ni,ij,nj->n", reached, self.W, reached) + reached @ self.b - 0.5 * np.sum(U * U,
                                                                                                          axis=1)


class RewardLearner(Learner):
    """Learns a quadratic reward by inverse optimal control and acts optimally for it (module docstring).

    Args:
        lam: the ridge on the reward's parameters (W, b) (> 0).
        inputs: "state" only (the positions r on the uArm's plane; the argument every learner takes).
    """

    name = "reward"
    policy_type = RewardPolicy

    def __init__(self, lam: float = 1e-3, inputs: str = "state"):
        self.lam = lam
        self.inputs = inputs

    def check_params(self) -> None:
        as_positive("lam", self.lam)
        check_inputs(self.inputs, ("state",))

    @classmethod
    def cannot_represent(cls, skill) -> str | None:
        """Its policies act on the plane's positions of a kinematic plant ``r <- r + u`` (2-D states
        and actions), and each is linear in the position (a quadratic reward's optimum)."""
        plant = skill.plant
        if not (isinstance(plant, KinematicPlant) and skill.state_dim == 2 and plant.action_dim == 2):
            return (f"it learns rewards over planar positions of a kinematic plant (2 state and 2 action "
                    f"numbers, r <- r + u), and skill {skill.key!r}'s plant ({type(plant).__name__}) has "
                    f"{skill.state_dim} state and {plant.action_dim} action numbers")
        if skill.policy is not None:
            return (f"its policies are the optima of quadratic rewards (linear in the position) and skill "
                    f"{skill.key!r} has a nonlinear target policy")
        return None

    def fit(self, X, U) -> RewardPolicy:
        """Learns the reward (W (2, 2), b (2,)) from positions X (N, 2) and actions U (N, 2)."""
        X, U = check_demonstrations(X, U)
        fitted = self.fit_batch(X, U[None])
        return RewardPolicy(fitted.W[0], fitted.b[0])

    def fit_batch(self, X, U_batch) -> RewardPolicies:
        """Learns B rewards (W (B, 2, 2), b (B, 2)) at positions X (N, 2) from actions U_batch (B, N, 2)."""
        self.check_params()
        X = as_float_array("X", X, ndim=2)
        U_batch = as_float_array("U_batch", U_batch, ndim=3, shape=(X.shape[0], None))
        if X.shape[1] != 2 or U_batch.shape[2] != 2:
            raise ValueError(f"X, U: expected planar positions and actions (N, 2) for the reward learner, "
                             f"got {X.shape} and {U_batch.shape[1:]}")
        reached = X[None] + U_batch                                 # (B, N, 2)
        B, n = U_batch.shape[:2]
        design = np.zeros((B, 2 * n, 5))                            # unknowns (w11, w12, w22, b1, b2)
        design[:, 0::2, 0], design[:, 0::2, 1], design[:, 0::2, 3] = reached[..., 0], reached[..., 1], -1.0
        design[:, 1::2, 1], design[:, 1::2, 2], design[:, 1::2, 4] = reached[..., 0], reached[..., 1], -1.0
        target = -U_batch.reshape(B, -1, 1)
        transposed = np.swapaxes(design, 1, 2)
        gram = transposed @ design + float(self.lam) * np.eye(5)
        w11, w12, w22, b1, b2 = np.moveaxis(np.linalg.solve(gram, transposed @ target)[..., 0], -1, 0)
        values, vectors = np.linalg.eigh(np.stack([np.stack([w11, w12], -1), np.stack([w12, w22], -1)], -2))
        W = (vectors * np.maximum(values, MIN_EIGENVALUE)[:, None, :]) @ np.swapaxes(vectors, 1, 2)
        return RewardPolicies(W, np.stack([b1, b2], axis=-1))

    def predict_batch(self, fitted, X_star) -> np.ndarray:
        """(B, M, 2): the optimal actions of B learnt rewards (``fit_batch``) at positions X_star (M, 2)."""
        if not isinstance(fitted, RewardPolicies):
            raise TypeError(f"fitted: expected RewardPolicies (what fit_batch returns), got {type(fitted).__name__}")
        return fitted.predict(X_star)
