"""How many participants a study needs: analytic power and power by simulation.

Analytic: the two-sample t-test with equal groups of n has, under an effect of size d, a
statistic distributed as the noncentral t with df = 2n - 2 and noncentrality d sqrt(n / 2)
(scipy.stats.nct). With the paper's settings (d = 0.9, alpha = 0.05, power 0.8, one-tailed,
as in G*Power 3.1) the smallest n is 16 per group, 32 in all.

By simulation: many in-silico studies of synthetic teachers (``mt_widgets.in_silico``)
are run through the protocol and analysed with the test the real study will use; the share of
studies in which the test rejects is the power. Unlike the analytic figure it needs no
assumed effect size: the effect is whatever the teacher models produce.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from mt_widgets.core.validation import as_bool, as_count, as_fraction
from mt_widgets.in_silico.engine import run_many_studies
from mt_widgets.in_silico.plan import resolve_protocol

from .effect_size import hedges_correction
from .statistics import check_alternative


def analytic_power(n_per_group: int, effect_size: float, alpha: float = 0.05,
                   alternative: str = "greater") -> float:
    """Power of the two-sample t-test with equal variances and n per group.

    Args:
        n_per_group: participants in each group (>= 2).
        effect_size: Cohen's d, the true difference of means in SDs (sign matters for
            one-sided tests: "greater" expects d > 0, "less" d < 0).
        alpha: the significance level.
        alternative: "two-sided", "greater" or "less".

    Returns:
        The probability that the test rejects, from the noncentral t distribution.
    """
    n_per_group = as_count("n_per_group", n_per_group, minimum=2)
    alpha = as_fraction("alpha", alpha)
    alternative = check_alternative(alternative)
    df = 2 * n_per_group - 2
    noncentrality = float(effect_size) * np.sqrt(n_per_group / 2)
    if alternative == "greater":
        return float(stats.nct.sf(stats.t.ppf(1 - alpha, df), df, noncentrality))
    if alternative == "less":
        return float(stats.nct.cdf(stats.t.ppf(alpha, df), df, noncentrality))
    critical = stats.t.ppf(1 - alpha / 2, df)
    return float(stats.nct.sf(critical, df, noncentrality) + stats.nct.cdf(-critical, df, noncentrality))


def sample_size_per_group(effect_size: float, alpha: float = 0.05, power: float = 0.8,
                          alternative: str = "greater", max_n: int = 100_000) -> int:
    """The smallest n per group whose analytic power reaches ``power``.

    Args:
        effect_size: Cohen's d (see ``analytic_power``).
        alpha: the significance level.
        power: the wanted power.
        alternative: "two-sided", "greater" or "less".
        max_n: give up above this (raises ValueError).

    Returns:
        n per group (the paper: 16 for d = 0.9, alpha = 0.05, power = 0.8, one-tailed).
    """
    power = as_fraction("power", power)
    if effect_size == 0:
        raise ValueError("effect_size: expected a non-zero effect, got 0 (no sample size detects it)")
    # Power rises monotonically with n, so a doubling search brackets the answer and a
    # bisection finds the smallest n.
    low, high = 2, 2
    while analytic_power(high, effect_size, alpha, alternative) < power:
        low, high = high, high * 2
        if high > max_n:
            raise ValueError(f"effect_size: expected an effect detectable with at most max_n={max_n} per group "
                             f"at power {power}, got {effect_size}")
    while low < high:
        middle = (low + high) // 2
        if analytic_power(middle, effect_size, alpha, alternative) >= power:
            high = middle
        else:
            low = middle + 1
    return int(high)


@dataclass(frozen=True)
class SimulatedPower:
    """Power of each test on each change, estimated from simulated studies.

    Attributes:
        power: {change: {test: share of studies that rejected}}.
        n_studies: how many studies were simulated.
        n_per_group: participants per group in each.
        alpha: the level.
        alternative: the sidedness, target minus control.
        p_values: {change: {test: (n_studies,) p-values}}, for histograms.
        mean_effect: {change: mean Hedges' g across studies}: the effect the teachers produce.
    """

    power: dict
    n_studies: int
    n_per_group: int
    alpha: float
    alternative: str
    p_values: dict
    mean_effect: dict

    def standard_error(self, change: str, test: str = "welch") -> float:
        """The Monte-Carlo standard error of one power estimate, sqrt(p (1 - p) / n_studies)."""
        p = self.power[change][test]
        return float(np.sqrt(p * (1 - p) / self.n_studies))

    def table(self):
        """One row per (change, test) with power, its standard error and the mean effect."""
        rows = [{"change": change, "test": test, "power": value, "mc_se": self.standard_error(change, test),
                 "mean_hedges_g": self.mean_effect[change], "n_per_group": self.n_per_group,
                 "n_studies": self.n_studies, "alpha": self.alpha}
                for change, tests in self.power.items() for test, value in tests.items()]
        return pd.DataFrame(rows)


def _hedges_g_columns(target: np.ndarray, control: np.ndarray) -> np.ndarray:
    """Hedges' g of each row of two (studies, n) arrays, vectorised over studies."""
    n1, n2 = target.shape[1], control.shape[1]
    pooled = np.sqrt(((n1 - 1) * target.var(axis=1, ddof=1) + (n2 - 1) * control.var(axis=1, ddof=1))
                     / (n1 + n2 - 2))
    return hedges_correction(n1 + n2 - 2) * (target.mean(axis=1) - control.mean(axis=1)) / pooled


def simulated_power(n_per_group: int = 16, n_studies: int = 1000, alpha: float = 0.05,
                    alternative: str = "less", seed: int = 0, parameters=None, changes=None,
                    progress: bool | None = None, protocol=None, share_states: bool = False,
                    workers: int | None = None, forgetting=None, delays: dict | None = None) -> SimulatedPower:
    """Power by simulation: ``n_studies`` in-silico studies of synthetic teachers, each analysed.

    Every study draws its own participants and its own query states (a study seed per study),
    so the estimate covers both sources of chance a real study meets. Reproductions are not
    rolled out: the outcome, the teaching error, needs only the learnt parameters.

    Args:
        n_per_group: participants per group in each study.
        n_studies: simulated studies.
        alpha: significance level.
        alternative: sidedness for target minus control ("less": the target group improves more).
        seed: the root seed; the same seed gives the same estimate.
        parameters: ``TeacherParameters`` (default: the ones fitted to the paper).
        changes: ``Change`` comparisons (default: the protocol's analysis plan's; the paper's three
            for the paper's protocols).
        progress: show a progress bar (default: only for long runs).
        protocol: the ``Protocol`` (default the paper's).
        share_states: give every study the protocol's own query states (faster; the estimate
            then leaves out the chance of the query states).
        workers: processes drawing query states (default: up to 2 for 100 studies or more).
        forgetting: how teachers forget between the protocol's sessions
            (``mt_widgets.in_silico.Forgetting``; None: they do not).
        delays: {session id: seconds} before later sessions (default: each window's earliest).

    Returns:
        A ``SimulatedPower``: the power of Student's t-test ("student"), Welch's t-test ("welch")
        and the Mann-Whitney U test ("mannwhitney") on each change.
    """
    alpha = as_fraction("alpha", alpha)
    alternative = check_alternative(alternative)
    share_states = as_bool("share_states", share_states)
    progress = as_bool("progress", progress, allow_none=True)
    protocol = resolve_protocol(protocol)
    changes = protocol.analysis.compared(protocol.name) if changes is None else tuple(changes)
    deltas = run_many_studies(n_studies, n_per_group, seed=seed, parameters=parameters, changes=changes,
                              progress=progress, protocol=protocol, share_states=share_states,
                              workers=workers, forgetting=forgetting, delays=delays)
    first, second = protocol.groups[:2]
    power, p_values, effect = {}, {}, {}
    for change in changes:
        target, control = deltas[change.name][first], deltas[change.name][second]
        student = stats.ttest_ind(target, control, axis=1, equal_var=True, alternative=alternative).pvalue
        welch = stats.ttest_ind(target, control, axis=1, equal_var=False, alternative=alternative).pvalue
        mwu = stats.mannwhitneyu(target, control, axis=1, alternative=alternative).pvalue
        p_values[change.name] = {"student": student, "welch": welch, "mannwhitney": mwu}
        power[change.name] = {name: float(np.mean(values < alpha)) for name, values in p_values[change.name].items()}
        effect[change.name] = float(np.mean(_hedges_g_columns(target, control)))
    return SimulatedPower(power, n_studies, n_per_group, alpha, alternative, p_values, effect)
