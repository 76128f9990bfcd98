"""One call from a study folder to every table and figure: ``analyse_study(folder)``.

The default folder is the small synthetic study shipped with the package
(``mt_widgets.analysis.example_studies.EXAMPLE_STUDY``), so the analysis notebook runs out of
the box.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from mt_widgets.core.learner import is_parametric_smoother
from mt_widgets.study.study_folder import StudyFolder
from mt_widgets.study.study_learners import learnt_policy_of, study_learner
from mt_widgets.study.tidy import read_study

from .example_studies import EXAMPLE_STUDY
from .figures import plot_changes, plot_error_by_episode, plot_trajectories, save_figure, trajectory_panels
from .statistics import StudyStatistics, analyse_protocol


@dataclass
class StudyAnalysis:
    """Everything ``analyse_study`` produced.

    Attributes:
        folder: the study folder read.
        episodes, demonstrations: the tidy rows as DataFrames.
        statistics: the ``StudyStatistics`` (tables, tests, summary).
        figures: {name: Figure}: "error_by_episode", "changes", and "trajectories" when made.
        saved: files written by ``save``.
    """

    folder: Path
    episodes: pd.DataFrame
    demonstrations: pd.DataFrame
    statistics: StudyStatistics
    figures: dict = field(default_factory=dict)
    saved: list = field(default_factory=list)

    def summary(self) -> str:
        return self.statistics.summary()

    def save(self, out_folder, formats=("png", "pdf")) -> list[Path]:
        """Writes the tables as CSV and every figure in each format into ``out_folder``."""
        out = Path(out_folder)
        out.mkdir(parents=True, exist_ok=True)
        tables = {"phase_summary": self.statistics.phases, "participant_changes": self.statistics.changes,
                  "results": self.statistics.results_table(), "between_groups": self.statistics.between,
                  "within_groups": self.statistics.within, "baseline_posthoc": self.statistics.baseline}
        written = []
        for name, table in tables.items():
            path = out / f"{name}.csv"
            table.to_csv(path, index=False)
            written.append(path)
        (out / "summary.txt").write_text(self.summary() + "\n", encoding="utf-8")
        written.append(out / "summary.txt")
        for name, figure in self.figures.items():
            for fmt in formats:
                written.append(save_figure(figure, out / f"{name}.{fmt}"))
        self.saved = written
        return written


def analyse_study(folder=None, alternative: str | None = None, alpha: float | None = None, changes=None,
                  trajectories_for=None, trajectory_duration: float | None = None,
                  test: str | None = None) -> StudyAnalysis:
    """Reads a study folder and computes every table and figure its protocol's analysis plan asks for.

    Groups (the first compared against the second), phases, changes, skills, the primary test
    and the baseline check all come from the study's protocol (``study.json``) and its
    ``[analysis]`` table; the paper's protocols give the paper's analysis.

    Args:
        folder: a study folder (``study.json`` and participant logs); default ``EXAMPLE_STUDY``.
        alternative: sidedness of the tests, first group minus second ("less": the paper's
            one-sided hypotheses; "two-sided"). Default: the study's analysis plan (its
            protocol's ``[analysis]`` table), as are ``alpha``, ``changes`` and ``test``.
        alpha: the significance level of the summary.
        changes: the comparisons (default the paper's three).
        test: the primary between-group test ("student", "welch", "mannwhitney").
        trajectories_for: participant codes for the trajectory figure (default: the first of
            each group; an empty list skips it).
        trajectory_duration: seconds of each rollout in that figure (default the plant's).

    Returns:
        A ``StudyAnalysis``.
    """
    folder = EXAMPLE_STUDY if folder is None else Path(folder)
    episodes, demonstrations = read_study(folder)
    if not episodes:
        raise ValueError(f"folder: expected completed episodes in {folder}, found none")
    episodes = pd.DataFrame(episodes)
    demonstrations = pd.DataFrame(demonstrations)
    protocol = StudyFolder(folder).protocol
    statistics = analyse_protocol(episodes, protocol, changes=changes, alternative=alternative, alpha=alpha,
                                  test=test)
    groups = statistics.groups
    figures = {"error_by_episode": plot_error_by_episode(episodes, groups=groups),
               "changes": plot_changes(episodes, statistics.compared, groups=groups)}
    if trajectories_for is None:
        firsts = episodes.groupby("group")["participant"].first()
        trajectories_for = [firsts[g] for g in groups if g in firsts.index]
    if trajectories_for:
        panels = trajectory_panels(protocol)
        # A learner with a Theta on the features (ridge) logs Theta_hat to roll out; another
        # learner's policy is fitted again from the logged states and actions (deterministic: the
        # one the participant saw).
        has_theta = all(is_parametric_smoother(study_learner(protocol, skill)) for skill in protocol.skills.values())
        refitted = None if has_theta else refitted_trajectories(
            episodes, demonstrations, protocol, trajectories_for, [p for panel in panels for p in panel],
            trajectory_duration)
        figures["trajectories"] = plot_trajectories(episodes, trajectories_for, panels=panels,
                                                    duration=trajectory_duration, trajectories=refitted,
                                                    skills=protocol.skills)
    return StudyAnalysis(folder, episodes, demonstrations, statistics, figures)


def refitted_trajectories(episodes, demonstrations, protocol, participants, phases, duration: float | None = None,
                          record_every: int = 20) -> dict:
    """The policies participants taught the protocol's learner, fitted again from the logged query
    states and actions and rolled out from each skill's start.

    Args:
        episodes, demonstrations: the tidy rows (``read_study``) as DataFrames.
        protocol: the study's ``Protocol`` (its learner, lambda and skills).
        participants: participant codes; phases: phase ids.
        duration: seconds per rollout (default the skill's); record_every: steps between samples.

    Returns:
        {(participant, phase, episode): Trajectory} for the completed episodes among them.
    """
    action_columns = sorted((c for c in demonstrations.columns if c.startswith("action_")), key=lambda c: int(c[7:]))
    out = {}
    chosen = episodes[episodes["participant"].isin([str(p) for p in participants]) & episodes["phase"].isin(phases)]
    for row in chosen.itertuples():
        mine = demonstrations[(demonstrations["participant"] == row.participant)
                              & (demonstrations["phase_index"] == row.phase_index)
                              & (demonstrations["episode"] == row.episode)].sort_values("index")
        skill = protocol.skills[row.skill]
        states = np.array([json.loads(state) for state in mine["state"]], dtype=float)
        actions = mine[action_columns[:skill.plant.action_dim]].to_numpy(dtype=float)
        policy = learnt_policy_of(protocol, skill, states, actions)
        out[(row.participant, row.phase, int(row.episode))] = skill.reproduce_policy(policy, duration, record_every)
    return out
