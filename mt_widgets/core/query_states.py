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


_CHUNK = 8


def _condition_numbers(rows: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Condition number of ``rows`` with each candidate row appended: (k, S), (m, S) -> (m,)."""
    if len(rows) == 0:  # one row: a single singular value, its norm
        return np.where(np.linalg.norm(candidates, axis=1) > 0, 1.0, np.inf)
    stacks = np.concatenate([np.broadcast_to(rows, (len(candidates),) + rows.shape), candidates[:, None, :]], axis=1)
    singular = np.linalg.svd(stacks, compute_uv=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(singular[:, -1] > 0, singular[:, 0] / singular[:, -1], np.inf)


def sample_query_states(plant, feature_map, n: int, seed=None, max_condition: float = 20.0,
                        max_candidates: int = 20_000, block: int = 32, patience: int = 256) -> np.ndarray:
    """Draws n query states, each accepted only while the features stay well conditioned.

    Candidates are drawn in blocks of ``block`` and tested together (one batched SVD), then
    accepted in the order drawn, so the result depends only on the seed. When ``patience``
    candidates in a row fail to extend the current set (the states so far leave no
    well-conditioned way to continue, which happens for a few seeds in a thousand), the
    most recently accepted state is dropped and the search goes on. When the set gets stuck
    again before growing past the size it was stuck at, one more state is dropped each time
    (the culprit can be an early state: the UR5 conveyor's seed 3820321158 stayed stuck at 3 or 4
    of 5 states through 80,000 candidates when only the last one was ever dropped), so a
    protocol's seed does not dead-end.

    Args:
        plant: where candidates come from (``plant.sample_states``) and what is valid.
        feature_map: phi, to build the partial feature matrix.
        n: how many states.
        seed: int, SeedSequence, Generator or None.
        max_condition: the largest condition number the partial feature matrix may reach.
        max_candidates: give up after this many candidates (raises ValueError).
        block: candidates drawn and tested at once.
        patience: consecutive failures before backtracking one state.

    Returns:
        states: (n, state_dim).
    """
    n = as_count("n", n)
    max_condition = as_positive("max_condition", max_condition)
    if max_condition < 1:
        raise ValueError(f"max_condition: expected a condition number >= 1, got {max_condition}")
    block = as_count("block", block)
    patience = as_count("patience", patience)
    rng = make_rng(seed)
    accepted = np.empty((0, plant.state_dim))
    rows = np.empty((0, feature_map.dim))
    drawn = failures = valid = 0
    # Backtracking: how many states the next drop removes, and the size the set was stuck at.
    drops, stuck_at = 0, n + 1

    def backtrack():
        nonlocal accepted, rows, failures, drops, stuck_at
        drops = drops + 1 if len(accepted) <= stuck_at else 1
        stuck_at = len(accepted)
        keep = max(len(accepted) - drops, 0)
        accepted, rows, failures = accepted[:keep], rows[:keep], 0

    while drawn < max_candidates:
        candidates = plant.sample_states(rng, block)
        drawn += block
        candidates = candidates[plant.is_valid_state(candidates)]
        valid += len(candidates)
        features = feature_map(candidates)
        start = 0
        while start < len(candidates):
            # Test a few candidates at a time: usually one of the first few passes, and an SVD
            # of candidates that are never looked at is wasted.
            chunk = features[start:start + _CHUNK]
            passing = np.flatnonzero(_condition_numbers(rows, chunk) <= max_condition)
            if passing.size == 0:
                failures += len(chunk)
                start += len(chunk)
                continue
            chosen = start + passing[0]
            failures += passing[0]
            if failures >= patience and len(accepted) > 0:
                # Backtrack instead of accepting: the current set has proved hard to extend.
                backtrack()
                start = chosen
                continue
            accepted = np.vstack([accepted, candidates[chosen]])
            rows = np.vstack([rows, features[chosen]])
            failures = 0
            if len(accepted) == n:
                return accepted
            start = chosen + 1
        if failures >= patience and len(accepted) > 0:
            backtrack()
    if valid == 0:
        # Not a matter of the threshold: the plant offers no state at all (an arm whose teaching
        # box is out of its reach, below its table or inside itself).
        raise ValueError(f"plant: expected valid candidate states (is_valid_state), got none of {drawn} sampled: "
                         f"is the workspace within the robot's reach and safe to teach in? ({plant!r})")
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
        if participant is None:
            key = (phase, episode)
        else:
            key = (phase, episode, as_count("participant", participant, minimum=0))
        return np.random.SeedSequence(self.study_seed, spawn_key=key)
