"""Shared test settings."""

import os

# Notebooks run by nbval inherit this: the one documented switch that shortens long work.
os.environ.setdefault("MT_WIDGETS_FAST", "1")

# Pages that browser tests serve through Voila or JupyterLab: they are driven by a browser,
# not executed by nbval.
collect_ignore_glob = ["*/pages/*.ipynb", "*/pages/**/*.ipynb"]


import pytest  # noqa: E402

from browser_support import CHROMIUM, CHROMIUM_ARGS, artifact_path  # noqa: E402


@pytest.fixture(scope="session")
def browser():
    """Debian's Chromium through Playwright, one for the whole run; fails when either is missing."""
    from pathlib import Path

    if not Path(CHROMIUM).exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: install it with `apt-get install -y chromium` "
                    f"(or set MT_WIDGETS_CHROMIUM)", pytrace=False)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as error:
        pytest.fail(f"playwright is not installed ({error}): pip install 'mt-widgets[test]'", pytrace=False)
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


#: Tests that take seconds each (subprocesses, whole simulated studies, long rollouts), as
#: "path::name" prefixes (every parametrisation): ``slow`` without an edit to their files. A new
#: slow test can as well carry ``@pytest.mark.slow`` itself.
SLOW_TESTS = (
    "tests/analysis/test_figures.py::test_the_report_shows_the_participants_own_errors_and_arrows",
    "tests/classroom/test_progress.py::test_two_kernels_of_one_student_writing_at_once_lose_nothing",
    "tests/core/test_energy_and_rollouts.py::test_energy_is_conserved_without_gravity",
    "tests/core/test_energy_and_rollouts.py::test_the_compiled_rollout_equals_the_generic_numpy_rollout",
    "tests/core/test_machine_teaching.py::test_learning_from_the_optimal_demonstration_gives_back_theta",
    "tests/core/test_query_states_and_skills.py::test_no_seed_dead_ends",
    "tests/in_silico/test_synthetic_teachers.py::test_batched_engine_and_session_engine_give_the_same_study",
    "tests/in_silico/test_synthetic_teachers.py::test_in_the_simulation_the_two_baselines_do_not_differ",
    "tests/in_silico/test_synthetic_teachers.py::test_the_shipped_synthetic_studies_are_what_the_current_model",
    "tests/in_silico/test_synthetic_teachers.py::test_the_study_analysis_imports_without_widgets",
    "tests/in_silico/test_synthetic_teachers.py::test_without_an_effect_simulated_power_is_the_false_positive",
    "tests/study/test_concurrency.py::",
    "tests/study/test_crash_safety.py::test_killed_and_resumed_sessions_log_exactly_the_uninterrupted",
    "tests/study/test_user_skill_protocol.py::",
    "tests/test_readme.py::test_readme_example_runs",
)


def pytest_collection_modifyitems(config, items):
    """Marks for the fast tier (``-m "not browser and not slow"``, scripts/test-fast.sh): every
    test that drives Chromium is ``browser`` (it takes the ``browser`` fixture, or lives in a
    folder named ``browser*``), every notebook run by nbval and every test of ``SLOW_TESTS`` is
    ``slow``."""
    for item in items:
        try:
            folders = item.path.relative_to(config.rootpath).parts[:-1]
        except ValueError:  # a path outside the repository (a temporary folder)
            folders = ()
        if "browser" in getattr(item, "fixturenames", ()) or any(f.startswith("browser") for f in folders):
            item.add_marker(pytest.mark.browser)
        if item.path.suffix == ".ipynb" or item.nodeid.startswith(SLOW_TESTS):
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def artifacts(request):
    """Where to keep screenshots: ``artifacts(step)`` -> test-artifacts/<test name>-<step>.png."""
    return lambda step: artifact_path(request.node.name, step)
