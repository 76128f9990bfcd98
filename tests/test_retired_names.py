"""Names nothing used any more are gone, not kept as dead weight a reader must puzzle over."""

import importlib

import pytest

RETIRED = [
    # The library does not ask whether it runs under test: notebooks take their shortening from a
    # cell tagged `parameters` (conftest.py), the simulated arm its speed from an argument.
    ("mt_widgets.core", "running_under_test"),
    ("mt_widgets.apps.study_app", "running_under_test"),
    ("mt_widgets.core.trajectory", "Trajectory.resampled"),
    ("mt_widgets.in_silico.paper_results", "PAPER_SIMULATION_RESULTS"),
    ("mt_widgets.in_silico.teachers", "UARM_FITTED_FIELDS"),
    ("mt_widgets.study.session", "TEXT_STEPS"),
    # One record of a demonstration (issue 21): the canvas confirms a core Demonstration, which the
    # episode keeps; the session keeps no actions of its own and rebuilds no episode.
    ("mt_widgets.widgets", "ConfirmedAction"),
    ("mt_widgets.widgets.teaching", "ConfirmedAction"),
    ("mt_widgets.study.session", "Session._record_logged_actions"),
    # One teaching episode (issue 41): one EpisodeWidget and one EpisodeController serve every arm; no
    # page asks whether a plant is drawn in space (the widget draws it as its drawing says).
    ("mt_widgets.widgets", "SpaceEpisodeWidget"),
    ("mt_widgets.widgets", "drawn_in_space"),
    ("mt_widgets.widgets.teaching", "TeachingCanvas._record"),
    ("mt_widgets.widgets.teaching", "InputTiming"),
    # Robots as data (issue 41): the URDF is read at run time, not generated into a module of literals.
    ("mt_widgets.core", "ur5_description"),
    ("mt_widgets.robot_models.urdf", "description_module"),
    ("mt_widgets.robot_models.urdf", "generate"),
    ("mt_widgets.robot_models.urdf", "read_serial_chain"),
    # The learner is the one seam (issue 42): no name picks ridge's road; a learner's protocols do.
    ("mt_widgets.study.study_learners", "PAPER_LEARNER"),
    ("mt_widgets.core.episode", "TeachingEpisode.ridge"),
    ("mt_widgets.core.episode", "TeachingEpisode._require_ridge"),
    ("mt_widgets.core.kernel_learners", "_check_inputs"),
    # Theta's error and the policy risk by their own names (issue 42): no field holds one or the other.
    ("mt_widgets.core.episode", "TeachingEpisode.error"),
    ("mt_widgets.core.episode", "EpisodeResult.error"),
    ("mt_widgets.core.episode", "EpisodeResult.teaching_error"),
    ("mt_widgets.in_silico.engine", "_BatchOutcome.error"),
    ("mt_widgets.widgets", "EpisodeWidget.error"),
]


@pytest.mark.parametrize(("module", "name"), RETIRED)
def test_a_retired_name_is_gone(module, name):
    owner = importlib.import_module(module)
    for part in name.split("."):
        if not hasattr(owner, part):
            return
        owner = getattr(owner, part)
    pytest.fail(f"{module}.{name} still exists")
