"""The tests of a teaching study, as the paper reports them and a little more.

The comparisons (``Change``, ``PAPER_CHANGES``) are the study's analysis plan
(``mt_widgets.study.analysis_plan``), fixed with the protocol, and so are the groups: the
first of a protocol's groups is compared against the second (the paper's target against
control), whatever their names; ``analyse_protocol`` takes groups, changes, sidedness, alpha,
the primary test and the baseline check from a protocol and its plan. The tests run on the
tables of ``mt_widgets.analysis.tables`` (episode rows, each participant's changes):

- ``between_group_tests``: Student's t-test (equal variances: the test the paper's power
  analysis assumes), Welch's t-test and the Mann-Whitney U test of target against control, one-
  or two-sided, and Hedges' g with a confidence interval (``mt_widgets.analysis.effect_size``).
  Which of the three is primary is the analysis plan's choice (``AnalysisPlan.test``),
  recorded in ``StudyStatistics.test``.
- ``within_group_tests``: paired t-test and Wilcoxon signed-rank test of each group's change.
- ``posthoc_baseline``: the paper's P1 vs P2 check (no difference between skills or groups at
  baseline).
- ``analyse_changes``: all of the above and the tables in one ``StudyStatistics`` with a tidy
  ``results_table`` and a plain-language ``summary`` (``mt_widgets.analysis.summary``).

All distributions come from ``scipy.stats``; nothing here writes one by hand. The tables',
effect sizes' and summary's names are importable from here too, as they always were.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from mt_widgets.core.learner_teaching import LEARNERS
from mt_widgets.core.validation import as_fraction
from mt_widgets.study.analysis_plan import ALTERNATIVES, PAPER_CHANGES, TESTS, Change

from .effect_size import EffectSize, hedges_correction, hedges_g
from .summary import TEST_NAMES, plain_language_summary
from .tables import (
    GROUPS,
    change_summary,
    confidence_interval,
    episode_errors,
    episodes_frame,
    participant_changes,
    phase_summary,
    study_groups,
)

__all__ = [
    "ALTERNATIVES", "GROUPS", "PAPER_BASELINE", "PAPER_CHANGES", "TESTS", "TEST_NAMES", "Change", "EffectSize",
    "StudyStatistics", "analyse_changes", "analyse_protocol", "between_group_tests", "change_summary",
    "check_alternative", "confidence_interval", "episodes_frame", "hedges_correction", "hedges_g",
    "participant_changes", "phase_summary", "plain_language_summary", "posthoc_baseline",
    "protocol_group_notes", "study_groups", "within_group_tests",
]

#: The paper's post-hoc baseline check: P1 against P2.
PAPER_BASELINE = (("P1", 1), ("P2", 1))


def check_alternative(alternative: str) -> str:
    """``alternative`` if it is a sidedness the tests know (``ALTERNATIVES``), else ValueError."""
    if alternative not in ALTERNATIVES:
        raise ValueError(f"alternative: expected one of {ALTERNATIVES}, got {alternative!r}")
    return alternative


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
    a = episode_errors(frame, *first)
    b = episode_errors(frame, *second)
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
    #: The robot learner the participants taught (``mt_widgets.core.LEARNERS``): what the teaching
    #: error measures depends on it (ridge: the distance of the parameters; else the policy risk).
    learner: str = "ridge"

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
                    baseline=PAPER_BASELINE, group_notes=None, learner: str = "ridge") -> StudyStatistics:
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
        learner: the robot learner taught (a name of ``mt_widgets.core.LEARNERS``), for the summary.
    """
    check_alternative(alternative)
    if learner not in LEARNERS:
        raise ValueError(f"learner: expected one of the available learners ({', '.join(LEARNERS)}), got {learner!r}")
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
        learner=learner,
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
    values = {"changes": plan.changes if overrides.get("changes") is not None else plan.compared(protocol.name),
              "alternative": plan.alternative, "alpha": plan.alpha, "test": plan.test,
              "baseline": plan.baseline}
    values.update({k: v for k, v in overrides.items() if v is not None})
    return analyse_changes(episodes, confidence=confidence, groups=protocol.groups[:2],
                           group_notes=protocol_group_notes(protocol), learner=protocol.learner, **values)
