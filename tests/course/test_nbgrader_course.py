"""The course's assignments go through nbgrader as an instructor would run them.

Every assignment is generated; then autograded for the instructor's own solutions (full marks),
the untouched released notebook (less than full, no crash), one seeded wrong answer (the exact
partial score it should get) and, for the first assignment, a submission with a test cell
deleted and one with an answer cell deleted; then the feedback HTML is generated.
"""

from __future__ import annotations

import re

import nbformat
import pytest
from nbgrader.api import Gradebook

from .course_support import ASSIGNMENTS, copy_course, course_env, grade_id, max_points, nbgrader, source_notebook

pytestmark = pytest.mark.slow

#: One seeded wrong answer per assignment: (answer cell, its wrong code, the score expected).
WRONG = {
    "a1_ridge_learner": ("ridge_fit", """
def ridge_fit(Phi, U, lam):
    return np.linalg.solve(Phi.T @ Phi, Phi.T @ U).T      # forgot lam
""", 4.0),  # ridge_fit (4) and E_novice (2) fail; teaching_error (2) and shrinks (2) pass
    "a2_optimal_demonstration": ("optimal_demo", """
def optimal_demo(Phi, theta, lam):
    return Phi @ np.asarray(theta).T                      # the skill's own actions
""", 4.0),  # ridge_matrix (3) and linear (1) pass; optimal_demo (3), exact (1), corrections (2) fail
    "a3_risk_bound": ("rho1", """
s = np.linalg.svd(Phi, compute_uv=False)
rho1 = float(s[0] / (s[0] ** 2 + lam))                    # the largest singular value only
""", 7.0),  # rho1 (3) fails; rho2, E and worst do not depend on it
    "a4_query_states": ("condition_number", """
def condition_number(Phi):
    return float(np.linalg.cond(Phi.T @ Phi))             # squares the condition number
""", 7.0),  # condition_number (3) fails
    "a5_teach_in_widget": ("my_action", """
def my_action(skill, state):
    position, velocity = skill.end_effector(np.asarray(state))
    return np.array(skill.target.point) - position         # no damping
""", 6.0),  # teaching (4) fails; gaps (3) and final distance (3) are measured on the same episode
    "a6_own_skill": ("my_skill", """
k, d, target = 2.0, 1.5, np.array([1.0, 0.6])
my_skill = Skill("my-reach", "Reach (1.0, 0.6) m", base.plant, base.feature_map,
                 theta=[[-k, 0, -d, 0, target[0]], [0, -k, 0, -d, target[1]]],   # rest point not times k
                 start=base.start, target=PointTarget((1.0, 0.6)))
""", 3.0),  # the skill (4) and where it ends (3) fail; teaching it exactly (3) still works
    "a7_reading_a_study": ("test", """
groups = episodes.groupby("participant")["group"].first()
target = retention[groups[retention.index] == "target"]
control = retention[groups[retention.index] == "control"]
test_choice = "welch-two-sided"                           # ignores the hypothesis' direction
p_value = float(stats.ttest_ind(target, control, equal_var=False).pvalue)
""", 7.0),  # the choice (1) and the p-value (2) fail; p = 0.155 and 0.078 are both above 0.05
}


def _write(notebook, course, student, assignment):
    folder = course / "submitted" / student / assignment
    folder.mkdir(parents=True, exist_ok=True)
    nbformat.write(notebook, folder / f"{assignment}.ipynb")


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    course = copy_course(tmp_path_factory.mktemp("course") / "course")
    generated = {}
    for assignment in ASSIGNMENTS:
        result = nbgrader(course, "generate_assignment", assignment, "--force")
        generated[assignment] = result
        assert result.returncode == 0, result.stderr[-3000:]
    for assignment in ASSIGNMENTS:
        _write(source_notebook(assignment), course, "solution", assignment)
        released = nbformat.read(course / "release" / assignment / f"{assignment}.ipynb", as_version=4)
        _write(released, course, "untouched", assignment)
        cell_id, code, _ = WRONG[assignment]
        wrong = source_notebook(assignment)
        cells = [c for c in wrong.cells if grade_id(c) == cell_id]
        assert len(cells) == 1, f"{assignment}: no answer cell {cell_id}"
        cells[0].source = code.strip()
        _write(wrong, course, "wrong", assignment)
    first = ASSIGNMENTS[0]
    for student, removed in (("deleted-test", "test_teaching_error"), ("deleted-answer", "teaching_error")):
        notebook = source_notebook(first)
        notebook.cells = [c for c in notebook.cells if grade_id(c) != removed]
        _write(notebook, course, student, first)
    logs = {}
    for assignment in ASSIGNMENTS:
        result = nbgrader(course, "autograde", assignment, "--create")
        logs[assignment] = result.stdout + result.stderr
        assert result.returncode == 0, logs[assignment][-3000:]
    for assignment in ASSIGNMENTS:
        result = nbgrader(course, "generate_feedback", assignment)
        assert result.returncode == 0, (result.stdout + result.stderr)[-3000:]
    scores = {}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        for assignment in ASSIGNMENTS:
            for submission in gradebook.assignment_submissions(assignment):
                scores[(assignment, submission.student.id)] = (submission.score, submission.max_score)
    return {"course": course, "scores": scores, "logs": logs, "generated": generated}


def test_there_are_at_least_six_assignments_each_worth_ten_points():
    assert len(ASSIGNMENTS) >= 6
    assert all(max_points(a) == 10 for a in ASSIGNMENTS)


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_generated_assignment_hides_the_solutions_and_hidden_tests(graded, assignment):
    released = (graded["course"] / "release" / assignment / f"{assignment}.ipynb").read_text()
    source = (graded["course"] / "source" / assignment / f"{assignment}.ipynb").read_text()
    assert "BEGIN SOLUTION" in source and "BEGIN SOLUTION" not in released
    assert "HIDDEN TESTS" not in released
    assert "raise NotImplementedError()" in released
    # The visible checks stay, with their words.
    assert released.count("checks.") >= 3


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_the_instructors_solutions_get_full_marks(graded, assignment):
    assert graded["scores"][(assignment, "solution")] == (max_points(assignment), max_points(assignment))


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_untouched_released_notebooks_get_less_than_full_marks_without_crashing(graded, assignment):
    score, total = graded["scores"][(assignment, "untouched")]
    assert score == 0.0 < total  # every answer is still nbgrader's placeholder
    autograded = graded["course"] / "autograded" / "untouched" / assignment / f"{assignment}.ipynb"
    text = autograded.read_text()
    # The checks' words ("not written yet", "expected a Skill, got NoneType"), not a bare assertion.
    assert "CheckFailed" in text and "expected" in text
    assert "not written yet" in text or "not answered yet" in text or "got NoneType" in text


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_a_seeded_wrong_answer_gets_exactly_its_partial_score(graded, assignment):
    expected = WRONG[assignment][2]
    score, total = graded["scores"][(assignment, "wrong")]
    assert 0 < expected < total
    assert score == expected


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_feedback_html_shows_the_score_and_what_is_wrong(graded, assignment):
    feedback = graded["course"] / "feedback" / "wrong" / assignment / f"{assignment}.html"
    html = feedback.read_text()
    score, total = graded["scores"][(assignment, "wrong")]
    assert re.search(rf"Score:\s*{score:g}(\.0)?\s*/\s*{total:g}", html.replace("&nbsp;", " ")) or \
        f"{score:g}" in html
    assert "CheckFailed" in html and "expected" in html


def test_a_deleted_test_cell_is_put_back_with_a_note_and_graded(graded):
    first = ASSIGNMENTS[0]
    assert graded["scores"][(first, "deleted-test")] == (10.0, 10.0)
    assert "Missing grade cell test_teaching_error" in graded["logs"][first]
    html = (graded["course"] / "feedback" / "deleted-test" / first / f"{first}.html").read_text()
    assert "was missing from your submission" in html


def test_a_deleted_answer_cell_costs_only_its_checks_and_grading_goes_on(graded):
    first = ASSIGNMENTS[0]
    # teaching_error (2) and E_novice (2), which uses it, fail; nothing else does.
    assert graded["scores"][(first, "deleted-answer")] == (6.0, 10.0)
    html = (graded["course"] / "feedback" / "deleted-answer" / first / f"{first}.html").read_text()
    assert "NameError" in html and "teaching_error" in html
    # Everyone else was graded as usual.
    assert graded["scores"][(first, "solution")] == (10.0, 10.0)
    assert graded["scores"][(first, "wrong")][0] == WRONG[first][2]


def test_grading_records_no_progress(graded):
    # No class folder is set while grading: the recorder writes nothing anywhere in the course.
    assert not list(graded["course"].rglob("*.jsonl"))
    assert "MT_WIDGETS_CLASS_FOLDER" not in course_env()
