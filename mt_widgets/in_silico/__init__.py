"""Synthetic teachers and in-silico studies: the simulation of a study, above its runner.

- ``teachers``: the documented model of how novices demonstrate and learn
  (``TeacherParameters``, ``TeacherPopulation``, the fitted ``PAPER_FIT`` / ``PAPER_FIT_UARM``).
- ``plan``: a protocol's episodes and query states as the engine runs them.
- ``engine``: whole studies of synthetic teachers at once (``run_in_silico``,
  ``run_many_studies``), on the batched teaching episode of ``mt_widgets.core.episode_batch``.
- ``sessions``: synthetic teachers driving the session engine into real logs
  (``run_through_sessions``).
- ``paper_results``: the paper's reported results; ``fitting``: fitting the model to them.

Depends on ``mt_widgets.core`` and ``mt_widgets.study`` only; no widget library.
"""

from .engine import InSilicoStudy, run_in_silico, run_many_studies, simulate_changes
from .fitting import FITTED_FIELDS, fit_loss, fit_to_paper
from .paper_results import PAPER_RESULTS, implied_baselines, paper_changes, paper_results, paper_targets
from .plan import (
    default_parameters,
    episode_plan,
    experiment_of,
    paper_fit,
    resolve_protocol,
    runs_on_uarm,
    session_delays,
)
from .sessions import SessionTeacher, run_through_sessions
from .teachers import OPTIMAL_TEACHER, PAPER_FIT, PAPER_FIT_UARM, Forgetting, TeacherParameters, TeacherPopulation

__all__ = [
    "FITTED_FIELDS", "Forgetting", "InSilicoStudy", "OPTIMAL_TEACHER", "PAPER_FIT", "PAPER_FIT_UARM", "PAPER_RESULTS",
    "SessionTeacher", "TeacherParameters", "TeacherPopulation", "default_parameters", "episode_plan",
    "experiment_of", "fit_loss", "fit_to_paper", "implied_baselines", "paper_changes", "paper_fit",
    "paper_results", "paper_targets", "resolve_protocol", "run_in_silico", "run_many_studies",
    "run_through_sessions", "runs_on_uarm", "session_delays", "simulate_changes",
]
