"""Fitting the teacher model to the paper: the parameters whose in-silico study lands nearest
the paper's reported changes and baselines (how ``PAPER_FIT`` and ``PAPER_FIT_UARM`` were made).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import minimize

from .engine import simulate_changes
from .paper_results import paper_targets
from .plan import episode_plan, experiment_of, paper_fit, query_states_for, resolve_protocol, teacher_seed
from .teachers import TeacherParameters, TeacherPopulation, logit

#: The fields ``fit_to_paper`` can adjust, with the transform that keeps each in its range.
TRANSFORMS = {
    "magnitude": "log", "magnitude_spread": "log", "direction_noise": "log", "magnitude_noise": "log",
    "exploration": "log", "learning_rate": "logit", "learning_spread": "log", "reproduction_learning": "logit",
    "retention": "logit", "transfer": "logit", "line_as_point": "logit",
}

#: The fields fitted by default. The drawing slips (``direction_noise``, ``magnitude_noise``)
#: are held at the start's values: fitted freely they shrink to nothing (the paper's small SDs
#: leave no room for them), yet a hand never draws the same arrow twice, so they stay at a
#: modest assumed size (0.05 rad, about 3 degrees, and 5 % in length).
FITTED_FIELDS = ("magnitude", "magnitude_spread", "exploration", "learning_rate", "learning_spread",
                 "reproduction_learning", "retention", "transfer", "line_as_point")


def _to_free(parameters: TeacherParameters, names) -> np.ndarray:
    values = []
    for name in names:
        value = getattr(parameters, name)
        values.append(np.log(max(value, 1e-6)) if TRANSFORMS[name] == "log" else logit(value))
    return np.array(values)


def _from_free(free: np.ndarray, base: TeacherParameters, names) -> TeacherParameters:
    changes = {}
    for value, name in zip(free, names):
        changes[name] = float(np.exp(value)) if TRANSFORMS[name] == "log" else float(1 / (1 + np.exp(-value)))
    # Rates must stay below 1 and shares at most 1: the logistic keeps them there except at
    # the edges of floating point.
    for name in ("learning_rate", "reproduction_learning"):
        if name in changes:
            changes[name] = min(changes[name], 0.999)
    return replace(base, **changes)


def fit_loss(deltas: dict, targets: dict) -> float:
    """Squared gaps of the simulated change means and SDs from the paper's, in units of the
    paper's SDs, plus the gaps of the target group's baseline error (in units of its SD)."""
    loss = 0.0
    for name, groups in targets["changes"].items():
        for group, values in groups.items():
            delta = deltas[name][group].ravel()
            loss += ((delta.mean() - values["mean"]) / values["sd"]) ** 2
            loss += ((delta.std(ddof=1) - values["sd"]) / values["sd"]) ** 2
        before = deltas[name]["before"][:, : deltas[name]["target"].shape[1]].ravel()
        loss += ((before.mean() - targets["baselines"][name]) / groups["target"]["sd"]) ** 2
    return float(loss)


def fit_to_paper(n_per_group: int = 1000, seed: int = 0, start: TeacherParameters | None = None, protocol=None,
                 max_evaluations: int = 1500, reference: dict | None = None, fields=FITTED_FIELDS,
                 experiment: str | None = None):
    """Fits the teacher model so an in-silico run of the protocol lands near the paper's changes.

    The loss (``fit_loss``) compares, for each of the paper's three changes and both groups,
    the mean and SD of the simulated changes with the paper's, and the target group's baseline
    error with the one the paper's percentages imply. The same simulated people (common random
    numbers) are used at every evaluation, on the protocol's own query states, so the loss is a
    smooth function of the parameters and Nelder-Mead can minimise it.

    Args:
        n_per_group: simulated participants per group (large: the population's moments).
        seed: seed of the simulated people.
        start: the starting parameters (default: the protocol's current fit, ``paper_fit``).
        protocol: the protocol (default the paper's simulation protocol; "paper-uarm" for the
            physical experiment).
        max_evaluations: the optimiser's budget.
        reference: the paper's results (default the shipped ones).
        fields: the parameters to fit (the others stay at ``start``'s values).
        experiment: the paper's experiment to aim at, "simulation" or "physical" (default: the
            protocol's, "physical" for a uArm protocol).

    Returns:
        (fitted ``TeacherParameters``, final loss).
    """
    protocol = resolve_protocol(protocol)
    start = paper_fit(protocol) if start is None else start
    targets = paper_targets(reference, experiment_of(protocol) if experiment is None else experiment)
    plan = episode_plan(protocol)
    states = [query_states_for(protocol, step)[None] for step in plan]
    n = 2 * n_per_group
    people = TeacherPopulation.draw(start, [teacher_seed(seed, p) for p in range(n)], len(plan),
                                    max(step["demonstrations"] for step in plan))

    unknown = [name for name in fields if name not in TRANSFORMS]
    if unknown:
        raise ValueError(f"fields: expected names from {sorted(TRANSFORMS)}, got also {unknown}")

    def loss(free):
        parameters = _from_free(free, start, fields)
        deltas = simulate_changes(protocol, people.with_parameters(parameters), 1, n_per_group, states)
        return fit_loss(deltas, targets)

    result = minimize(loss, _to_free(start, fields), method="Nelder-Mead",
                      options={"maxfev": max_evaluations, "xatol": 1e-3, "fatol": 1e-4, "adaptive": True})
    return _from_free(result.x, start, fields), float(result.fun)
