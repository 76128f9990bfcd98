"""The fast tier's list of slow tests, in a module of its own: tests import it by name
(``from tiers import SLOW_TESTS``), which a ``conftest`` import cannot do reliably, since pytest
re-imports every folder's conftest.py under the one name ``conftest``."""

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
