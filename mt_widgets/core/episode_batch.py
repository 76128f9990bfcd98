"""The batched form of a teaching episode: many teachers' demonstrations of one skill at once.

``TeachingEpisode`` (``mt_widgets.core.episode``) is one teacher's episode, demonstration by
demonstration; ``EpisodeBatch`` is the same episode for many teachers who have all given their
demonstrations, with the same names and the same definitions (``theta_hat``, ``error``, ``rho1``,
``rho2``, ``bound``, ``residual_norm``, ``reproduction`` over ``duration`` seconds).

One episode of a study gives every teacher the same skill and (per study) the same query
states, so one SVD of each feature matrix serves all the teachers who answer it. An
``EpisodeBatch`` (for any ``learner.ParametricSmoother`` on the skill's features; the paper's ridge
is one) holds, for K sets of query states, the learner's map
``A = (Phi^T Phi + lam I)^-1 Phi^T``, the optimal actions ``U_bar`` and ``rho1 = ||A||_2``;
``complete`` fits B teachers' demonstrations at once (``Theta_hat^T = A U``) and scores them
(the teaching error, rho2, the bound), exactly as ``analyse_demonstrations`` does one at a time;
``reproduce`` rolls out the learnt skills as one batch. The in-silico engine
(``mt_widgets.in_silico.engine``) runs its synthetic studies through it.

Rank follows the one rule of ``ridge_kernels.rank_of`` (the learner's and machine
teaching's): directions below the tolerance carry no gain, so a deficient set of query states
gives the minimum-norm fit and the least-error optimal actions, as for a single episode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .learner import Learner, RidgeLearner, is_parametric_smoother
from .learner_teaching import evaluation_states
from .skills import Skill
from .validation import as_float_array, as_positive


@dataclass(frozen=True)
class BatchOutcome:
    """What B completed episodes taught, one row per teacher.

    Attributes:
        theta_hat: (B, R, S) the learnt parameters.
        theta_error: (B,) the teaching error ||Theta_hat - Theta||_F.
        policy_risk: (B,) the learnt policies' risk over the skill's evaluation states
            (``learner_teaching``), as ``TeachingEpisode.policy_risk``.
        rho1: (B,) ||A||_2 of each teacher's query states.
        rho2: (B,) ||U - U_bar||_F of each teacher's demonstrations.
        bound: (B,) rho1 * rho2 plus the norm of the part no demonstration removes (0 when
            exact), as ``TeachingEpisode.bound``.
    """

    theta_hat: np.ndarray
    theta_error: np.ndarray
    policy_risk: np.ndarray
    rho1: np.ndarray
    rho2: np.ndarray
    bound: np.ndarray


class QuerySetBatch:
    """What a batch of teachers' episodes shares, ridge's or another learner's: K sets of query states
    (``query_states``, (K, N, state_dim)) with their optimal actions (``optimal_actions``, (K, N, R)),
    and which set each teacher was given."""

    query_states: np.ndarray
    optimal_actions: np.ndarray

    def __len__(self) -> int:
        return len(self.query_states)

    def _which(self, episode_of, n_teachers: int) -> np.ndarray:
        if episode_of is None:
            if len(self) not in (1, n_teachers):
                raise ValueError(f"episode_of: expected the set of query states of each of {n_teachers} teachers "
                                 f"({len(self)} sets), got None")
            return np.zeros(n_teachers, dtype=int) if len(self) == 1 else np.arange(n_teachers)
        which = np.asarray(episode_of)
        if which.shape != (n_teachers,) or which.dtype.kind not in "iu" or which.min() < 0 or which.max() >= len(self):
            raise ValueError(f"episode_of: expected {n_teachers} indices in [0, {len(self)}), got {which!r}")
        return which

    def optimal_for(self, episode_of=None, n_teachers: int | None = None) -> np.ndarray:
        """(B, N, R) the optimal actions each teacher's query states call for."""
        n = len(self) if n_teachers is None else n_teachers
        return self.optimal_actions[self._which(episode_of, n)]


@dataclass(frozen=True)
class EpisodeBatch(QuerySetBatch):
    """One episode of a skill on K sets of query states, for many teachers at once.

    Build with ``EpisodeBatch.of(skill, query_states, learner, duration)``.

    Attributes:
        skill: the ``Skill`` taught.
        query_states: (K, N, state_dim) the states of each set.
        learner: the ``ParametricSmoother`` (the paper's ``RidgeLearner``) whose operators A these are.
        duration: seconds of each reproduction (the skill's ``default_duration`` unless given).
        features: (K, N, S) Phi of each set.
        learner_map: (K, S, N) A of each set.
        optimal_actions: (K, N, R) U_bar of each set.
        rho1: (K,) ||A||_2 of each set.
        rank: (K,) the rank of each Phi.
        residual_norm: (K,) ||(A U_bar)^T - Theta||, 0 where exact teaching is possible.
        evaluation_features: (M, S) the features of the skill's evaluation states (the policy risk's).
        evaluation_targets: (M, R) the target's actions there.
    """

    skill: Skill
    query_states: np.ndarray
    learner: Learner
    duration: float
    features: np.ndarray
    learner_map: np.ndarray
    optimal_actions: np.ndarray
    rho1: np.ndarray
    rank: np.ndarray
    residual_norm: np.ndarray
    evaluation_features: np.ndarray
    evaluation_targets: np.ndarray

    @classmethod
    def of(cls, skill: Skill, query_states, learner: Learner | None = None,
           duration: float | None = None) -> EpisodeBatch:
        """Decomposes the learner's map for each of K sets of query states (K, N, state_dim).

        ``learner``: a ``ParametricSmoother`` on the skill's features (default: ``RidgeLearner()``);
        another learner is refused by name (``learner_batch.episode_batch`` batches every learner)."""
        if not isinstance(skill, Skill):
            raise TypeError(f"skill: expected a Skill, got {type(skill).__name__}")
        learner = RidgeLearner() if learner is None else learner
        if not is_parametric_smoother(learner):
            raise TypeError(f"learner: expected a parametric smoother on the skill's features (learner."
                            f"ParametricSmoother with inputs 'features', e.g. RidgeLearner), got {learner!r}")
        states = as_float_array("query_states", query_states, ndim=3, shape=(None, None, skill.state_dim))
        duration = skill.default_duration if duration is None else as_positive("duration", duration)
        Phi = skill.features(states.reshape(-1, states.shape[-1])).reshape(states.shape[:2] + (-1,))
        theta = np.asarray(skill.theta, dtype=float)
        A, optimal, rho1, rank = learner.batched_operators(Phi, theta.T)
        residual_norm = np.linalg.norm((A @ optimal - theta.T).reshape(len(A), -1), axis=1)
        evaluation = evaluation_states(skill)
        return cls(skill, states, learner, duration, Phi, A, optimal, rho1, rank, residual_norm,
                   skill.features(evaluation), skill.target_actions(evaluation))

    @property
    def lam(self) -> float:
        """The learner's ``lam`` (its ridge parameter)."""
        return self.learner.lam

    @property
    def exact(self) -> np.ndarray:
        """(K,) whether each set of query states allows exact teaching (rank S)."""
        return self.rank == self.features.shape[2]

    def complete(self, actions, episode_of=None) -> BatchOutcome:
        """Fits and scores B teachers' demonstrations.

        Args:
            actions: (B, N, R) each teacher's demonstrated actions.
            episode_of: (B,) which set of query states each teacher answered (default: all the
                one set, or teacher b the set b).

        Returns:
            A ``BatchOutcome``.
        """
        N, R = self.optimal_actions.shape[1:]
        actions = as_float_array("actions", actions, ndim=3, shape=(N, R))
        which = self._which(episode_of, len(actions))
        theta_hat = np.swapaxes(np.einsum("bsn,bnr->bsr", self.learner_map[which], actions), 1, 2)
        theta = np.asarray(self.skill.theta, dtype=float)
        error = np.linalg.norm((theta_hat - theta).reshape(len(actions), -1), axis=1)
        # The learnt policies on the evaluation states, (B, R, M): a batched product (BLAS), not einsum.
        gap = theta_hat @ self.evaluation_features.T - self.evaluation_targets.T
        risk = np.sqrt(np.sum(gap * gap, axis=(1, 2)) / len(self.evaluation_features))
        rho2 = np.linalg.norm((actions - self.optimal_actions[which]).reshape(len(actions), -1), axis=1)
        rho1 = self.rho1[which]
        return BatchOutcome(theta_hat, error, risk, rho1, rho2, rho1 * rho2 + self.residual_norm[which])

    def reproduce(self, theta_hats, record_every: int | None = None):
        """Rolls out learnt skills (B, R, S) from the skill's start over ``duration`` seconds, as one
        ``TrajectoryBatch``: the reproductions of B episodes in one call."""
        return self.skill.reproduce(as_float_array("theta_hats", theta_hats, ndim=3), duration=self.duration,
                                    record_every=record_every)
