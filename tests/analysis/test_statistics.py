"""The study statistics, checked against values computed independently here."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mt_widgets.analysis.power import analytic_power, sample_size_per_group
from mt_widgets.analysis.statistics import (
    PAPER_CHANGES,
    analyse_changes,
    between_group_tests,
    change_summary,
    confidence_interval,
    hedges_correction,
    hedges_g,
    participant_changes,
    phase_summary,
    posthoc_baseline,
    within_group_tests,
)

PHASES = [("P1", 1), ("P2", 1), ("P3", 8), ("P4", 1), ("P5", 1)]


def make_episodes(errors_by_participant, groups):
    """Tidy episode rows: errors_by_participant[p] is a list of 12 errors in protocol order."""
    rows = []
    for p, (errors, group) in enumerate(zip(errors_by_participant, groups)):
        k = 0
        for phase_index, (phase, n) in enumerate(PHASES):
            for episode in range(1, n + 1):
                rows.append({"study": "t", "participant": f"p{p:02d}", "group": group, "phase": phase,
                             "phase_index": phase_index, "episode": episode, "teaching_error": errors[k]})
                k += 1
    return rows


@pytest.fixture
def study():
    rng = np.random.default_rng(7)
    groups = ["target"] * 6 + ["control"] * 5
    errors = []
    for group in groups:
        base = rng.uniform(2.0, 4.0, size=12)
        if group == "target":
            base[2:] *= np.linspace(0.8, 0.3, 10)
        errors.append(base)
    return make_episodes(errors, groups), np.array(errors), groups


def test_phase_summary_matches_numpy_per_episode(study):
    rows, errors, groups = study
    table = phase_summary(rows)
    assert len(table) == 12 * 2
    target = errors[[g == "target" for g in groups]]
    row = table[(table.group == "target") & (table.phase == "P3") & (table.episode == 4)].iloc[0]
    column = target[:, 2 + 3]
    assert row["mean"] == pytest.approx(column.mean())
    assert row["sd"] == pytest.approx(np.std(column, ddof=1))
    assert row["median"] == pytest.approx(np.median(column))
    half = stats.t.ppf(0.975, column.size - 1) * np.std(column, ddof=1) / math.sqrt(column.size)
    assert (row["ci_low"], row["ci_high"]) == pytest.approx((column.mean() - half, column.mean() + half))
    # Protocol order: P1E1 first, P5E1 last, target before control within an episode.
    assert list(table["label"][:4]) == ["P1E1", "P1E1", "P2E1", "P2E1"]
    assert table["label"].iloc[-1] == "P5E1"


def test_confidence_interval_textbook_example():
    # Mean 5, SD 2 (values 3, 5, 7 have SD exactly 2), n = 3: t_{0.975, 2} = 4.303.
    low, high = confidence_interval([3.0, 5.0, 7.0])
    assert (low, high) == pytest.approx((5 - 4.302653 * 2 / math.sqrt(3), 5 + 4.302653 * 2 / math.sqrt(3)), abs=1e-5)


def test_changes_are_later_minus_earlier_and_percent_is_of_the_mean_before(study):
    rows, errors, groups = study
    changes = participant_changes(rows)
    p3e8 = changes[(changes.change == "P1_to_P3E8") & (changes.participant == "p03")].iloc[0]
    assert p3e8["delta"] == pytest.approx(errors[3, 9] - errors[3, 0])
    summary = change_summary(changes)
    row = summary[(summary.change == "P2_to_P5") & (summary.group == "control")].iloc[0]
    control = errors[[g == "control" for g in groups]]
    delta = control[:, 11] - control[:, 1]
    assert row["mean"] == pytest.approx(delta.mean())
    assert row["sd"] == pytest.approx(np.std(delta, ddof=1))
    assert row["percent_change"] == pytest.approx(100 * delta.mean() / control[:, 1].mean())
    assert list(summary["change"]) == [c.name for c in PAPER_CHANGES for _ in (0, 1)]


def test_last_episode_of_a_phase_can_be_asked_for(study):
    from mt_widgets.analysis.statistics import Change
    rows, errors, _ = study
    last = participant_changes(rows, [Change("x", ("P1", 1), ("P3", None), "x", "")])
    assert last["delta"].to_numpy() == pytest.approx(errors[:, 9] - errors[:, 0])


def test_between_group_tests_agree_with_scipy_on_the_same_numbers(study):
    rows, errors, groups = study
    changes = participant_changes(rows)
    tests = between_group_tests(changes, alternative="less")
    target = errors[[g == "target" for g in groups]]
    control = errors[[g == "control" for g in groups]]
    dt, dc = target[:, 10] - target[:, 0], control[:, 10] - control[:, 0]
    row = tests[tests.change == "P1_to_P4"].iloc[0]
    # Welch's t by its textbook formula, the p-value from the t distribution with Welch's df.
    v1, v2 = dt.var(ddof=1) / dt.size, dc.var(ddof=1) / dc.size
    t = (dt.mean() - dc.mean()) / math.sqrt(v1 + v2)
    df = (v1 + v2) ** 2 / (v1**2 / (dt.size - 1) + v2**2 / (dc.size - 1))
    assert row["welch_t"] == pytest.approx(t)
    assert row["welch_df"] == pytest.approx(df)
    assert row["welch_p"] == pytest.approx(stats.t.cdf(t, df))
    # U counts the pairs in which the target's change exceeds the control's.
    u = sum((a > b) + 0.5 * (a == b) for a in dt for b in dc)
    assert row["mannwhitney_u"] == pytest.approx(u)
    two = between_group_tests(changes, alternative="two-sided")
    two_sided = two[two.change == "P1_to_P4"].iloc[0]["welch_p"]
    assert two_sided == pytest.approx(2 * min(row["welch_p"], 1 - row["welch_p"]))


def test_mann_whitney_textbook_example():
    # Exact test: 3 against 3 fully separated samples; P(U = 0) = 1 / C(6, 3) = 0.05.
    changes = pd.DataFrame({"change": "c", "label": "c", "participant": list("abcdef"),
                            "group": ["target"] * 3 + ["control"] * 3,
                            "before": 0.0, "after": 0.0, "delta": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]})
    row = between_group_tests(changes, alternative="less").iloc[0]
    assert row["mannwhitney_u"] == 0
    assert row["mannwhitney_p"] == pytest.approx(1 / 20)


def test_hedges_g_textbook_values():
    x = np.array([5.0, 6.0, 7.0, 8.0, 9.0])
    y = np.array([3.0, 4.0, 5.0, 6.0, 7.0])
    # Both SDs are sqrt(2.5); d = 2 / sqrt(2.5) = 1.2649; J(8) = 1 - 3 / (4 * 8 - 1) approximately.
    effect = hedges_g(x, y)
    assert effect.d == pytest.approx(2 / math.sqrt(2.5))
    assert hedges_correction(8) == pytest.approx(1 - 3 / 31, abs=2e-3)
    assert effect.g == pytest.approx(effect.d * hedges_correction(8))
    normal = hedges_g(x, y, method="normal")
    se = math.sqrt(10 / 25 + normal.g**2 / 20)
    assert (normal.ci_low, normal.ci_high) == pytest.approx((normal.g - 1.959964 * se, normal.g + 1.959964 * se))


def test_hedges_g_exact_interval_puts_the_observed_t_at_the_tails():
    rng = np.random.default_rng(3)
    x, y = rng.normal(1, 1, 12), rng.normal(0, 1, 10)
    effect = hedges_g(x, y, confidence=0.9)
    scale = math.sqrt(12 * 10 / 22)
    t = effect.d * scale
    j = hedges_correction(20)
    assert stats.nct.sf(t, 20, effect.ci_low / j * scale) == pytest.approx(0.05, abs=1e-6)
    assert stats.nct.sf(t, 20, effect.ci_high / j * scale) == pytest.approx(0.95, abs=1e-6)
    assert effect.ci_low < effect.g < effect.ci_high


def test_hedges_g_exact_and_normal_intervals_agree_for_large_samples():
    rng = np.random.default_rng(4)
    x, y = rng.normal(0.5, 1, 400), rng.normal(0, 1, 400)
    exact, normal = hedges_g(x, y), hedges_g(x, y, method="normal")
    assert exact.ci_low == pytest.approx(normal.ci_low, abs=0.01)
    assert exact.ci_high == pytest.approx(normal.ci_high, abs=0.01)


def test_within_group_tests_are_paired(study):
    rows, errors, groups = study
    tests = within_group_tests(participant_changes(rows), alternative="two-sided")
    target = errors[[g == "target" for g in groups]]
    diff = target[:, 9] - target[:, 0]
    t = diff.mean() / (np.std(diff, ddof=1) / math.sqrt(diff.size))
    row = tests[(tests.change == "P1_to_P3E8") & (tests.group == "target")].iloc[0]
    assert row["paired_t"] == pytest.approx(t)
    assert row["paired_p"] == pytest.approx(2 * stats.t.sf(abs(t), diff.size - 1))
    assert row["wilcoxon_p"] == pytest.approx(stats.wilcoxon(diff).pvalue)


def test_posthoc_baseline_compares_skills_within_groups_and_groups_at_each_baseline(study):
    rows, errors, groups = study
    table = posthoc_baseline(rows)
    control = errors[[g == "control" for g in groups]]
    row = table[table.comparison == "P1 vs P2, control group"].iloc[0]
    assert row["p"] == pytest.approx(stats.ttest_rel(control[:, 0], control[:, 1]).pvalue)
    assert len(table) == 4


def test_results_table_and_summary_hold_every_change(study):
    rows, _, _ = study
    results = analyse_changes(rows)
    table = results.results_table()
    assert len(table) == 6
    assert {"mean", "sd", "percent_change", "welch_p", "mannwhitney_p", "hedges_g", "paired_p"} <= set(table.columns)
    text = results.summary()
    for change in PAPER_CHANGES:
        assert change.label in text


def test_bad_input_names_the_argument():
    with pytest.raises(ValueError, match="episodes: expected columns"):
        phase_summary([{"participant": "a"}])
    with pytest.raises(ValueError, match="alternative"):
        analyse_changes(make_episodes([np.ones(12)] * 2, ["target", "control"]), alternative="one")


def test_the_papers_sample_size_is_16_per_group():
    assert sample_size_per_group(0.9, alpha=0.05, power=0.8, alternative="greater") == 16
    assert analytic_power(16, 0.9) >= 0.8 > analytic_power(15, 0.9)


def test_analytic_power_matches_a_monte_carlo_t_test():
    rng = np.random.default_rng(0)
    x = rng.normal(0.9, 1, size=(20_000, 16))
    y = rng.normal(0.0, 1, size=(20_000, 16))
    p = stats.ttest_ind(x, y, axis=1, alternative="greater").pvalue
    assert np.mean(p < 0.05) == pytest.approx(analytic_power(16, 0.9), abs=0.01)


def test_two_sided_power_needs_more_participants():
    assert sample_size_per_group(0.9, alternative="two-sided") == 21
    assert analytic_power(10, 0.0, alternative="two-sided") == pytest.approx(0.05)
