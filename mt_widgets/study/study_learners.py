"""The robot learner a study's episodes teach, and what its log records of each learner.

A protocol names its learner (``learner = ...``, one of ``mt_widgets.core.LEARNERS``). The paper's
ridge learner is built by the episode itself with the protocol's ``lambda`` (its log is the
paper protocols' log, unchanged: Theta_hat and the ridge analysis). Any other learner is made
here, once per skill, with ``make_learner``'s defaults for that skill (a kernel learner's width is
the skill's typical distance, so it depends on the skill), and its episodes log what every learner
can give instead of Theta_hat: the learner's name and parameters (``episode_started``), and the
fitted policy's actions at the query states (``episode_finished``'s ``learnt_actions``). Since a
learner's fit is deterministic, the logged query states and actions give back the learnt policy
(``learnt_policy_of``), which is how the analysis rolls out what a participant taught.
"""

from __future__ import annotations

import weakref

import numpy as np

from mt_widgets.core.learner import Learner, RidgeLearner
from mt_widgets.core.learner_teaching import learnt_policy, make_learner

#: The learner a protocol has when it names none: the paper's.
PAPER_LEARNER = "ridge"

#: (learner name, skill) -> the learner: one per skill (a kernel width is computed once), weakly
#: keyed by the skill object so an entry goes with its skill.
_LEARNERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def study_learner(name: str, skill) -> Learner | None:
    """The learner called ``name`` for ``skill``'s episodes; None for ridge (the episode builds the
    paper's ridge itself, with the protocol's ``lambda``)."""
    if name == PAPER_LEARNER:
        return None
    made = _LEARNERS.setdefault(skill, {})
    if name not in made:
        made[name] = make_learner(name, skill)
    return made[name]


def learner_parameters(learner: Learner) -> dict:
    """The learner's hyper-parameters (``get_params``: what its constructor took), for the log."""
    return {key: value.item() if isinstance(value, np.generic) else value
            for key, value in learner.get_params().items()}


def learnt_actions(episode) -> np.ndarray:
    """(N, R) the complete episode's fitted policy at its own query states."""
    policy = learnt_policy(episode.learner, episode.skill, episode.query_states, episode.actions)
    return np.asarray(policy(episode.query_states), dtype=float)


def learnt_policy_of(name: str, skill, query_states, actions, lam: float):
    """The policy ``name``'s learner (ridge: with the protocol's ``lam``) learns for ``skill`` from
    logged query states (N, state_dim) and actions (N, R): a callable from states (M, state_dim)
    to actions (M, R)."""
    learner = study_learner(name, skill)
    if learner is None:
        learner = RidgeLearner(lam)
    return learnt_policy(learner, skill, np.asarray(query_states, dtype=float), np.asarray(actions, dtype=float))


__all__ = ["PAPER_LEARNER", "learner_parameters", "learnt_actions", "learnt_policy_of", "study_learner"]
