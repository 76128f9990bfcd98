"""How near a study lands to the paper: its changes and baselines beside the paper's, row by row."""

from __future__ import annotations

import pandas as pd

from mt_widgets.in_silico.engine import InSilicoStudy
from mt_widgets.in_silico.paper_results import implied_baselines, paper_changes
from mt_widgets.in_silico.plan import experiment_of

from .tables import change_summary, participant_changes


def compare_with_paper(result, reference: dict | None = None, experiment: str | None = None) -> pd.DataFrame:
    """Row-by-row comparison of an in-silico study's changes with the paper's.

    Args:
        result: an ``InSilicoStudy``, or episode rows.
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical" (default: the study's protocol's, else
            "simulation"). The physical experiment's P1 -> P4 row, printed as an improvement,
            is compared as later minus earlier like the others (``paper_changes``).

    Returns:
        One row per (change, group): the paper's mean and SD, the in-silico mean and SD, and
        how near: ``mean_gap`` (in-silico minus paper) and ``mean_gap_in_sd`` (the gap in units
        of the paper's SD), ``sd_ratio`` (in-silico / paper).
    """
    if experiment is None:
        experiment = experiment_of(result.protocol) if isinstance(result, InSilicoStudy) else "simulation"
    episodes = result.episodes if isinstance(result, InSilicoStudy) else result
    summary = change_summary(participant_changes(episodes)).set_index(["change", "group"])
    rows = []
    for name, groups in paper_changes(reference, experiment).items():
        for group, values in groups.items():
            if (name, group) not in summary.index:
                continue
            s = summary.loc[(name, group)]
            rows.append({"change": name, "group": group, "paper_mean": values["mean"], "paper_sd": values["sd"],
                         "in_silico_mean": float(s["mean"]), "in_silico_sd": float(s["sd"]),
                         "mean_gap": float(s["mean"]) - values["mean"],
                         "mean_gap_in_sd": (float(s["mean"]) - values["mean"]) / values["sd"],
                         "sd_ratio": float(s["sd"]) / values["sd"], "n": int(s["n"])})
    return pd.DataFrame(rows)


def baseline_comparison(result, reference: dict | None = None, experiment: str | None = None) -> pd.DataFrame:
    """The baselines (P1 and P2 teaching errors) of an in-silico study against the paper's.

    The paper prints no baseline means; they follow from each target-group change and its
    percentage reduction (baseline = -change / percent), e.g. P2 in simulation 1.47 / 50.03 %
    = 2.94. Groups are pooled in silico (the randomisation makes them alike at baseline).

    Args:
        result: an ``InSilicoStudy``, or episode rows.
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical" (default: as ``compare_with_paper``).

    Returns:
        One row per baseline phase: ``phase``, ``paper_mean`` (implied), ``in_silico_mean``,
        ``in_silico_sd``, ``n``.
    """
    if experiment is None:
        experiment = experiment_of(result.protocol) if isinstance(result, InSilicoStudy) else "simulation"
    episodes = result.episodes if isinstance(result, InSilicoStudy) else result
    frame = pd.DataFrame(episodes)
    rows = []
    for phase, paper in implied_baselines(reference, experiment).items():
        # The paper's E_l2: Theta's error (its learner, ridge, has a Theta).
        errors = frame[(frame.phase == phase) & (frame.episode == 1)].theta_error.to_numpy(dtype=float)
        rows.append({"phase": phase, "paper_mean": paper, "in_silico_mean": float(errors.mean()),
                     "in_silico_sd": float(errors.std(ddof=1)) if errors.size > 1 else float("nan"),
                     "n": int(errors.size)})
    return pd.DataFrame(rows)
