"""The robot learner a study's episodes teach, and what its log records of each learner.

A protocol names its learner (``learner = ...``, one of ``mt_widgets.core.LEARNERS``; "ridge", the
paper's, when absent). Every learner is made here, once per skill, with ``make_learner``'s defaults
for that skill (a kernel learner's width is the skill's typical distance, so it depends on the
skill) and the hyper-parameters the protocol sets for its class (``Learner.protocol_parameters``:
ridge's ``lam`` is the protocol's ``lambda``). A learner with a Theta on the skill's features logs
Theta_hat and the paper's analysis (the paper protocols' log, unchanged); every other learner's
episodes log what every learner can give instead: the learner's name and parameters
(``episode_started``), and the fitted policy's actions at the query states (``episode_finished``'s
``learnt_actions``). Since a
learner's fit is deterministic, the logged query states and actions give back the learnt policy
(``learnt_policy_of``), which is how the analysis rolls out what a participant taught.
"""

from __future__ import annotations

import weakref

import numpy as np

from mt_widgets.core.learner import Learner
from mt_widgets.core.learner_teaching import LEARNERS, learnt_policy, make_learner

#: skill -> {(learner name, protocol-set parameters): the learner}: one per skill (a kernel width is
#: computed once), weakly keyed by the skill object so an entry goes with its skill.
_LEARNERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def study_learner(protocol, skill) -> Learner:
    """The protocol's learner for ``skill``'s episodes: ``make_learner(protocol.learner, skill)`` with
    the hyper-parameters the protocol sets for its class (``Learner.protocol_parameters``; for the
    paper's protocols a ``RidgeLearner`` with the protocol's ``lambda``)."""
    name = protocol.learner
    cls = LEARNERS.get(name)
    given = {} if cls is None else {parameter: getattr(protocol, attribute)
                                    for parameter, attribute in cls.protocol_parameters}
    made = _LEARNERS.setdefault(skill, {})
    key = (name, tuple(sorted(given.items())))
    if key not in made:
        made[key] = make_learner(name, skill, **given)
    return made[key]


def learner_parameters(learner: Learner) -> dict:
    """The learner's hyper-parameters (``get_params``: what its constructor took), for the log."""
    return {key: value.item() if isinstance(value, np.generic) else value
            for key, value in learner.get_params().items()}


def learnt_actions(episode) -> np.ndarray:
    """(N, R) the complete episode's fitted policy at its own query states."""
    policy = learnt_policy(episode.learner, episode.skill, episode.query_states, episode.actions)
    return np.asarray(policy(episode.query_states), dtype=float)


def learnt_policy_of(protocol, skill, query_states, actions):
    """The policy the protocol's learner (``study_learner``) learns for ``skill`` from logged query
    states (N, state_dim) and actions (N, R): a callable from states (M, state_dim) to actions (M, R)."""
    learner = study_learner(protocol, skill)
    return learnt_policy(learner, skill, np.asarray(query_states, dtype=float), np.asarray(actions, dtype=float))


__all__ = ["learner_parameters", "learnt_actions", "learnt_policy_of", "study_learner"]
