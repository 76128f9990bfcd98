"""The plain-language summary of a study's statistics: a few sentences, one per change.

``plain_language_summary`` (what ``StudyStatistics.summary()`` returns) says, for a reader
without statistics, how much each group's teaching error changed, what the primary test and
the others found, the effect size, and whether the baselines differ.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from mt_widgets.study.analysis_plan import TESTS


class SummarisedStatistics(Protocol):
    """What the summary reads of a study's statistics (``statistics.StudyStatistics`` has it). A
    protocol rather than an import of StudyStatistics, which imports this module: no import circle."""

    groups: Any
    group_notes: Any
    alternative: str
    alpha: float
    test: str
    changes: Any
    change_summary: Any
    compared: Any
    between: Any
    baseline: Any
    baseline_episodes: Any

#: The tests' names as a reader sees them.
TEST_NAMES = {"student": "Student's t-test", "welch": "Welch's t-test", "mannwhitney": "Mann-Whitney U"}


def _p(p: float) -> str:
    if np.isnan(p):
        return "p not computable"
    return "p < 0.001" if p < 0.001 else f"p = {p:.3f}"


def plain_language_summary(results: SummarisedStatistics) -> str:
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
