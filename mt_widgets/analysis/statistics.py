"""Statistics of a teaching study, as the paper reports them and a little more.

The comparisons (``Change``, ``PAPER_CHANGES``) are the study's analysis plan
(``mt_widgets.study.analysis_plan``), fixed with the protocol, and so are the groups: the
first of a protocol's groups is compared against the second (the paper's target against
control), whatever their names; ``analyse_protocol`` takes groups, changes, sidedness, alpha,
the primary test and the baseline check from a protocol and its plan. Everything starts from the tidy
episode rows (``mt_widgets.study.tidy``: one row per completed episode with ``participant``,
``group``, ``phase``, ``episode`` and ``teaching_error``, the paper's E_l2). From them:

- ``phase_summary``: per group, phase and episode, the mean, SD, median and a t confidence
  interval of the teaching error (the paper's Fig. 3a).
- ``participant_changes``: each participant's change of error between two episodes (later minus
  earlier, negative = better), for the paper's three comparisons ``PAPER_CHANGES``:
  P1 -> P3E8 (effect of guidance), P1 -> P4 (retention), P2 -> P5 (transfer).
- ``change_summary``: per change and group, the mean and SD of the change and the percentage
  change of the group's mean error (how the paper prints its results).
- ``between_group_tests``: Student's t-test (equal variances: the test the paper's power
  analysis assumes), Welch's t-test and the Mann-Whitney U test of target against control, one-
  or two-sided, and Hedges' g with a confidence interval. Which of the three is primary is the
  analysis plan's choice (``AnalysisPlan.test``), recorded in ``StudyStatistics.test``.
- ``within_group_tests``: paired t-test and Wilcoxon signed-rank test of each group's change.
- ``posthoc_baseline``: the paper's P1 vs P2 check (no difference between skills or groups at
  baseline).
- ``analyse_changes``: all of the above in one ``StudyStatistics`` with a tidy ``results_table``
  and a plain-language ``summary``.

All distributions come from ``scipy.stats``; nothing here writes one by hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from mt_widgets.core.validation import as_fraction
from mt_widgets.study.analysis_plan import ALTERNATIVES, PAPER_CHANGES, TESTS, Change  # noqa: F401  (re-exported)

#: The paper's two groups, in the order tables and figures use when no protocol says otherwise.
GROUPS = ("target", "control")
#: The paper's post-hoc baseline check: P1 against P2.
PAPER_BASELINE = (("P1", 1), ("P2", 1))


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

#: The tests' names as a reader sees them.
TEST_NAMES = {"student": "Student's t-test", "welch": "Welch's t-test", "mannwhitney": "Mann-Whitney U"}


_REQUIRED = ("participant", "group", "phase", "episode", "teaching_error")


def check_alternative(alternative: str) -> str:
    if alternative not in ALTERNATIVES:
        raise ValueError(f"alternative: expected one of {ALTERNATIVES}, got {alternative!r}")
    return alternative


def episodes_frame(episodes, groups=None) -> pd.DataFrame:
    """The episode rows as a DataFrame with the columns the statistics need, checked.

    Args:
        episodes: a DataFrame or a list of dicts (``read_study``'s first return value), one row
            per completed episode.
        groups: the protocol's groups (rows of other groups are refused), or None.

    Returns:
        A copy with ``episode`` as int, ``teaching_error`` as float and ``participant``,
        ``group``, ``phase`` as str, sorted by participant, phase order (sessions in order) and
        episode, with a ``position`` column: the phase's rank in the protocol.
    """
    frame = episodes.copy() if isinstance(episodes, pd.DataFrame) else pd.DataFrame(list(episodes))
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
    frame["teaching_error"] = frame["teaching_error"].astype(float)
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
    for (group, phase, episode), part in frame.groupby(["group", "phase", "episode"], sort=False):
        errors = part["teaching_error"].to_numpy()
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


def _episode_errors(frame: pd.DataFrame, phase: str, episode: int | None) -> pd.Series:
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
    return rows.groupby("participant")["teaching_error"].last()


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
        before = _episode_errors(frame, *change.before)
        after = _episode_errors(frame, *change.after)
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


# -- effect sizes ---------------------------------------------------------------------------------

def hedges_correction(df: float) -> float:
    """The exact small-sample factor J(df) = Gamma(df/2) / (sqrt(df/2) Gamma((df-1)/2)), g = J d."""
    if not df > 1:
        raise ValueError(f"df: expected degrees of freedom > 1, got {df!r}")
    return float(np.exp(special.gammaln(df / 2) - special.gammaln((df - 1) / 2)) / np.sqrt(df / 2))


@dataclass(frozen=True)
class EffectSize:
    """Hedges' g of x against y with its confidence interval.

    Attributes:
        d: Cohen's d, (mean x - mean y) / pooled SD.
        g: Hedges' g, d times the exact small-sample correction.
        ci_low, ci_high: the confidence interval of g.
        confidence: its coverage.
        method: "noncentral-t" (exact inversion) or "normal" (Hedges & Olkin's large-sample SE).
    """

    d: float
    g: float
    ci_low: float
    ci_high: float
    confidence: float
    method: str


def hedges_g(x, y, confidence: float = 0.95, method: str = "noncentral-t") -> EffectSize:
    """Hedges' g of two independent samples with a confidence interval.

    Args:
        x: (n1,) the first sample (the target group in this package).
        y: (n2,) the second sample.
        confidence: coverage of the interval.
        method: "noncentral-t": the exact interval of Steiger & Fouladi (1997), found by
            inverting the noncentral t distribution of t = d sqrt(n1 n2 / (n1 + n2)) and then
            scaled to g; "normal": g +- z SE with SE^2 = (n1 + n2) / (n1 n2) + g^2 / (2 (n1 + n2))
            (Hedges & Olkin 1985).

    Returns:
        An ``EffectSize``.
    """
    confidence = as_fraction("confidence", confidence)
    if method not in ("noncentral-t", "normal"):
        raise ValueError(f"method: expected 'noncentral-t' or 'normal', got {method!r}")
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    n1, n2 = x.size, y.size
    if n1 < 2 or n2 < 2:
        raise ValueError(f"x, y: expected at least 2 observations in each sample, got {n1} and {n2}")
    df = n1 + n2 - 2
    pooled = np.sqrt(((n1 - 1) * x.var(ddof=1) + (n2 - 1) * y.var(ddof=1)) / df)
    if pooled == 0:
        raise ValueError("x, y: expected some spread within the samples, got a pooled SD of 0")
    d = float((x.mean() - y.mean()) / pooled)
    correction = hedges_correction(df)
    g = correction * d
    tail = (1 - confidence) / 2
    if method == "normal":
        se = np.sqrt((n1 + n2) / (n1 * n2) + g**2 / (2 * (n1 + n2)))
        z = stats.norm.ppf(1 - tail)
        return EffectSize(d, g, float(g - z * se), float(g + z * se), confidence, method)
    scale = np.sqrt(n1 * n2 / (n1 + n2))
    t_observed = d * scale

    def noncentrality_for(probability: float) -> float:
        # The noncentrality at which the observed t sits at this upper-tail probability; the
        # cdf falls monotonically in the noncentrality, so a wide bracket always holds the root.
        def gap(nc):
            return stats.nct.sf(t_observed, df, nc) - probability
        width = 10.0 + 2 * abs(t_observed)
        return optimize.brentq(gap, t_observed - width, t_observed + width, xtol=1e-10)

    low = noncentrality_for(tail) / scale * correction
    high = noncentrality_for(1 - tail) / scale * correction
    return EffectSize(d, g, float(low), float(high), confidence, method)


# -- tests ----------------------------------------------------------------------------------------

def _pair(changes_table: pd.DataFrame, groups) -> tuple[str, str]:
    """The two groups compared: the first against the second."""
    groups = study_groups(changes_table, groups)
    if len(groups) == 1:
        groups = groups + tuple(g for g in GROUPS if g not in groups)[:1]
    if len(groups) != 2:
        raise ValueError(f"groups: expected the two groups of a between-subjects comparison, got {list(groups)}")
    return groups[0], groups[1]


def between_group_tests(changes_table: pd.DataFrame, alternative: str = "less",
                        confidence: float = 0.95, groups=None) -> pd.DataFrame:
    """The first group against the second on each change (target against control in the paper):
    Student's t, Welch's t, Mann-Whitney U and Hedges' g.

    Args:
        changes_table: ``participant_changes`` output.
        alternative: "two-sided", or one-sided "less" (the target group's change is lower, i.e.
            it improved more: the paper's hypotheses) or "greater", always target minus control.
        confidence: coverage of the interval of g.
        groups: the protocol's two groups, the first compared against the second (None: the
            paper's target and control).

    Returns:
        One row per change with ``n_<first group>``, ``n_<second group>`` (``n_target``,
        ``n_control`` in the paper), ``student_t``, ``student_df``,
        ``student_p``, ``welch_t``, ``welch_df``,
        ``welch_p``, ``mannwhitney_u``, ``mannwhitney_p``, ``hedges_g``, ``g_ci_low``,
        ``g_ci_high`` and ``alternative``. Tests that cannot run (fewer than 2 per group) are NaN.
    """
    alternative = check_alternative(alternative)
    first, second = _pair(changes_table, groups)
    rows = []
    for name, part in changes_table.groupby("change", sort=False):
        target = part.loc[part["group"] == first, "delta"].to_numpy()
        control = part.loc[part["group"] == second, "delta"].to_numpy()
        row = {"change": name, "label": part["label"].iloc[0], f"n_{first}": target.size, f"n_{second}": control.size,
               "student_t": np.nan, "student_df": np.nan, "student_p": np.nan, "welch_t": np.nan,
               "welch_df": np.nan, "welch_p": np.nan, "mannwhitney_u": np.nan,
               "mannwhitney_p": np.nan, "hedges_g": np.nan, "g_ci_low": np.nan, "g_ci_high": np.nan,
               "alternative": alternative}
        if target.size >= 2 and control.size >= 2:
            student = stats.ttest_ind(target, control, equal_var=True, alternative=alternative)
            welch = stats.ttest_ind(target, control, equal_var=False, alternative=alternative)
            mwu = stats.mannwhitneyu(target, control, alternative=alternative)
            row.update(student_t=float(student.statistic), student_df=float(student.df),
                       student_p=float(student.pvalue),
                       welch_t=float(welch.statistic), welch_df=float(welch.df), welch_p=float(welch.pvalue),
                       mannwhitney_u=float(mwu.statistic), mannwhitney_p=float(mwu.pvalue))
            if np.var(target) + np.var(control) > 0:
                effect = hedges_g(target, control, confidence)
                row.update(hedges_g=effect.g, g_ci_low=effect.ci_low, g_ci_high=effect.ci_high)
        rows.append(row)
    return pd.DataFrame(rows)


def within_group_tests(changes_table: pd.DataFrame, alternative: str = "less") -> pd.DataFrame:
    """Did each group's error change? Paired t-test and Wilcoxon signed-rank test of after vs before.

    Args:
        changes_table: ``participant_changes`` output.
        alternative: "two-sided", "less" (error fell) or "greater", for after minus before.

    Returns:
        One row per (change, group) with ``n``, ``paired_t``, ``paired_p``, ``wilcoxon_w`` and
        ``wilcoxon_p`` (NaN where a test cannot run: fewer than 2 pairs, or all changes zero).
    """
    alternative = check_alternative(alternative)
    rows = []
    for (name, group), part in changes_table.groupby(["change", "group"], sort=False):
        before, after = part["before"].to_numpy(), part["after"].to_numpy()
        row = {"change": name, "label": part["label"].iloc[0], "group": group, "n": before.size,
               "paired_t": np.nan, "paired_p": np.nan, "wilcoxon_w": np.nan, "wilcoxon_p": np.nan,
               "alternative": alternative}
        if before.size >= 2 and np.any(after != before):
            paired = stats.ttest_rel(after, before, alternative=alternative)
            signed = stats.wilcoxon(after, before, alternative=alternative)
            row.update(paired_t=float(paired.statistic), paired_p=float(paired.pvalue),
                       wilcoxon_w=float(signed.statistic), wilcoxon_p=float(signed.pvalue))
        rows.append(row)
    return pd.DataFrame(rows)


def posthoc_baseline(episodes, first=("P1", 1), second=("P2", 1), groups=None) -> pd.DataFrame:
    """The paper's post-hoc check that the baselines do not differ (its P1 vs P2 p-values).

    The paper reports two p-values ("no significant difference ... between the two skills and
    two groups") without naming the tests; this gives both readings, two-sided:
    the two skills compared within each group (paired t-test, P1 against P2) and the two
    groups compared at each baseline episode (Welch's t-test).

    Args:
        episodes: episode rows.
        first, second: (phase, episode) of the two baseline episodes.
        groups: the protocol's two groups (None: the paper's).

    Returns:
        One row per test with ``comparison``, ``test``, ``n``, ``statistic``, ``p``; no rows
        when the protocol has no such phases.
    """
    frame = episodes_frame(episodes, groups)
    pair = _pair(frame, groups)
    if not {first[0], second[0]} <= set(frame["phase"]):
        return pd.DataFrame(columns=["comparison", "test", "n", "statistic", "p"])
    a = _episode_errors(frame, *first)
    b = _episode_errors(frame, *second)
    groups = frame.groupby("participant")["group"].first()
    label_a, label_b = f"{first[0]}", f"{second[0]}"
    rows = []
    for group in pair:
        members = [p for p in a.index.intersection(b.index) if groups[p] == group]
        row = {"comparison": f"{label_a} vs {label_b}, {group} group", "test": "paired t", "n": len(members),
               "statistic": np.nan, "p": np.nan}
        if len(members) >= 2 and np.any(a[members].to_numpy() != b[members].to_numpy()):
            result = stats.ttest_rel(a[members], b[members])
            row.update(statistic=float(result.statistic), p=float(result.pvalue))
        rows.append(row)
    for label, errors in ((label_a, a), (label_b, b)):
        target = errors[[groups[p] == pair[0] for p in errors.index]].to_numpy()
        control = errors[[groups[p] == pair[1] for p in errors.index]].to_numpy()
        row = {"comparison": f"{pair[0]} vs {pair[1]} at {label}", "test": "Welch t", "n": target.size + control.size,
               "statistic": np.nan, "p": np.nan}
        if target.size >= 2 and control.size >= 2:
            result = stats.ttest_ind(target, control, equal_var=False)
            row.update(statistic=float(result.statistic), p=float(result.pvalue))
        rows.append(row)
    return pd.DataFrame(rows)


# -- everything at once ---------------------------------------------------------------------------

@dataclass(frozen=True)
class StudyStatistics:
    """The statistics of one study (see ``analyse_changes``)."""

    phases: pd.DataFrame
    changes: pd.DataFrame
    change_summary: pd.DataFrame
    between: pd.DataFrame
    within: pd.DataFrame
    baseline: pd.DataFrame
    alternative: str
    alpha: float
    test: str = "student"
    #: The groups, the first compared against the second.
    groups: tuple = GROUPS
    #: {group: what it received, in words} ("guided in P3"), from the protocol.
    group_notes: dict = None
    #: The ``Change``s compared (their meanings go into the summary).
    compared: tuple = PAPER_CHANGES
    #: The baseline episodes checked (``posthoc_baseline``), or None.
    baseline_episodes: tuple | None = PAPER_BASELINE

    @property
    def primary_p(self) -> pd.Series:
        """The primary test's p-value of each change (``test``: the analysis plan's choice)."""
        return self.between[f"{self.test}_p"]

    def results_table(self) -> pd.DataFrame:
        """One tidy row per (change, group): descriptives, the within-group tests, and the
        between-group tests and effect size of that change (repeated on both groups' rows)."""
        table = self.change_summary.merge(
            self.within[["change", "group", "paired_t", "paired_p", "wilcoxon_w", "wilcoxon_p"]],
            on=["change", "group"], how="left")
        table = table.merge(self.between.drop(columns=["label"]), on="change", how="left")
        table["primary_test"] = self.test
        return table

    def summary(self) -> str:
        """A short plain-language account of the results."""
        return plain_language_summary(self)


def analyse_changes(episodes, changes=PAPER_CHANGES, alternative: str = "less", alpha: float = 0.05,
                    confidence: float = 0.95, test: str = "student", groups=None,
                    baseline=PAPER_BASELINE, group_notes=None) -> StudyStatistics:
    """Every table of the paper's analysis from the episode rows.

    Args:
        episodes: episode rows (a DataFrame or ``read_study``'s list of dicts).
        changes: the comparisons (default the paper's three).
        alternative: sidedness of the between- and within-group tests (see
            ``between_group_tests``); the paper's hypotheses are one-sided, "less".
        alpha: the significance level the summary uses.
        confidence: coverage of every confidence interval.
        test: the primary between-group test the summary's verdict uses ("student", "welch" or
            "mannwhitney"; a study's analysis plan names it); all three are computed. The
            default is Student's t, as ``AnalysisPlan``'s: the test the paper's sample size was
            planned for (G*Power, d = 0.9, alpha 0.05, power 0.8, one-tailed: 16 per group) is
            the one its primary verdict should use; Welch's t, robust to unequal variances,
            is reported beside it.
        groups: the protocol's two groups, the first compared against the second (None: the
            paper's target and control).
        baseline: the two (phase, episode) baselines ``posthoc_baseline`` compares, or None.
        group_notes: {group: what it received, in words} for the summary.
    """
    check_alternative(alternative)
    if test not in TESTS:
        raise ValueError(f"test: expected one of {list(TESTS)}, got {test!r}")
    alpha = as_fraction("alpha", alpha)
    frame = episodes_frame(episodes, groups)
    groups = _pair(frame, groups)
    changes = tuple(changes)
    table = participant_changes(frame, changes)
    return StudyStatistics(
        phases=phase_summary(frame, confidence, groups),
        changes=table,
        change_summary=change_summary(table, confidence, groups),
        between=between_group_tests(table, alternative, confidence, groups),
        within=within_group_tests(table, alternative),
        baseline=(posthoc_baseline(frame, *baseline, groups=groups) if baseline is not None
                  else pd.DataFrame(columns=["comparison", "test", "n", "statistic", "p"])),
        alternative=alternative,
        alpha=alpha,
        test=test,
        groups=groups,
        group_notes=dict(group_notes or {}),
        compared=changes,
        baseline_episodes=None if baseline is None else tuple(tuple(b) for b in baseline),
    )


def protocol_group_notes(protocol) -> dict:
    """{group: "guided in P3"} from a protocol's phases (every session's); "never guided" else."""
    notes = {}
    for group in protocol.groups:
        guided = [phase.id for phase in protocol.all_phases if group in phase.guidance]
        notes[group] = ("guided in " + ", ".join(guided)) if guided else "never guided"
    return notes


def analyse_protocol(episodes, protocol, confidence: float = 0.95, **overrides) -> StudyStatistics:
    """``analyse_changes`` as a protocol and its analysis plan say: its groups (the first against
    the second), changes, sidedness, alpha, primary test and baseline check.

    Args:
        episodes: episode rows of a study of ``protocol``.
        protocol: the ``Protocol`` (``StudyFolder(folder).protocol``).
        confidence: coverage of every confidence interval.
        **overrides: any of changes, alternative, alpha, test, baseline to use instead of the plan's.
    """
    plan = protocol.analysis
    known = {"changes", "alternative", "alpha", "test", "baseline"}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise TypeError(f"analyse_protocol: unexpected arguments {unknown}; expected some of {sorted(known)}")
    values = {"changes": plan.changes, "alternative": plan.alternative, "alpha": plan.alpha, "test": plan.test,
              "baseline": plan.baseline}
    values.update({k: v for k, v in overrides.items() if v is not None})
    return analyse_changes(episodes, confidence=confidence, groups=protocol.groups[:2],
                           group_notes=protocol_group_notes(protocol), **values)


def _p(p: float) -> str:
    if np.isnan(p):
        return "p not computable"
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}"


def plain_language_summary(results: StudyStatistics) -> str:
    """A few sentences a reader without statistics can follow, one paragraph per change."""
    first, second = results.groups[:2]
    notes = results.group_notes or {}
    sided = {"two-sided": "two-sided", "less": f"one-sided ({first} improves more)",
             "greater": f"one-sided ({second} improves more)"}[results.alternative]
    n = results.changes.groupby("group")["participant"].nunique()

    def note(group):
        return f" ({notes[group]})" if notes.get(group) else ""
    lines = [f"{n.get(first, 0)} participants in the {first} group{note(first)} and "
             f"{n.get(second, 0)} in the {second} group{note(second)}. Teaching error is the distance between the "
             f"learnt and the true skill parameters; a negative change means better teaching. "
             f"Tests are {sided}, at alpha = {results.alpha}."]
    summary = results.change_summary.set_index(["change", "group"])
    meaning = {c.name: c.meaning for c in results.compared}
    for _, row in results.between.iterrows():
        parts = []
        for group in (first, second):
            if (row["change"], group) in summary.index:
                s = summary.loc[(row["change"], group)]
                parts.append(f"the {group} group changed by {s['mean']:+.2f} (SD {s['sd']:.2f}, "
                             f"{s['percent_change']:+.0f}% of its error before)")
        primary = row[f"{results.test}_p"]
        significant = primary < results.alpha
        verdict = ("a difference unlikely to be chance" if significant else
                   "a difference that could well be chance")
        what = meaning.get(row["change"], "")
        lines.append(f"{row['label']}{' (' + what + ')' if what else ''}: " + "; ".join(parts) +
                     f". {TEST_NAMES[results.test]} (primary): {_p(primary)}; "
                     + ", ".join(f"{TEST_NAMES[t]}: {_p(row[f'{t}_p'])}" for t in TESTS if t != results.test)
                     + f"; Hedges' g = {row['hedges_g']:.2f} [{row['g_ci_low']:.2f}, {row['g_ci_high']:.2f}]: "
                     f"{verdict}.")
    baseline = results.baseline.dropna(subset=["p"])
    if not baseline.empty:
        smallest = baseline["p"].min()
        pair = " vs ".join(phase for phase, _ in results.baseline_episodes) if results.baseline_episodes else ""
        lines.append(f"Baseline check ({pair}): " + ("no test finds a difference between skills or groups"
                     if smallest >= results.alpha else "some baseline test finds a difference")
                     + f" (smallest {_p(smallest)}).")
    return "\n".join(lines)
