"""Machine teaching for any learner: exact for linear smoothers, approximate for the rest.

**The teaching risk of a learner that has no Theta.** The paper measures teaching by
``||Theta_hat - Theta||``, which only a parametric learner on the skill's own features has. For
every learner this module measures the *policy risk*: the root-mean-square distance between the
learnt policy's actions and the target's over a fixed evaluation set of the skill's states
(``evaluation_states``: 256 states the plant samples as it samples query states, seed 0),

    R = sqrt( (1/M) sum_m ||pi_hat(x_m) - pi*(x_m)||^2 ),

in the skill's action units. For ridge it is ``sqrt(tr(dTheta Sigma dTheta^T))`` with
``Sigma = (1/M) sum_m phi(x_m) phi(x_m)^T``: zero exactly when Theta is taught exactly (Sigma has
full rank), and comparable across learners on one skill, which ``||dTheta||`` is not.

**Exact machine teaching for a linear smoother** (ridge, kernel ridge, a GP's posterior mean):
the learnt policy on the evaluation states is ``S U`` with S (M, N) fixed by the query states, so
the least-risk demonstration is the least-squares solution ``U = pinv(S) Y*`` (Y* the target's
actions on the evaluation states), the minimum-norm one when several are. Its risk is the risk
no demonstration on these query states can remove: 0 (to machine precision) when the target is
representable from them, the least achievable otherwise. For ridge with Phi of full column rank
it is the paper's ``U_bar = pinv(A) Theta^T``.

**Approximate machine teaching** for a learner not linear in the actions (the neural network):
Levenberg-Marquardt on the demonstrated actions against the same risk, the Jacobian of the
learnt policy by finite differences through the (deterministic) fit, started from the target's
own actions at the query states and accepting only steps that lower the risk; so its risk is
never above the target actions' risk. It is a local optimum, and it says so (``exact`` False).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

import numpy as np

from .kernel_learners import GaussianProcessLearner, KernelRidgeLearner
from .learner import Learner, RidgeLearner, has_batched_fit, is_linear_smoother
from .network_learner import NeuralNetworkLearner
from .reward_learner import RewardLearner
from .ridge_kernels import svd_with_rank
from .validation import UnknownKeyError, as_count, as_float_array

#: The learners a protocol or a notebook can name, and their classes.
LEARNERS = {
    "ridge": RidgeLearner,
    "kernel-ridge": KernelRidgeLearner,
    "gaussian-process": GaussianProcessLearner,
    "neural-network": NeuralNetworkLearner,
    "reward": RewardLearner,
}

#: How many evaluation states measure the policy risk.
EVALUATION_SIZE = 256


def learner_inputs(learner: Learner, skill, states) -> np.ndarray:
    """What ``learner`` learns from at states (N, state_dim): features, states or task space (N, D)."""
    learner.check_params()   # its inputs among them
    states = as_float_array("states", states, ndim=2, shape=(None, skill.state_dim))
    if learner.inputs == "features":
        return skill.features(states)
    if learner.inputs == "state":
        return states
    positions, velocities = skill.end_effector(states)
    return np.concatenate([positions, velocities], axis=-1)


def evaluation_states(skill, n: int = EVALUATION_SIZE, seed: int = 0) -> np.ndarray:
    """n valid states of the skill's plant, seeded: where the policy risk is measured."""
    n = as_count("n", n)
    rng = np.random.default_rng(seed)
    kept = np.empty((0, skill.state_dim))
    for _ in range(100):
        states = skill.plant.sample_states(rng, 2 * n)
        kept = np.concatenate([kept, states[skill.plant.is_valid_state(states)]])
        if len(kept) >= n:
            return kept[:n]
    raise ValueError(f"skill: its plant gave {len(kept)} valid states out of {200 * n} sampled, fewer than the "
                     f"{n} the evaluation set needs")


def typical_length_scale(skill, inputs: str = "task") -> float:
    """The median distance between the skill's evaluation states in a learner's input space: the
    default RBF width (the median heuristic), so one default serves metres and centimetres."""
    probe = KernelRidgeLearner(1.0, inputs=inputs)
    X = learner_inputs(probe, skill, evaluation_states(skill, 128))
    distances = np.linalg.norm(X[:, None, :] - X[None, :, :], axis=-1)
    return float(np.median(distances[np.triu_indices(len(X), 1)]))


def make_learner(name: str, skill=None, **parameters) -> Learner:
    """The learner called ``name`` (one of ``LEARNERS``) with ``parameters``, checked; a kernel
    learner's ``length_scale`` defaults to ``typical_length_scale(skill)`` when a skill is given.
    Every other hyper-parameter has its class's default (one default per hyper-parameter)."""
    if name not in LEARNERS:
        raise UnknownKeyError(f"learner: expected one of the available learners ({', '.join(LEARNERS)}), got {name!r}")
    cls = LEARNERS[name]
    if cls in (KernelRidgeLearner, GaussianProcessLearner) and "length_scale" not in parameters:
        if skill is None:
            raise ValueError(f"length_scale: expected a kernel width for {name!r}, or a skill to take the "
                             f"typical one from, got neither")
        inputs = parameters.get("inputs", inspect.signature(cls).parameters["inputs"].default)
        parameters["length_scale"] = typical_length_scale(skill, inputs)
    try:
        learner = cls(**parameters)
    except TypeError as error:
        raise TypeError(f"{name}: {error}") from None
    learner.check_params()   # a protocol's or a notebook's bad value fails here, by name
    return learner


def policy_risk(predicted, target) -> float:
    """R = sqrt(mean_m ||predicted_m - target_m||^2) over the rows of (M, R) arrays."""
    predicted = as_float_array("predicted", predicted, ndim=2)
    target = as_float_array("target", target, ndim=2, shape=predicted.shape)
    return float(np.sqrt(np.mean(np.sum((predicted - target) ** 2, axis=1))))


def risk_of_actions(learner: Learner, skill, query_states, actions, eval_states=None) -> float:
    """The policy risk of what ``learner`` learns from ``actions`` (N, R) at ``query_states``."""
    eval_states = evaluation_states(skill) if eval_states is None else eval_states
    fitted = learner.fit(learner_inputs(learner, skill, query_states), actions)
    predicted = learner.predict(fitted, learner_inputs(learner, skill, eval_states))
    return policy_risk(predicted, skill.target_actions(eval_states))


@dataclass(frozen=True)
class LearnerTeaching:
    """Machine teaching's answer for one learner, skill and set of query states.

    Attributes:
        optimal: (N, R) the least-risk demonstration MT found.
        risk: its policy risk (for exact MT, the risk no demonstration on these states removes).
        target_risk: the policy risk of the target's own actions at the query states.
        exact: True for a linear smoother (the least-squares optimum); False: a local optimum.
        representable: whether ``risk`` is zero to working precision (exact MT only).
        iterations: the optimiser's accepted steps (0 for exact MT).
    """

    optimal: np.ndarray
    risk: float
    target_risk: float
    exact: bool
    representable: bool
    iterations: int = 0


def teach(learner: Learner, skill, query_states, eval_states=None, **options) -> LearnerTeaching:
    """Machine teaching for ``learner``: ``exact_teaching`` for a linear smoother, otherwise
    ``approximate_teaching`` (``options`` go to it)."""
    if is_linear_smoother(learner):
        return exact_teaching(learner, skill, query_states, eval_states)
    return approximate_teaching(learner, skill, query_states, eval_states, **options)


def exact_teaching(learner: Learner, skill, query_states, eval_states=None) -> LearnerTeaching:
    """The least-squares demonstration ``pinv(S) Y*`` for a linear smoother (module docstring)."""
    if not is_linear_smoother(learner):
        raise TypeError(f"learner: expected a linear smoother (a learner with a smoother matrix, "
                        f"learner.LinearSmoother) for exact teaching, got {learner!r}, which is not linear in the "
                        f"demonstrated actions; its machine teaching is approximate (approximate_teaching)")
    query_states = as_float_array("query_states", query_states, ndim=2, shape=(None, skill.state_dim))
    eval_states = evaluation_states(skill) if eval_states is None else eval_states
    X_eval = learner_inputs(learner, skill, eval_states)
    S = learner.smoother(learner_inputs(learner, skill, query_states), X_eval)
    Y = skill.target_actions(eval_states)
    left, singular, right_t, rank = svd_with_rank(np.ascontiguousarray(S))
    optimal = right_t[:rank].T @ ((left[:, :rank].T @ Y) / singular[:rank, None])
    risk = policy_risk(S @ optimal, Y)
    target_risk = policy_risk(S @ skill.target_actions(query_states), Y)
    # Representable: what is left is round-off, relative to the size of the target's actions.
    scale = float(np.sqrt(np.mean(np.sum(Y * Y, axis=1))))
    return LearnerTeaching(optimal, risk, target_risk, True, risk <= 1e-9 * max(scale, 1e-300))


def approximate_teaching(learner: Learner, skill, query_states, eval_states=None, *, iterations: int = 4,
                         start=None) -> LearnerTeaching:
    """Levenberg-Marquardt on the actions against the policy risk (module docstring); approximate.

    Args:
        learner: any learner; one with a batched fit (``learner.BatchedFit``: the network) fits the
            Jacobian's perturbed demonstrations in one pass.
        skill, query_states, eval_states: as for ``exact_teaching``.
        iterations: Jacobian evaluations at most.
        start: (N, R) the actions to start from (default: the target's at the query states).
    """
    iterations = as_count("iterations", iterations)
    query_states = as_float_array("query_states", query_states, ndim=2, shape=(None, skill.state_dim))
    eval_states = evaluation_states(skill) if eval_states is None else eval_states
    X = learner_inputs(learner, skill, query_states)
    X_eval = learner_inputs(learner, skill, eval_states)
    Y = skill.target_actions(eval_states)
    target_actions = skill.target_actions(query_states)
    U = target_actions.copy() if start is None else as_float_array("start", start, shape=target_actions.shape)
    N, R = U.shape
    M = len(Y)

    def residuals(batch):   # (B, N, R) -> (B, M * R) scaled so that ||r||^2 = risk^2
        return (_predict_many(learner, X, batch, X_eval) - Y).reshape(len(batch), -1) / np.sqrt(M)

    step = 1e-4 * max(float(np.sqrt(np.mean(target_actions**2))), 1e-12)
    nudges = step * np.eye(N * R).reshape(N * R, N, R)

    def with_jacobians(points):   # (T, N, R) -> residuals (T, M R) and Jacobians (T, M R, N R)
        values = residuals(np.concatenate([np.concatenate([p[None], p[None] + nudges]) for p in points]))
        values = values.reshape(len(points), 1 + N * R, -1)
        return values[:, 0], np.transpose(values[:, 1:] - values[:, :1], (0, 2, 1)) / step

    (current,), (jacobian,) = with_jacobians(U[None])
    target_risk = float(np.linalg.norm(current)) if start is None else float(
        np.linalg.norm(residuals(target_actions[None])[0]))
    # A learner that trains a batch in one pass gets the trial points' Jacobians with them (one
    # pass an iteration); another fits them one by one, so only the accepted point's is taken.
    batched = has_batched_fit(learner)
    damping, accepted = 1e-3, 0
    for _ in range(iterations):
        gram = jacobian.T @ jacobian
        gradient = jacobian.T @ current
        trial_steps = [np.linalg.solve(gram + d * np.diag(np.diag(gram) + 1e-12), -gradient)
                       for d in (damping, 10 * damping, 100 * damping)]
        trials = np.stack([U + s.reshape(N, R) for s in trial_steps])
        trial_values, trial_jacobians = with_jacobians(trials) if batched else (residuals(trials), None)
        norms = np.linalg.norm(trial_values, axis=1)
        best = int(np.argmin(norms))
        if norms[best] >= np.linalg.norm(current):
            damping *= 1000.0
            continue
        U, damping, accepted = trials[best], damping * (10.0**best) / 3.0, accepted + 1
        if batched:
            current, jacobian = trial_values[best], trial_jacobians[best]
        else:
            (current,), (jacobian,) = with_jacobians(U[None])
    return LearnerTeaching(U, float(np.linalg.norm(current)), target_risk, False, False, accepted)


def _predict_many(learner: Learner, X, batch, X_eval) -> np.ndarray:
    """(B, M, R): what ``learner`` learns from each of B action sets (B, N, R) at X, at X_eval."""
    if has_batched_fit(learner):   # B fits in one pass (the network)
        return learner.predict_batch(learner.fit_batch(X, batch), X_eval)
    return np.stack([learner.predict(learner.fit(X, actions), X_eval) for actions in batch])


def action_sensitivity(learner: Learner, skill, query_states, actions, eval_states=None) -> tuple[float, np.ndarray]:
    """How much the policy risk can move per unit of action error: (rho1, gains (N,)).

    With J the Jacobian of the learnt policy on the evaluation states (divided by sqrt(M), as the
    risk is) with respect to the demonstrated actions, ``rho1 = ||J||_2`` and ``gains[n]`` the
    spectral norm of demonstration n's block, so a demonstration's gap g_n moves the risk by at
    most ``gains[n] |g_n|``. For a linear smoother J is ``S / sqrt(M)`` (exact, any actions); for
    another learner it is taken by finite differences at ``actions`` (a linearisation). For ridge
    on the features this is the paper's ``||A||_2`` weighted by the evaluation set's features.
    """
    query_states = as_float_array("query_states", query_states, ndim=2, shape=(None, skill.state_dim))
    eval_states = evaluation_states(skill) if eval_states is None else eval_states
    X, X_eval = learner_inputs(learner, skill, query_states), learner_inputs(learner, skill, eval_states)
    M = len(X_eval)
    if is_linear_smoother(learner):
        S = learner.smoother(X, X_eval) / np.sqrt(M)
        return float(np.linalg.norm(S, 2)), np.linalg.norm(S, axis=0)
    actions = as_float_array("actions", actions, ndim=2, shape=(len(X), None))
    N, R = actions.shape
    step = 1e-4 * max(float(np.sqrt(np.mean(actions**2))), 1e-12)
    batch = np.concatenate([actions[None], actions[None] + step * np.eye(N * R).reshape(N * R, N, R)])
    predicted = _predict_many(learner, X, batch, X_eval).reshape(len(batch), -1) / np.sqrt(M)
    J = (predicted[1:] - predicted[0]).T / step                       # (M R, N R)
    gains = np.array([np.linalg.norm(J[:, n * R:(n + 1) * R], 2) for n in range(N)])
    return float(np.linalg.norm(J, 2)), gains


def learnt_policy(learner: Learner, skill, query_states, actions):
    """The policy ``learner`` learns from ``actions`` at ``query_states``, as a function states -> actions."""
    fitted = learner.fit(learner_inputs(learner, skill, query_states), actions)
    return lambda states: learner.predict(fitted, learner_inputs(learner, skill, states))


@dataclass(frozen=True)
class TeachingComparison:
    """Machine teaching against two baselines over random query sets, one row per set.

    Attributes:
        mt: (K,) the policy risk MT's demonstration leaves.
        target: (K,) the risk of the target's own actions at the query states.
        random: (K,) the risk of random actions (normal, with the target actions' RMS size).
    """

    mt: np.ndarray
    target: np.ndarray
    random: np.ndarray

    @property
    def target_factor(self) -> float:
        """The median over sets of target risk / MT risk (> 1: MT leaves less risk)."""
        return float(np.median(self.target / self.mt))

    @property
    def random_factor(self) -> float:
        """The median over sets of random risk / MT risk."""
        return float(np.median(self.random / self.mt))


def compare_with_baselines(learner: Learner, skill, n_sets: int = 100, n_states: int | None = None, seed: int = 0,
                           **options) -> TeachingComparison:
    """MT's risk against the target's actions and random actions over ``n_sets`` random query
    sets of ``n_states`` states (default: the skill's number of features), seeded.

    ``options`` go to ``approximate_teaching`` for a learner that is not a linear smoother.
    """
    n_sets = as_count("n_sets", n_sets)
    rng = np.random.default_rng(seed)
    eval_states = evaluation_states(skill)
    rows = []
    for query_seed in rng.integers(0, 2**32, size=n_sets):
        query = skill.query_states(seed=int(query_seed), n=n_states)
        result = teach(learner, skill, query, eval_states, **options)
        target_actions = skill.target_actions(query)
        size = float(np.sqrt(np.mean(np.sum(target_actions**2, axis=1))))
        random_actions = rng.normal(scale=size / np.sqrt(target_actions.shape[1]), size=target_actions.shape)
        rows.append((result.risk, result.target_risk,
                     risk_of_actions(learner, skill, query, random_actions, eval_states)))
    mt, target, random = (np.array(column) for column in zip(*rows))
    return TeachingComparison(mt, target, random)
