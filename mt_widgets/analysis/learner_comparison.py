"""How much machine-teaching guidance helps, per learner: one in-silico study per robot learner.

The same protocol is run once per learner (its ``learner`` replaced, nothing else), each time by
the same synthetic teachers (``mt_widgets.in_silico.run_through_sessions``: the same seeds, the
same groups) through the session engine, so the guidance they see is that learner's machine
teaching and their errors are that learner's (ridge: ||Theta_hat - Theta||; any other: the
policy risk). The protocol's analysis plan then compares its groups on its changes, per learner.

The synthetic teachers' model was fitted to the paper's ridge study
(``mt_widgets.in_silico.teachers``): for another learner it is an assumption that novices blend
their naive arrows with the shown arrows the same way, whatever the robot does with them.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from mt_widgets.core.learner_teaching import LEARNERS
from mt_widgets.core.validation import UnknownKeyError, as_count
from mt_widgets.in_silico import resolve_protocol, run_through_sessions
from mt_widgets.study.protocol import protocol_from_data
from mt_widgets.study.tidy import read_study

from .statistics import analyse_protocol

#: The columns of ``guidance_by_learner``'s table.
LEARNER_COLUMNS = ("learner", "change", "label", "target_mean_before", "target_percent_change",
                   "control_mean_before", "control_percent_change", "difference", "hedges_g", "p")


def protocol_with_learner(protocol, learner: str):
    """``protocol`` (a ``Protocol``, shipped name or path) with its ``learner`` replaced, named
    "<name>-<learner>" so its study folder is its own."""
    protocol = resolve_protocol(protocol)
    if learner not in LEARNERS:
        raise UnknownKeyError(f"learner: expected one of the available learners ({', '.join(LEARNERS)}), "
                              f"got {learner!r}")
    return protocol_from_data({**protocol.data, "learner": learner, "name": f"{protocol.name}-{learner}"},
                              f"{protocol.source} with learner {learner}")


def guidance_by_learner(folder, learners=tuple(LEARNERS), protocol="paper-uarm", n_participants: int = 16,
                        seed: int = 0) -> pd.DataFrame:
    """Runs the protocol once per learner with the same synthetic teachers and compares its groups.

    Args:
        folder: a folder for the study folders (one sub-folder per learner, created).
        learners: names of ``mt_widgets.core.LEARNERS``.
        protocol: the protocol (a ``Protocol``, a shipped name or a path); its groups alternate.
        n_participants: synthetic participants per learner (half per group).
        seed: the teachers' root seed (the same teachers for every learner).

    Returns:
        One row per (learner, change) with ``LEARNER_COLUMNS``: each group's mean error before and
        its mean change in percent of it, the difference of the mean changes (first group minus
        second: negative when guidance helps), Hedges' g and the primary test's p.
    """
    n_participants = as_count("n_participants", n_participants)
    base = resolve_protocol(protocol)
    groups = [base.groups[i % 2] for i in range(n_participants)]
    rows = []
    for learner in learners:
        variant = protocol_with_learner(base, learner)
        study = run_through_sessions(Path(folder) / learner, n_participants, protocol=variant, seed=seed,
                                     groups=groups, progress=False)
        episodes, _ = read_study(study.folder)
        statistics = analyse_protocol(episodes, variant)
        first, second = statistics.groups
        summary = statistics.change_summary.set_index(["change", "group"])
        for test in statistics.between.itertuples():
            one, two = summary.loc[(test.change, first)], summary.loc[(test.change, second)]
            rows.append({"learner": learner, "change": test.change, "label": test.label,
                         "target_mean_before": one["mean_before"], "target_percent_change": one["percent_change"],
                         "control_mean_before": two["mean_before"], "control_percent_change": two["percent_change"],
                         "difference": one["mean"] - two["mean"], "hedges_g": test.hedges_g,
                         "p": getattr(test, f"{statistics.test}_p")})
    return pd.DataFrame(rows, columns=list(LEARNER_COLUMNS))


__all__ = ["LEARNER_COLUMNS", "guidance_by_learner", "protocol_with_learner"]
