"""The tables of a teaching study: its episode rows, summarised by phase and by change.

Everything starts from the tidy episode rows (``mt_widgets.study.tidy``: one row per
completed episode with ``participant``, ``group``, ``phase``, ``episode``, ``theta_error`` (the
paper's E_l2, where the learner has a Theta) and ``policy_risk`` (every learner)). The error the
analysis compares is ``error_measure``'s: theta_error where every episode has one, else the policy
risk. From them:

- ``episodes_frame``: the rows checked and in protocol order.
- ``phase_summary``: per group, phase and episode, the mean, SD, median and a t confidence
  interval of the teaching error (the paper's Fig. 3a).
- ``participant_changes``: each participant's change of error between two episodes (later minus
  earlier, negative = better), for the paper's three comparisons ``PAPER_CHANGES``:
  P1 -> P3E8 (effect of guidance), P1 -> P4 (retention), P2 -> P5 (transfer).
- ``change_summary``: per change and group, the mean and SD of the change and the percentage
  change of the group's mean error (how the paper prints its results).

Descriptive only: the tests are in ``mt_widgets.analysis.statistics``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from mt_widgets.core.validation import as_fraction
from mt_widgets.study.analysis_plan import PAPER_CHANGES

#: The paper's two groups, in the order tables and figures use when no protocol says otherwise.
GROUPS = ("target", "control")


def study_groups(frame: pd.DataFrame, groups=None) -> tuple[str, ...]:
    """The groups in the order the analysis compares them (the first against the second).

    Args:
        frame: episode rows.
        groups: the protocol's groups (None: the paper's ``GROUPS`` first, then any others in
            order of name).

    Raises:
        ValueError: the rows hold a group that ``groups`` does not name.
    """
    present = list(dict.fromkeys(frame["group"].astype(str)))
    if groups is not None:
        groups = tuple(str(g) for g in groups)
        unknown = sorted(set(present) - set(groups))
        if unknown:
            raise ValueError(f"episodes: expected groups {groups}, got also {unknown}")
        return groups
    others = tuple(sorted(set(present) - set(GROUPS)))
    if not others:
        return GROUPS
    return tuple(g for g in GROUPS if g in present) + others


_REQUIRED = ("participant", "group", "phase", "episode")

#: The two errors an episode reports (``TeachingEpisode.theta_error`` and ``policy_risk``).
ERROR_MEASURES = ("theta_error", "policy_risk")

#: How figures and tables name each error.
ERROR_LABELS = {"theta_error": "teaching error ||Theta_hat - Theta||", "policy_risk": "policy risk"}


def error_measure(frame: pd.DataFrame) -> str:
    """The error a study's analysis compares: ``theta_error`` (the paper's E_l2) where every episode
    has one (a learner with a Theta), else ``policy_risk``."""
    for measure in ERROR_MEASURES:
        if measure in frame.columns and frame[measure].notna().all():
            return measure
    raise ValueError(f"episodes: expected a theta_error or a policy_risk in every row, got columns "
                     f"{list(frame.columns)}")


def _split_old_error(frame: pd.DataFrame) -> None:
    """Rows written when both errors were one ``teaching_error`` (older tidy files and frames):
    Theta's error where a row has a theta_hat (or no theta_hat column: the paper's E), else the
    policy risk."""
    if "teaching_error" not in frame.columns or any(m in frame.columns for m in ERROR_MEASURES):
        return
    has_theta = (frame["theta_hat"].notna() & (frame["theta_hat"].astype(str) != "")) if "theta_hat" in frame.columns \
        else pd.Series(True, index=frame.index)
    frame["theta_error"] = frame["teaching_error"].where(has_theta)
    frame["policy_risk"] = frame["teaching_error"].where(~has_theta)
    del frame["teaching_error"]


def episodes_frame(episodes, groups=None) -> pd.DataFrame:
    """The episode rows as a DataFrame with the columns the statistics need, checked.

    Args:
        episodes: a DataFrame or a list of dicts (``read_study``'s first return value), one row
            per completed episode.
        groups: the protocol's groups (rows of other groups are refused), or None.

    Returns:
        A copy with ``episode`` as int, ``theta_error`` and ``policy_risk`` as float (NaN where
        an episode has none; a frame with the one ``teaching_error`` of older files is split) and ``participant``,
        ``group``, ``phase`` as str, sorted by participant, phase order (sessions in order) and
        episode, with a ``position`` column: the phase's rank in the protocol.
    """
    frame = episodes.copy() if isinstance(episodes, pd.DataFrame) else pd.DataFrame(list(episodes))
    _split_old_error(frame)
    missing = [column for column in _REQUIRED if column not in frame.columns]
    if missing:
        raise ValueError(f"episodes: expected columns {list(_REQUIRED)}, missing {missing} "
                         f"(got {list(frame.columns)})")
    if frame.empty:
        raise ValueError("episodes: expected at least one episode row, got none")
    frame["participant"] = frame["participant"].astype(str)
    frame["group"] = frame["group"].astype(str)
    frame["phase"] = frame["phase"].astype(str)
    frame["episode"] = frame["episode"].astype(int)
    for measure in ERROR_MEASURES:
        frame[measure] = frame[measure].astype(float) if measure in frame.columns else np.nan
    error_measure(frame)   # one of them in every row, or refused by name
    study_groups(frame, groups)
    order = _phase_order(frame)
    frame["position"] = [order[phase] for phase in frame["phase"]]
    return frame.sort_values(["participant", "position", "episode"], kind="stable").reset_index(drop=True)


def confidence_interval(values, confidence: float = 0.95) -> tuple[float, float]:
    """The t confidence interval of a mean: mean +- t_{(1+c)/2, n-1} * SD / sqrt(n).

    Args:
        values: (n,) observations.
        confidence: the coverage, e.g. 0.95.

    Returns:
        (low, high); (nan, nan) with fewer than two observations.
    """
    confidence = as_fraction("confidence", confidence)
    values = np.asarray(values, dtype=float)
    if values.size < 2:
        return (float("nan"), float("nan"))
    low, high = stats.t.interval(confidence, values.size - 1, loc=values.mean(), scale=stats.sem(values))
    return float(low), float(high)


def phase_summary(episodes, confidence: float = 0.95, groups=None) -> pd.DataFrame:
    """Teaching error per group, phase and episode (the data of the paper's Fig. 3a).

    Args:
        episodes: episode rows (see ``episodes_frame``).
        confidence: coverage of the confidence interval of the mean.
        groups: the protocol's groups, in order (None: see ``study_groups``).

    Returns:
        One row per (group, phase, episode) in protocol order, with ``n``, ``mean``, ``sd``
        (sample SD, ddof=1), ``sem``, ``median``, ``ci_low``, ``ci_high`` and ``label``
        ("P3E2").
    """
    frame = episodes_frame(episodes, groups)
    groups = study_groups(frame, groups)
    rows = []
    order = _phase_order(frame)
    measure = error_measure(frame)
    for (group, phase, episode), part in frame.groupby(["group", "phase", "episode"], sort=False):
        errors = part[measure].to_numpy()
        low, high = confidence_interval(errors, confidence)
        rows.append({"group": group, "phase": phase, "episode": int(episode), "label": f"{phase}E{episode}",
                     "n": errors.size, "mean": errors.mean(), "sd": _sd(errors), "sem": _sem(errors),
                     "median": float(np.median(errors)), "ci_low": low, "ci_high": high,
                     "_order": (order[phase], int(episode), groups.index(group))})
    table = pd.DataFrame(rows).sort_values("_order").drop(columns="_order").reset_index(drop=True)
    return table


def _phase_order(frame: pd.DataFrame) -> dict[str, int]:
    """{phase: rank in the protocol}: by session (in the order the rows meet them), then phase_index."""
    if "phase_index" in frame.columns:
        sessions = ({s: i for i, s in enumerate(dict.fromkeys(frame["session"]))} if "session" in frame.columns
                    else None)
        keys = {}
        for row in frame[["phase", "phase_index"] + (["session"] if sessions else [])].itertuples(index=False):
            key = (sessions[row.session] if sessions else 0, int(row.phase_index))
            keys[row.phase] = min(keys.get(row.phase, key), key)
        return {phase: rank for rank, phase in enumerate(sorted(keys, key=keys.get))}
    return {phase: i for i, phase in enumerate(sorted(frame["phase"].unique()))}


def _sd(values) -> float:
    return float(np.std(values, ddof=1)) if len(values) > 1 else float("nan")


def _sem(values) -> float:
    return float(stats.sem(values)) if len(values) > 1 else float("nan")


def episode_errors(frame: pd.DataFrame, phase: str, episode: int | None) -> pd.Series:
    """{participant: teaching error} at one (phase, episode) of checked rows (episode None: each
    participant's last episode of the phase)."""
    rows = frame[frame["phase"] == phase]
    if rows.empty:
        raise ValueError(f"changes: expected episodes of phase {phase!r}, got phases {sorted(frame['phase'].unique())}")
    if episode is None:
        rows = rows[rows["episode"] == rows.groupby("participant")["episode"].transform("max")]
    else:
        rows = rows[rows["episode"] == episode]
        if rows.empty:
            raise ValueError(f"changes: expected episode {episode} of phase {phase!r}, got episodes "
                             f"{sorted(frame.loc[frame['phase'] == phase, 'episode'].unique())}")
    # A repeated episode (a participant redid one) counts once: its last completed attempt.
    return rows.groupby("participant")[error_measure(frame)].last()


def participant_changes(episodes, changes=PAPER_CHANGES) -> pd.DataFrame:
    """Each participant's change of teaching error for each comparison.

    Args:
        episodes: episode rows (see ``episodes_frame``).
        changes: the ``Change`` comparisons (default: the paper's three).

    Returns:
        One row per (change, participant) who completed both episodes, with ``change``,
        ``label``, ``participant``, ``group``, ``before``, ``after`` and ``delta`` = after - before.
    """
    frame = episodes_frame(episodes)
    groups = frame.groupby("participant")["group"].first()
    rows = []
    for change in changes:
        before = episode_errors(frame, *change.before)
        after = episode_errors(frame, *change.after)
        both = before.index.intersection(after.index)
        for participant in both:
            rows.append({"change": change.name, "label": change.label, "participant": participant,
                         "group": groups[participant], "before": float(before[participant]),
                         "after": float(after[participant]),
                         "delta": float(after[participant] - before[participant])})
    if not rows:
        raise ValueError("episodes: no participant completed both episodes of any requested change")
    return pd.DataFrame(rows)


def change_summary(changes_table: pd.DataFrame, confidence: float = 0.95, groups=None) -> pd.DataFrame:
    """Mean, SD and percentage change per comparison and group (how the paper prints them).

    Args:
        changes_table: ``participant_changes`` output.
        confidence: coverage of the confidence interval of the mean change.

    Returns:
        One row per (change, group) with ``n``, ``mean``, ``sd``, ``median``, ``ci_low``,
        ``ci_high`` of the change, ``mean_before``, ``mean_after`` and ``percent_change`` =
        100 * mean change / mean error before (the paper's "51.47% lower" is -51.47 here).
    """
    rows = []
    for (name, group), part in changes_table.groupby(["change", "group"], sort=False):
        delta = part["delta"].to_numpy()
        low, high = confidence_interval(delta, confidence)
        mean_before = float(part["before"].mean())
        rows.append({"change": name, "label": part["label"].iloc[0], "group": group, "n": delta.size,
                     "mean": float(delta.mean()), "sd": _sd(delta), "median": float(np.median(delta)),
                     "ci_low": low, "ci_high": high, "mean_before": mean_before,
                     "mean_after": float(part["after"].mean()),
                     "percent_change": 100.0 * float(delta.mean()) / mean_before if mean_before else float("nan")})
    table = pd.DataFrame(rows)
    order = {name: i for i, name in enumerate(dict.fromkeys(changes_table["change"]))}
    groups = study_groups(changes_table, groups)
    table["_order"] = [(order[c], groups.index(g)) for c, g in zip(table["change"], table["group"])]
    return table.sort_values("_order").drop(columns="_order").reset_index(drop=True)
