"""Choosing the query states a teacher demonstrates at.

As in the paper, states are appended one at a time, pseudo-randomly, and a candidate is kept
only if the feature matrix of the states so far stays well conditioned (the ratio of its
largest to its smallest singular value stays under a threshold). Ill-conditioned states
make the learner amplify a teacher's small mistakes (rho1 = ||A||_2 grows as the smallest
singular value shrinks), so they would punish teachers for the states, not for their arrows.
"""

from __future__ import annotations

import numbers

import numpy as np

from .validation import as_count, as_positive


def condition_number(Phi: np.ndarray) -> float:
    """s_max / s_min over the min(N, S) singular values of Phi (N, S); inf when one is zero."""
    singular = np.linalg.svd(Phi, compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")


def make_rng(seed) -> np.random.Generator:
    """A generator from an int, a SeedSequence, a Generator or None (fresh entropy)."""
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None or isinstance(seed, np.random.SeedSequence):
        return np.random.default_rng(seed)
    if isinstance(seed, (numbers.Integral, np.integer)) and not isinstance(seed, bool) and seed >= 0:
        return np.random.default_rng(int(seed))
    raise ValueError(f"seed: expected a non-negative int, a numpy SeedSequence or Generator, or None, got {seed!r}")


def sample_query_states(plant, feature_map, n: int, seed=None, max_condition: float = 20.0,
                        max_candidates: int = 10_000) -> np.ndarray:
    """Draws n query states, each accepted only while the features stay well conditioned.

    Args:
        plant: where candidates come from (``plant.sample_states``) and what is valid.
        feature_map: phi, to build the partial feature matrix.
        n: how many states.
        seed: int, SeedSequence, Generator or None.
        max_condition: the largest condition number the partial feature matrix may reach.
        max_candidates: give up after this many candidates (raises ValueError).

    Returns:
        states: (n, state_dim).
    """
    n = as_count("n", n)
    max_condition = as_positive("max_condition", max_condition)
    if max_condition < 1:
        raise ValueError(f"max_condition: expected a condition number >= 1, got {max_condition}")
    rng = make_rng(seed)
    accepted: list[np.ndarray] = []
    rows: list[np.ndarray] = []
    for _ in range(max_candidates):
        candidate = plant.sample_states(rng, 1)
        if not plant.is_valid_state(candidate)[0]:
            continue
        phi = feature_map(candidate)[0]
        if condition_number(np.array(rows + [phi])) <= max_condition:
            accepted.append(candidate[0])
            rows.append(phi)
            if len(accepted) == n:
                return np.array(accepted)
    raise ValueError(f"max_condition: found only {len(accepted)} of {n} states with a condition number under "
                     f"{max_condition} in {max_candidates} candidates; raise max_condition or lower n")


class SeedSchedule:
    """Reproducible, distinct seeds for every phase and episode of a protocol.

    The seed of (phase, episode[, participant]) is derived from one study seed with numpy's
    SeedSequence spawn keys, so the schedule is reproducible, streams never overlap, and adding
    an episode does not shift the others.

    Args:
        study_seed: the one number a protocol file stores.
    """

    def __init__(self, study_seed: int = 0):
        if isinstance(study_seed, bool) or not isinstance(study_seed, (numbers.Integral, np.integer)) or study_seed < 0:
            raise ValueError(f"study_seed: expected a non-negative int, got {study_seed!r}")
        self.study_seed = int(study_seed)

    def __repr__(self) -> str:
        return f"SeedSchedule({self.study_seed})"

    def seed(self, phase: int, episode: int, participant: int | None = None) -> np.random.SeedSequence:
        """The seed for one episode: phase and episode are 0-based indices of the protocol."""
        phase = as_count("phase", phase, minimum=0)
        episode = as_count("episode", episode, minimum=0)
        key = (phase, episode) if participant is None else (phase, episode, as_count("participant", participant, minimum=0))
        return np.random.SeedSequence(self.study_seed, spawn_key=key)
