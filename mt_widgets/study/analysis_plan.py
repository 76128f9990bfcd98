"""The study's analysis plan: which changes of teaching error it compares.

A comparison is fixed before the data come (it belongs to a pre-registration, with the
protocol), so it lives with the runner; the statistics (``mt_widgets.analysis.statistics``)
and the in-silico engine (``mt_widgets.in_silico``) both read it.
"""

from __future__ import annotations

from dataclasses import dataclass


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
