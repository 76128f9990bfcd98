"""The analysis of a teaching study: statistics, power, figures and the comparison with the paper.

- ``tables``: the episode rows checked, summarised by phase and by change.
- ``effect_size``: Hedges' g with its confidence interval.
- ``statistics``: the paper's tests of the changes, all in one ``StudyStatistics`` (and every
  name of ``tables``, ``effect_size`` and ``summary``, importable from here as before).
- ``summary``: the statistics in plain language.
- ``power``: analytic power and power by simulation (in-silico studies).
- ``figures``: the paper's figures (matplotlib).
- ``paper_comparison``: a study's changes and baselines beside the paper's.
- ``study_analysis``: ``analyse_study(folder)``, every table and figure in one call.
- ``learner_comparison``: how much guidance helps per robot learner (``guidance_by_learner``).
- ``example_studies``: the synthetic studies shipped with the package.

Above ``mt_widgets.study`` (the runner) and ``mt_widgets.in_silico`` (simulated teachers); no
widget library.
"""

from .example_studies import EXAMPLE_STUDY, EXAMPLE_UARM_STUDY, write_example_study
from .learner_comparison import guidance_by_learner, protocol_with_learner
from .paper_comparison import baseline_comparison, compare_with_paper
from .power import SimulatedPower, analytic_power, sample_size_per_group, simulated_power
from .statistics import PAPER_CHANGES, Change, StudyStatistics, analyse_changes, hedges_g
from .study_analysis import StudyAnalysis, analyse_study, refitted_trajectories

__all__ = [
    "Change", "EXAMPLE_STUDY", "EXAMPLE_UARM_STUDY", "PAPER_CHANGES", "SimulatedPower", "StudyAnalysis",
    "StudyStatistics", "analyse_changes", "analyse_study", "analytic_power", "baseline_comparison",
    "compare_with_paper", "hedges_g", "sample_size_per_group", "simulated_power", "write_example_study",
    "refitted_trajectories", "guidance_by_learner", "protocol_with_learner",
]
