"""The paper's reported results, and what the teacher model is fitted to.

The paper prints, per experiment, each group's mean and SD change of teaching error and the
target group's percentage reductions; it prints no baselines, but they follow from the two
(``implied_baselines``). ``paper_targets`` is what ``mt_widgets.in_silico.fitting`` aims at and
``mt_widgets.analysis.paper_comparison`` compares a study with.
"""

from __future__ import annotations

import json

import numpy as np

from mt_widgets.study.analysis_plan import PAPER_CHANGES

#: The paper's rows whose names differ from ``PAPER_CHANGES``' and whose sign is flipped: the
#: physical experiment prints its P1 -> P4 row as an improvement (positive = better).
_PRINTED_AS_IMPROVEMENT = {"P1_to_P4_improvement": "P1_to_P4"}


def paper_changes(reference: dict | None = None, experiment: str = "simulation") -> dict:
    """The paper's changes of one experiment, every row as later minus earlier (negative = better).

    Args:
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical".

    Returns:
        {change name (as in ``PAPER_CHANGES``): {group: {"mean", "sd"}}}; a row printed as an
        improvement has its mean negated and keeps its SD.
    """
    reference = paper_results() if reference is None else reference
    if experiment not in reference:
        raise ValueError(f"experiment: expected one of {sorted(k for k in reference if 'changes' in reference[k])}, "
                         f"got {experiment!r}")
    out = {}
    for name, groups in reference[experiment]["changes"].items():
        flip = name in _PRINTED_AS_IMPROVEMENT
        out[_PRINTED_AS_IMPROVEMENT.get(name, name)] = {
            group: {"mean": -values["mean"] if flip else values["mean"], "sd": values["sd"]}
            for group, values in groups.items() if isinstance(values, dict)}
    return out



#: The paper's printed summary figures (its results section and Fig. 3): per
#: experiment the changes (mean and SD per group) and the target group's percentage reductions.
PAPER_RESULTS = {
    "simulation": {
        "p1_vs_p2_posthoc_p": [0.0989, 0.1148],
        "changes": {
            "P1_to_P3E8": {"target": {"mean": -2.03, "sd": 0.82}, "control": {"mean": 0.025, "sd": 0.53}},
            "P1_to_P4": {"target": {"mean": -1.51, "sd": 0.84}, "control": {"mean": -0.22, "sd": 0.56}},
            "P2_to_P5": {"target": {"mean": -1.47, "sd": 0.80}, "control": {"mean": -0.06, "sd": 0.64}},
        },
        "percent_reduction_target": {"during_P3": 69.40, "P4_vs_P1": 51.47, "P5_vs_P2": 50.03},
    },
    "physical": {
        "changes": {
            "P1_to_P3E8": {"target": {"mean": -5.30, "sd": 1.79}, "control": {"mean": -1.54, "sd": 3.44}},
            # Printed as an improvement (positive = better), unlike the other rows.
            "P1_to_P4_improvement": {"target": {"mean": 4.55, "sd": 1.80}, "control": {"mean": -0.35, "sd": 2.46}},
            "P2_to_P5": {"target": {"mean": -6.32, "sd": 2.92}, "control": {"mean": 2.21, "sd": 5.54}},
        },
        "percent_reduction_target": {"P3E8_vs_P1": 88.26, "P5_vs_P2": 77.34},
    },
}

def paper_results() -> dict:
    """The paper's reported results of both experiments (a fresh copy: changes, % reductions)."""
    return json.loads(json.dumps(PAPER_RESULTS))


#: Which change each printed percentage reduction of the target group belongs to.
_PERCENT_OF_CHANGE = {"during_P3": "P1_to_P3E8", "P3E8_vs_P1": "P1_to_P3E8", "P4_vs_P1": "P1_to_P4",
                      "P5_vs_P2": "P2_to_P5"}


def _baselines_by_change(reference: dict, experiment: str) -> dict:
    """{change: the target group's baseline error implied by its change and % reduction}; a change
    without a printed percentage borrows the value of another with the same baseline episode."""
    changes = paper_changes(reference, experiment)
    implied = {}
    for key, percent in reference[experiment]["percent_reduction_target"].items():
        name = _PERCENT_OF_CHANGE.get(key)
        if name in changes:
            implied[name] = -changes[name]["target"]["mean"] / (percent / 100)
    before = {c.name: c.before for c in PAPER_CHANGES}
    for name in changes:
        if name not in implied:
            same = [implied[other] for other in implied if before.get(other) == before.get(name)]
            if same:
                implied[name] = float(np.mean(same))
    return implied


def implied_baselines(reference: dict | None = None, experiment: str = "simulation") -> dict:
    """The paper's baseline errors, by phase, implied by its changes and percentage reductions.

    The paper prints no baseline means, but every target-group change with a percentage gives
    one: baseline = -change / percent (simulation P2: 1.47 / 50.03 % = 2.94). Where two
    percentages give the same baseline (simulation P1, from P3E8 and from P4) their mean is
    used.

    Args:
        reference: the paper's results (default the shipped ones).
        experiment: "simulation" or "physical".

    Returns:
        {phase: baseline teaching error}, e.g. {"P1": 2.93, "P2": 2.94}.
    """
    reference = paper_results() if reference is None else reference
    by_change = _baselines_by_change(reference, experiment)
    phases: dict[str, list] = {}
    for change in PAPER_CHANGES:
        if change.name in by_change:
            phases.setdefault(change.before[0], []).append(by_change[change.name])
    return {phase: float(np.mean(values)) for phase, values in phases.items()}


def paper_targets(reference: dict | None = None, experiment: str = "simulation") -> dict:
    """What the fit aims at: the paper's change means and SDs per group (every row as later minus
    earlier) and the target group's baseline error implied by its percentage reductions
    (change / percent), per change."""
    reference = paper_results() if reference is None else reference
    return {"changes": paper_changes(reference, experiment), "baselines": _baselines_by_change(reference, experiment)}
