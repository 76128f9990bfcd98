"""The study's analysis plan: which changes of teaching error it compares.

A comparison is fixed before the data come (it belongs to a pre-registration, with the
protocol), so it lives with the runner; the statistics (``mt_widgets.analysis.statistics``)
and the in-silico engine (``mt_widgets.in_silico``) both read it.
"""

from __future__ import annotations

from dataclasses import dataclass

from mt_widgets.core.validation import as_finite, as_fraction


@dataclass(frozen=True)
class Change:
    """A change of teaching error between two episodes: ``after`` minus ``before``.

    Attributes:
        name: a key for tables ("P1_to_P3E8").
        before: (phase, episode) of the earlier episode; episode is 1-based, or None for the
            phase's last episode.
        after: (phase, episode) of the later episode, the same way.
        label: a human label ("P1 -> P3E8").
        meaning: what the change measures, in one phrase ("effect of guidance").
    """

    name: str
    before: tuple[str, int | None]
    after: tuple[str, int | None]
    label: str
    meaning: str


#: The paper's three comparisons (its Fig. 3b-d and the rows of ``mt_widgets.in_silico.paper_results``).
PAPER_CHANGES = (
    Change("P1_to_P3E8", ("P1", 1), ("P3", 8), "P1 -> P3E8", "effect of guidance"),
    Change("P1_to_P4", ("P1", 1), ("P4", 1), "P1 -> P4", "retention"),
    Change("P2_to_P5", ("P2", 1), ("P5", 1), "P2 -> P5", "transfer to a new skill"),
)


def changes_that_fit(changes, episodes_per_phase: dict) -> tuple:
    """The ``changes`` whose two episodes a protocol has: both phases, each episode within its
    phase's count (None, a phase's last episode, fits any phase).

    A protocol without an ``[analysis]`` table is analysed on the paper's comparisons that fit
    its phases: the online pilot's three-phase study (P1, P3 of two episodes, P4) keeps P1 -> P4
    and has no P3E8 or P5 to compare.

    Args:
        changes: ``Change`` comparisons.
        episodes_per_phase: {phase id: its number of episodes}, every session's phases.
    """
    def fits(point) -> bool:
        phase, episode = point
        return phase in episodes_per_phase and (episode is None or 1 <= episode <= episodes_per_phase[phase])

    return tuple(change for change in changes if fits(change.before) and fits(change.after))


#: The between-group tests an analysis plan can name as its primary test.
TESTS = ("student", "welch", "mannwhitney")
#: Sidedness of the tests, phrased as target minus control.
ALTERNATIVES = ("two-sided", "less", "greater")


@dataclass(frozen=True)
class AnalysisPlan:
    """What the study will test, fixed with the protocol (its ``[analysis]`` table) before data come.

    The defaults are the paper's: Student's t-test (the test its G*Power analysis assumes: d =
    0.9, alpha 0.05, power 0.8, one-tailed, 16 per group), one-sided (the target group improves
    more: target minus control "less"), on the three changes of ``PAPER_CHANGES``. Welch's t and
    the Mann-Whitney U test are reported beside the primary test, which the report names.

    Attributes:
        test: the primary between-group test, one of ``TESTS``.
        alternative: one of ``ALTERNATIVES``.
        alpha: the significance level.
        effect_size: the Cohen's d the sample size was planned for.
        power: the power planned for.
        changes: the comparisons (``Change``), by default the paper's three; a protocol without
            an ``[analysis]`` table gets those of the three that fit its phases
            (``changes_that_fit``), none if none does.
        baseline: the two (phase, episode) episodes of the post-hoc baseline check (the
            paper's P1 against P2), or None for none; a protocol without those phases gets no
            check.

    The first of the protocol's groups is compared against the second (``alternative`` is
    first minus second), whatever their names.
    """

    test: str = "student"
    alternative: str = "less"
    alpha: float = 0.05
    effect_size: float = 0.9
    power: float = 0.8
    changes: tuple = PAPER_CHANGES
    baseline: tuple | None = (("P1", 1), ("P2", 1))

    def __post_init__(self):
        if self.test not in TESTS:
            raise ValueError(f"test: expected one of {list(TESTS)}, got {self.test!r}")
        if self.alternative not in ALTERNATIVES:
            raise ValueError(f"alternative: expected one of {list(ALTERNATIVES)}, got {self.alternative!r}")
        for name in ("alpha", "power"):
            as_fraction(name, getattr(self, name))
        if as_finite("effect_size", self.effect_size) == 0:
            raise ValueError(f"effect_size: expected a non-zero number (Cohen's d), got {self.effect_size!r}")

    def compared(self, protocol_name: str) -> tuple:
        """The changes to analyse.

        Raises:
            ValueError: the plan compares nothing (a protocol whose phases fit none of the paper's
                comparisons and whose ``[analysis]`` table names none), naming the protocol and
                how to add its comparisons.
        """
        if not self.changes:
            paper = ", ".join(change.label for change in PAPER_CHANGES)
            raise ValueError(f"changes: protocol {protocol_name!r} has no comparisons to analyse: its phases fit none "
                             f"of the paper's ({paper}); name them in its [analysis] table, e.g. changes = "
                             f'[{{name = "guidance", before = ["P1", 1], after = ["P3", 2]}}] '
                             f"(docs/user/analysis.md), or pass changes=")
        return self.changes

    def as_dict(self) -> dict:
        return {"test": self.test, "alternative": self.alternative, "alpha": self.alpha,
                "effect_size": self.effect_size, "power": self.power,
                "changes": [{"name": c.name, "before": list(c.before), "after": list(c.after), "label": c.label,
                             "meaning": c.meaning} for c in self.changes],
                "baseline": None if self.baseline is None else [list(b) for b in self.baseline]}
