"""The batched teaching episode for any learner: many teachers' demonstrations of one skill at once.

``episode_batch`` picks the batch by what the learner declares, as ``TeachingEpisode`` does:
``EpisodeBatch`` (``episode_batch``) for a learner with a Theta on the skill's features
(``learner.ParametricSmoother``: the paper's ridge), one stacked SVD per set of query states
giving its map, the teaching error ``||Theta_hat - Theta||``. ``LearnerEpisodeBatch`` is the same
episode for every other learner, scored as a
``TeachingEpisode`` with that learner scores one: the teaching error is the policy risk
(``learner_teaching``), rho1 and the optimal arrows are the learner's (``action_sensitivity``,
``teach``), rho2 is ``||U - U_opt||_F``. Two kinds of learner batch:

- a *linear smoother* (``learner.LinearSmoother``): its smoother matrix S on the evaluation
  states depends on the query states only, so it is computed once per set, and B teachers'
  learnt policies are one batched product ``S U_b``, as ridge's ``A U_b``;
- a learner with a *batched fit* (``learner.BatchedFit``): the teachers who answered one set are
  fitted in one ``fit_batch`` call.

A learner with neither is refused by name. Machine teaching and rho1 are computed once per set of
query states (for a learner that is not a linear smoother they are approximate, as for one episode).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .episode_batch import EpisodeBatch, QuerySetBatch
from .learner import Learner, has_batched_fit, is_linear_smoother, is_parametric_smoother
from .learner_teaching import action_sensitivity, evaluation_states, learner_inputs, teach
from .skills import Skill
from .validation import as_float_array, as_positive


@dataclass(frozen=True)
class LearnerBatchOutcome:
    """What B completed episodes taught, one row per teacher (``BatchOutcome``'s names).

    Attributes:
        theta_hat: None (a learner without a Theta on the features has none).
        theta_error: None, likewise.
        policy_risk: (B,) the policy risk of what each teacher taught.
        rho1: (B,) the learnt policy's sensitivity to the actions at each teacher's query states.
        rho2: (B,) ||U - U_opt||_F of each teacher's demonstrations.
    """

    theta_hat: None
    theta_error: None
    policy_risk: np.ndarray
    rho1: np.ndarray
    rho2: np.ndarray


@dataclass(frozen=True)
class LearnerEpisodeBatch(QuerySetBatch):
    """One episode of a skill on K sets of query states for any learner, for many teachers at once.

    Build with ``LearnerEpisodeBatch.of(skill, query_states, learner, duration)``.

    Attributes:
        skill: the ``Skill`` taught.
        learner: the ``Learner``.
        query_states: (K, N, state_dim) the states of each set.
        duration: seconds of each reproduction.
        optimal_actions: (K, N, R) MT's demonstration for each set.
        rho1: (K,) the sensitivity of each set (``action_sensitivity``).
        smoothers: (K, M, N) each set's smoother on the evaluation states (linear smoothers), or None.
    """

    skill: Skill
    learner: Learner
    query_states: np.ndarray
    duration: float
    optimal_actions: np.ndarray
    rho1: np.ndarray
    smoothers: np.ndarray | None
    evaluation_inputs: np.ndarray
    evaluation_targets: np.ndarray

    @classmethod
    def of(cls, skill: Skill, query_states, learner: Learner, duration: float | None = None) -> LearnerEpisodeBatch:
        """Machine teaching, rho1 and (for a linear smoother) S for each of K sets (K, N, state_dim)."""
        if not isinstance(skill, Skill):
            raise TypeError(f"skill: expected a Skill, got {type(skill).__name__}")
        if not isinstance(learner, Learner):
            raise TypeError(f"learner: expected a mt_widgets.core Learner, got {type(learner).__name__}")
        smoother = is_linear_smoother(learner)
        if not smoother and not has_batched_fit(learner):
            raise TypeError(f"learner: expected a linear smoother or a learner with a batched fit (fit_batch and "
                            f"predict_batch) to teach many teachers at once, got {learner!r}")
        states = as_float_array("query_states", query_states, ndim=3, shape=(None, None, skill.state_dim))
        duration = skill.default_duration if duration is None else as_positive("duration", duration)
        evaluation = evaluation_states(skill)
        X_eval = learner_inputs(learner, skill, evaluation)
        optimal, rho1, smoothers = [], [], []
        for query in states:
            taught = teach(learner, skill, query, evaluation)
            optimal.append(taught.optimal)
            rho1.append(action_sensitivity(learner, skill, query, taught.optimal, evaluation)[0])
            if smoother:
                smoothers.append(learner.smoother(learner_inputs(learner, skill, query), X_eval))
        return cls(skill, learner, states, duration, np.stack(optimal), np.array(rho1),
                   np.stack(smoothers) if smoother else None, X_eval, skill.target_actions(evaluation))

    def learnt_on_evaluation(self, actions, episode_of=None) -> np.ndarray:
        """(B, M, R): each teacher's learnt policy on the evaluation states."""
        N, R = self.optimal_actions.shape[1:]
        actions = as_float_array("actions", actions, ndim=3, shape=(N, R))
        which = self._which(episode_of, len(actions))
        if self.smoothers is not None:
            return np.einsum("bmn,bnr->bmr", self.smoothers[which], actions)
        learnt = np.empty((len(actions),) + self.evaluation_targets.shape)
        for k in np.unique(which):
            teachers = np.flatnonzero(which == k)
            X = learner_inputs(self.learner, self.skill, self.query_states[k])
            learnt[teachers] = self.learner.predict_batch(self.learner.fit_batch(X, actions[teachers]),
                                                          self.evaluation_inputs)
        return learnt

    def complete(self, actions, episode_of=None) -> LearnerBatchOutcome:
        """Fits and scores B teachers' demonstrations (B, N, R); ``episode_of`` as for ``EpisodeBatch``."""
        actions = as_float_array("actions", actions, ndim=3)
        which = self._which(episode_of, len(actions))
        learnt = self.learnt_on_evaluation(actions, which)
        error = np.sqrt(np.mean(np.sum((learnt - self.evaluation_targets) ** 2, axis=2), axis=1))
        rho2 = np.linalg.norm((actions - self.optimal_actions[which]).reshape(len(actions), -1), axis=1)
        return LearnerBatchOutcome(None, None, error, self.rho1[which], rho2)


def episode_batch(skill: Skill, query_states, learner: Learner,
                  duration: float | None = None) -> EpisodeBatch | LearnerEpisodeBatch:
    """The batched episode of ``skill`` on K sets of query states (K, N, state_dim) with ``learner``:
    ``EpisodeBatch`` for a ``ParametricSmoother`` on the skill's features, ``LearnerEpisodeBatch``
    for any other linear smoother or learner with a batched fit (the one choice, by protocol)."""
    if is_parametric_smoother(learner):
        return EpisodeBatch.of(skill, query_states, learner, duration)
    return LearnerEpisodeBatch.of(skill, query_states, learner, duration)
