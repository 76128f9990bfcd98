"""One teaching episode, headless: the model that a view renders and a study session records.

An episode is the paper's unit of teaching: a skill, its query states x_1..x_N and their
features Phi (N x S), the learner's lambda, the optimal actions U_bar, and the teacher's
demonstrations u_1..u_N given one at a time. Each demonstration is analysed as it comes (its
gap to the optimal action, and how much that gap can move the learnt skill). Once all N are
given the episode knows what the robot learnt and how far it is from the skill:

- ``theta_hat``: (R, S) ``Theta_hat^T = A U`` with ``A = (Phi^T Phi + lam I)^-1 Phi^T``;
- ``theta_error``: E = ||vec(Theta_hat) - vec(Theta)||_2 (``policy_risk`` for every learner);
- ``rho1 = ||A||_2``, ``rho2 = ||U - U_bar||_F`` and the bound ``rho1 * rho2 >= E``;
- ``contributions``: each demonstration's exact term of the error,
  ``Theta_hat - Theta = sum_n (u_n - u_bar_n) a_n^T + residual`` (a_n the n-th column of A;
  the residual ``(A U_bar)^T - Theta`` is zero when exact teaching is possible);
- ``reproduction``: the learnt skill rolled out from the skill's start, computed once, on first
  use, and kept, so a view that plays it and a log that records it share one rollout.

Everything is computed from one SVD of Phi (the learner's ``operator``: ``ridge_operator`` for
ridge), the same rank rule as ``RidgeLearner`` and ``optimal_actions``. That is the path of every
learner with a Theta on the skill's features (``learner.ParametricSmoother``); any other learner's
episode reports the policy risk and its own machine teaching (``TeachingEpisode``'s ``learner``).
Nothing here does I/O or knows about widgets.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np

from .learner import DEFAULT_LAMBDA, Learner, RidgeLearner, is_parametric_smoother
from .learner_teaching import action_sensitivity, evaluation_states, learnt_policy, policy_risk, teach
from .machine_teaching import (
    ActionDifference,
    TeachingAnalysis,
    action_difference,
    analyse_with,
    optimal_from,
)
from .skills import Skill
from .validation import as_float_array, as_positive


class EpisodeStateError(RuntimeError):
    """A call that does not fit the episode's progress (a demonstration too many, a result too early)."""


@dataclass(frozen=True)
class Demonstration:
    """One demonstration: what the person gave at a query state, and what can be said about it at once.

    The one record of a demonstration: a view builds it (``TeachingEpisode.analyse``) when an
    arrow is confirmed, the study log writes it, and the episode keeps it in ``demonstrations``.
    Nothing copies it: a view, a session and a step all read the episode's.

    Attributes:
        index: 0-based position of the query state in the episode.
        state: (state_dim,) the query state.
        action: (R,) the demonstrated action u_n, in the skill's action units.
        optimal_action: (R,) the optimal action u_bar_n at this state (computed whether or not
            it is shown).
        gap: (R,) u_n - u_bar_n.
        action_difference: angle, size ratio and distance of the arrow against the optimal one
            (an ``ActionDifference``) for planar actions (R = 2); None otherwise.
        contribution_norm: ||a_n|| ||u_n - u_bar_n||, the size of this demonstration's term
            (u_n - u_bar_n) a_n^T in Theta_hat - Theta. Known before the episode is complete,
            since a_n depends only on the query states.
        method: how it was given: "pointer", "keyboard", "numeric", "hand", "code", ...
        time_to_first_input_s: seconds from the state appearing to the first input (None: not
            measured, e.g. given by code).
        drawing_duration_s: seconds from the first input to the confirmation (None: not measured).
        redraws: how many times the arrow was set before it was confirmed.
        confirmed_at: wall-clock time of the confirmation (``time.time()``), None when unknown.
        guidance_shown: whether the optimal arrow was shown after this demonstration.
        episode_index: the episode's index as its view was told (0 when none).
    """

    index: int
    state: np.ndarray
    action: np.ndarray
    optimal_action: np.ndarray
    gap: np.ndarray
    action_difference: ActionDifference | None
    contribution_norm: float
    method: str = "code"
    time_to_first_input_s: float | None = None
    drawing_duration_s: float | None = None
    redraws: int = 0
    confirmed_at: float | None = None
    guidance_shown: bool = False
    episode_index: int = 0


#: The name ``Demonstration`` had when it held the analysis only (kept: ``mt_widgets.core`` exports it).
DemonstrationAnalysis = Demonstration


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


#: skill -> {duration: the target skill's own rollout}. Keyed by the skill object itself (a Skill
#: hashes by identity), weakly: an entry goes with its skill, and a new skill that happens to
#: get a freed skill's id never gets that skill's ghost.
_TARGET_ROLLOUTS: weakref.WeakKeyDictionary[Skill, dict[float, object]] = weakref.WeakKeyDictionary()


def target_reproduction(skill: Skill, duration: float | None = None):
    """The target skill's own rollout (``skill.theta`` from ``skill.start``, or the skill's target
    ``policy`` when it has one), computed once per skill and duration.

    Views draw it faintly beside a learnt reproduction; it depends on nothing a teacher does,
    so every episode of a skill shares one.
    """
    if not isinstance(skill, Skill):
        raise TypeError(f"skill: expected a mt_widgets.core.Skill, got {type(skill).__name__}")
    duration = skill.default_duration if duration is None else as_positive("duration", duration)
    rollouts = _TARGET_ROLLOUTS.setdefault(skill, {})
    if duration not in rollouts:
        # A nonlinear skill's target is its policy, not its best linear theta.
        rollouts[duration] = (skill.reproduce(skill.theta, duration=duration) if skill.policy is None
                              else skill.reproduce_policy(skill.policy, duration=duration))
    return rollouts[duration]


class TeachingEpisode:
    """One teaching episode of a skill on its query states.

    Args:
        skill: the ``Skill`` taught.
        query_states: (N, state_dim) the states to demonstrate at; default
            ``skill.query_states(seed=seed)`` (N = S, the rank condition's minimum).
        seed: seed of the default query states (int, ``SeedSequence``, ``Generator`` or None);
            only when ``query_states`` is not given.
        lam: the default learner's ridge parameter (>= 0; default ``DEFAULT_LAMBDA``). With a
            learner given that has a ``lam`` of its own, that is the one source: a different
            explicit ``lam`` beside it is refused.
        duration: seconds of the reproduction (default: the skill's ``default_duration``).
        learner: the learner (``mt_widgets.core.LEARNERS``; None: ``RidgeLearner(lam)``, the
            paper's). Every learner takes one path, chosen by what it declares: a learner with a
            Theta on the skill's features (``learner.ParametricSmoother``: ridge) gets the paper's
            analysis from its operator A (``theta_hat``, ``theta_error``, ``analysis``,
            ``contributions``, ``residual``, ``bound``); any other gets its machine teaching's
            optimal actions (``teach``), ``rho1`` and each demonstration's ``contribution_norm``
            from ``action_sensitivity``, ``exact`` when the target is representable from the query
            states, and asking it for what only a Theta gives raises an ``EpisodeStateError``.
            ``policy_risk`` and ``reproduction`` exist for every learner.

    Attributes:
        features: (N, S) Phi.
        optimal_actions: (N, R) U_bar, the demonstration that teaches the skill (exactly when
            ``exact``).
        exact: True when Phi has rank S (the query states meet the rank condition); when
            False no demonstration teaches Theta exactly (``optimal_actions`` of
            ``mt_widgets.core`` then warns with ``UnderdeterminedTeachingWarning``) and U_bar is
            the least-error one.
        rank: the rank of Phi.
        demonstrations: the ``Demonstration`` of each demonstration given so far, in order: the one
            place they live (a view, a session and a study step read this list).
    """

    def __init__(self, skill: Skill, query_states=None, *, seed=None, lam: float | None = None,
                 duration: float | None = None, learner: Learner | None = None):
        if learner is not None and not isinstance(learner, Learner):
            raise TypeError(f"learner: expected a mt_widgets.core Learner or None, got {type(learner).__name__}")
        if not isinstance(skill, Skill):
            raise TypeError(f"skill: expected a mt_widgets.core.Skill, got {type(skill).__name__}")
        self.skill = skill
        # Whatever the learner, its own ``lam`` (when it has one) is the one source: an explicit lam
        # beside a learner with another is refused.
        own = None if learner is None else learner.get_params().get("lam")
        if own is not None:
            learner.check_params()
            if lam is not None and as_positive("lam", lam, allow_zero=True) != float(own):
                raise ValueError(f"lam: expected none (or the learner's own lam {own}) beside {learner!r}, got "
                                 f"{lam}: the learner's lam is the one source")
            lam = own
        self.lam = as_positive("lam", DEFAULT_LAMBDA if lam is None else lam, allow_zero=True)
        self.duration = skill.default_duration if duration is None else as_positive("duration", duration)
        if query_states is None:
            states = skill.query_states(seed=seed)
        else:
            if seed is not None:
                raise ValueError(f"seed: expected None when query_states are given (the states are not drawn), "
                                 f"got {seed!r}")
            states = as_float_array("query_states", query_states, ndim=2, shape=(None, skill.state_dim))
            if len(states) == 0:
                raise ValueError(f"query_states: expected at least one state of {skill.state_dim} numbers, "
                                 f"got shape {states.shape}")
        self.query_states = _frozen(states)
        self.features = _frozen(skill.features(self.query_states))
        self.learner = learner if learner is not None else RidgeLearner(self.lam)
        self.demonstrations: list[Demonstration] = []
        self._reproduction = None
        self._analysis = None
        self._policy_risk = None
        if not is_parametric_smoother(self.learner):
            self._init_learner()
            return
        # A learner with a Theta on the skill's features (the paper's ridge): the paper's analysis,
        # from one SVD of Phi.
        operator = self.learner.operator(self.features)
        self._operator = operator
        self._A = operator.matrix()                      # (S, N)
        self._a_norms = np.linalg.norm(self._A, axis=0)  # (N,) ||a_n||
        self.optimal_actions = _frozen(optimal_from(operator, skill.theta))
        self.rank = operator.rank
        self.exact = bool(operator.exact)
        self.rho1 = operator.rho1()

    def _init_learner(self) -> None:
        """Machine teaching for a learner without a Theta on the features (``learner`` in the class docstring)."""
        self._evaluation = evaluation_states(self.skill)
        teaching = teach(self.learner, self.skill, self.query_states, self._evaluation)
        self.teaching = teaching
        self.optimal_actions = _frozen(teaching.optimal)
        self.rho1, self._a_norms = action_sensitivity(self.learner, self.skill, self.query_states, teaching.optimal,
                                                      self._evaluation)
        self.exact = bool(teaching.representable)
        self.rank = len(self.query_states)
        self._operator = None

    @property
    def has_theta(self) -> bool:
        """Whether the learner has a Theta on the skill's features (a ``ParametricSmoother`` such as
        the paper's ridge): then Theta_hat and the paper's analysis exist."""
        return self._operator is not None

    def _require_theta(self, name: str) -> None:
        if not self.has_theta:
            raise EpisodeStateError(f"{name}: only a learner with a Theta on the skill's features (learner."
                                    f"ParametricSmoother, such as ridge) has one; this episode's learner is "
                                    f"{self.learner!r}: use policy_risk and reproduction")

    @classmethod
    def from_actions(cls, skill: Skill, query_states, actions, *, lam: float | None = None,
                     duration: float | None = None, learner: Learner | None = None) -> TeachingEpisode:
        """An episode resumed with actions already given (k, R), k <= N (complete when k = N)."""
        episode = cls(skill, query_states, lam=lam, duration=duration, learner=learner)
        episode.restore(actions)
        return episode

    def __repr__(self) -> str:
        return (f"TeachingEpisode({self.skill.key!r}, {len(self.demonstrations)}/{self.n_states} demonstrations, "
                f"lam={self.lam})")

    # -- progress ---------------------------------------------------------------------------------
    @property
    def n_states(self) -> int:
        """N, the number of query states (and of demonstrations a complete episode has)."""
        return len(self.query_states)

    @property
    def action_dim(self) -> int:
        return self.skill.plant.action_dim

    @property
    def complete(self) -> bool:
        """True once every query state has its demonstration."""
        return len(self.demonstrations) == self.n_states

    @property
    def next_index(self) -> int | None:
        """The index of the query state awaiting a demonstration, or None when complete."""
        return None if self.complete else len(self.demonstrations)

    @property
    def actions(self) -> np.ndarray:
        """(k, R) the demonstrated actions so far."""
        if not self.demonstrations:
            return np.zeros((0, self.action_dim))
        return np.array([d.action for d in self.demonstrations])

    # -- demonstrating ------------------------------------------------------------------------------
    def check_action(self, action) -> np.ndarray:
        """Validates one action (R,) without recording it; returns it as a float array."""
        return as_float_array("action", action, ndim=1, shape=(self.action_dim,))

    def analyse(self, action, *, method: str = "code", time_to_first_input_s: float | None = None,
                drawing_duration_s: float | None = None, redraws: int = 0, confirmed_at: float | None = None,
                guidance_shown: bool = False, episode_index: int = 0) -> Demonstration:
        """The ``Demonstration`` the action (R,) would be at the next query state, NOT recorded.

        A view hands it to whoever must keep it first (the study log) and records it with
        ``record`` once they did, so a demonstration the log refused is never counted.
        The keyword arguments say how it was given (see ``Demonstration``).
        """
        if self.complete:
            raise EpisodeStateError(f"demonstrate: expected at most {self.n_states} demonstrations (one per query "
                                    f"state); the episode is complete")
        action = _frozen(self.check_action(action))
        if not isinstance(method, str):
            raise TypeError(f"method: expected text (how the action was given), got {type(method).__name__}")
        index = len(self.demonstrations)
        optimal = self.optimal_actions[index]
        gap = _frozen(action - optimal)
        difference = action_difference(action, optimal) if self.action_dim == 2 else None
        return Demonstration(index, self.query_states[index], action, optimal, gap, difference,
                             float(self._a_norms[index] * np.linalg.norm(gap)), method, time_to_first_input_s,
                             drawing_duration_s, int(redraws), confirmed_at, bool(guidance_shown),
                             int(episode_index))

    def record(self, demonstration: Demonstration) -> Demonstration:
        """Keeps a ``Demonstration`` from ``analyse`` as the next one; returns it.

        Recording the very demonstration already kept at its index again does nothing (a
        session and the view it serves both record the one object: whoever comes first).
        """
        if not isinstance(demonstration, Demonstration):
            raise TypeError(f"demonstration: expected a Demonstration (from analyse), got "
                            f"{type(demonstration).__name__}")
        index = demonstration.index
        if index < len(self.demonstrations) and self.demonstrations[index] is demonstration:
            return demonstration
        if index != len(self.demonstrations):
            raise EpisodeStateError(f"record: expected demonstration {len(self.demonstrations)} (the next one), "
                                    f"got demonstration {index}")
        if not (np.array_equal(demonstration.state, self.query_states[index])
                and np.array_equal(demonstration.optimal_action, self.optimal_actions[index])):
            raise ValueError(f"demonstration: expected one analysed by this episode (its query state {index} and "
                             f"optimal action), got another episode's")
        self.demonstrations.append(demonstration)
        return demonstration

    def demonstrate(self, action, **given) -> Demonstration:
        """Records the action (R,) for the next query state and returns its ``Demonstration``
        (``given``: how it was given, as for ``analyse``)."""
        return self.record(self.analyse(action, **given))

    def _check_actions(self, name: str, actions) -> np.ndarray:
        """(k, R) actions, one per row; the one place their shape is checked."""
        try:
            given = len(actions)
        except TypeError:
            raise ValueError(f"{name}: expected shape (k, {self.action_dim}), one action per row, got "
                             f"{type(actions).__name__} {actions!r}"[:200]) from None
        if given == 0:
            return np.zeros((0, self.action_dim))
        actions = as_float_array(name, actions)
        if actions.ndim != 2 or actions.shape[1] != self.action_dim:
            raise ValueError(f"{name}: expected shape (k, {self.action_dim}), one action per row, got "
                             f"{actions.shape}")
        return actions

    def restore(self, actions) -> None:
        """Records already-given actions (k, R) in order, after any given so far (resuming)."""
        actions = self._check_actions("actions", actions)
        if len(self.demonstrations) + len(actions) > self.n_states:
            raise ValueError(f"actions: expected at most {self.n_states - len(self.demonstrations)} more (one per "
                             f"remaining query state), got {len(actions)}")
        for action in actions:
            self.demonstrate(action)

    def extend_to(self, actions, name: str = "actions") -> None:
        """Brings the episode up to all of ``actions`` (k, R), k <= N, given so far (resuming a view).

        The episode's own demonstrations must be the first of them: an episode holding other
        actions is refused (``ValueError``), never rebuilt, so no recorded demonstration is lost.
        ``name`` is the argument named in errors.
        """
        actions = self._check_actions(name, actions)
        if len(actions) > self.n_states:
            raise ValueError(f"{name}: expected at most {self.n_states} (one per query state), got {len(actions)}")
        held = self.actions
        if len(held) > len(actions) or not np.array_equal(held, actions[:len(held)]):
            raise ValueError(f"{name}: expected the {len(held)} actions the episode holds first, then any more, "
                             f"got {len(actions)} others")
        for action in actions[len(held):]:
            self.demonstrate(action)

    # -- the result (complete episodes) -------------------------------------------------------------
    def _require_complete(self, name: str) -> None:
        if not self.complete:
            raise EpisodeStateError(f"{name}: expected a complete episode ({self.n_states} demonstrations), "
                                    f"got {len(self.demonstrations)}")

    @property
    def analysis(self) -> TeachingAnalysis:
        """The complete episode's ``TeachingAnalysis``: ``analyse_demonstrations``' numbers,
        computed once through the same function (``analyse_with``) from the episode's own SVD."""
        self._require_complete("analysis")
        self._require_theta("analysis")
        if self._analysis is None:
            self._analysis = analyse_with(self._operator, self.actions, self.skill.theta)
        return self._analysis

    @property
    def theta_hat(self) -> np.ndarray:
        """(R, S) the learnt policy, Theta_hat^T = A U."""
        self._require_complete("theta_hat")
        self._require_theta("theta_hat")
        return self.analysis.theta_hat

    @property
    def theta_error(self) -> float | None:
        """||vec(Theta_hat) - vec(Theta)||_2 where the learner has a Theta (ridge), else None."""
        self._require_complete("theta_error")
        return self.analysis.risk if self.has_theta else None

    @property
    def policy_risk(self) -> float:
        """The policy risk of what the learner learnt (``learner_teaching``), for every learner:
        the root-mean-square distance to the target's actions over the skill's evaluation states."""
        self._require_complete("policy_risk")
        if self._policy_risk is None:
            evaluation = evaluation_states(self.skill)
            policy = learnt_policy(self.learner, self.skill, self.query_states, self.actions)
            self._policy_risk = policy_risk(policy(evaluation), self.skill.target_actions(evaluation))
        return self._policy_risk

    @property
    def rho2(self) -> float:
        """||U - U_bar||_F over the demonstrations given so far (all of them once complete)."""
        if not self.demonstrations:
            return 0.0
        return float(np.linalg.norm([d.gap for d in self.demonstrations]))

    @property
    def bound(self) -> float:
        """rho1 * rho2 (+ the residual norm when the rank condition fails), an upper bound on E."""
        self._require_complete("bound")
        self._require_theta("bound")
        return self.rho1 * self.rho2 + self.residual_norm

    @property
    def contributions(self) -> np.ndarray:
        """(N, R, S) each demonstration's exact term (u_n - u_bar_n) a_n^T of Theta_hat - Theta.

        They add up, with ``residual``, to Theta_hat - Theta exactly. Their norms
        (``contribution_norms``) say how large each term is but do NOT add up to E: the terms
        point in different directions and partly cancel, so E <= sum of the norms (+ the
        residual's), with equality only when they are aligned.
        """
        self._require_complete("contributions")
        self._require_theta("contributions")
        gaps = np.array([d.gap for d in self.demonstrations])           # (N, R)
        return gaps[:, :, None] * self._A.T[:, None, :]                  # (N, R, S)

    @property
    def contribution_norms(self) -> np.ndarray:
        """(N,) ||(u_n - u_bar_n) a_n^T||_F = ||a_n|| ||u_n - u_bar_n|| (see ``contributions``)."""
        self._require_complete("contribution_norms")
        return np.array([d.contribution_norm for d in self.demonstrations])

    @property
    def residual(self) -> np.ndarray:
        """(R, S) (A U_bar)^T - Theta: the part of the error no demonstration can remove (0 when exact)."""
        self._require_theta("residual")
        return (self._A @ self.optimal_actions).T - self.skill.theta

    @property
    def residual_norm(self) -> float:
        return float(np.linalg.norm(self.residual))

    @property
    def reproduction(self):
        """The learnt skill's ``Trajectory`` from the skill's start over ``duration`` seconds.

        Rolled out on first use and kept: every reader (a view, a log, a result) gets this one.
        """
        self._require_complete("reproduction")
        if self._reproduction is None and not self.has_theta:
            policy = learnt_policy(self.learner, self.skill, self.query_states, self.actions)
            self._reproduction = self.skill.reproduce_policy(policy, duration=self.duration)
        if self._reproduction is None:
            self._reproduction = self.skill.reproduce(self.theta_hat, duration=self.duration)
        return self._reproduction

    @property
    def target_reproduction(self):
        """The target skill's own rollout over ``duration`` (shared by every episode of the skill)."""
        return target_reproduction(self.skill, self.duration)

    @property
    def reproduced(self) -> bool:
        """Whether the reproduction has been rolled out yet (it is, on first use of ``reproduction``)."""
        return self._reproduction is not None


@dataclass(frozen=True)
class EpisodeResult:
    """A finished episode as a view or a study session reports it: its ``TeachingEpisode``, with
    where it was taught and how fast the view answered. Every number is read from the episode:
    nothing is copied, so the result, the view and the log can never disagree.

    Attributes:
        episode: the complete ``TeachingEpisode`` (query states, demonstrations, theta_hat, ...).
        feedback_latency_s: seconds from the last confirmation to the reproduction sent (a view's;
            None from a session).
        phase, phase_index: the study phase ("P3") and its 0-based index (None outside a study).
        episode_number: the 1-based episode within the phase (None outside a study).
    """

    episode: TeachingEpisode = field(repr=False, compare=False)
    feedback_latency_s: float | None = None
    phase: str | None = None
    phase_index: int | None = None
    episode_number: int | None = None

    def __post_init__(self):
        if not isinstance(self.episode, TeachingEpisode):
            raise TypeError(f"episode: expected a TeachingEpisode, got {type(self.episode).__name__}")
        if not self.episode.complete:
            raise EpisodeStateError(f"episode: expected a complete episode ({self.episode.n_states} "
                                    f"demonstrations), got {len(self.episode.demonstrations)}")

    @property
    def teaching_episode(self) -> TeachingEpisode:
        """The episode (the name a study step uses)."""
        return self.episode

    @property
    def skill_key(self) -> str:
        return self.episode.skill.key

    @property
    def query_states(self) -> np.ndarray:
        """(N, state_dim)."""
        return self.episode.query_states

    @property
    def demonstrations(self) -> np.ndarray:
        """(N, R) the demonstrated actions (the episode's ``actions``)."""
        return self.episode.actions

    @property
    def optimal_actions(self) -> np.ndarray:
        """(N, R) U_bar for these states and ``lam``."""
        return self.episode.optimal_actions

    @property
    def lam(self) -> float:
        return self.episode.lam

    @property
    def theta_hat(self) -> np.ndarray:
        """(R, S) the learnt policy."""
        return self.episode.theta_hat

    @property
    def theta_error(self) -> float | None:
        """||Theta_hat - Theta|| where the learner has a Theta, else None (the episode's)."""
        return self.episode.theta_error

    @property
    def policy_risk(self) -> float:
        """The learnt policy's risk (the episode's), for every learner."""
        return self.episode.policy_risk

    @property
    def rho1(self) -> float:
        return self.episode.rho1

    @property
    def rho2(self) -> float:
        return self.episode.rho2

    @property
    def trajectory(self):
        """The learnt skill's reproduction: the episode's one rollout."""
        return self.episode.reproduction

    @property
    def diverged(self) -> bool:
        return bool(self.episode.reproduction.diverged)


__all__ = ["Demonstration", "DemonstrationAnalysis", "EpisodeResult", "EpisodeStateError", "TeachingEpisode",
           "target_reproduction"]
