"""The course's assignments go through nbgrader as an instructor would run them.

Every assignment is generated; then autograded, in one nbgrader run per assignment, for the
instructor's own solutions (full marks), the untouched released notebook (0, no crash) and the
bank of wrong answers in tests/course/wrong_answers.py (each at the score the instructor's guide
states) and, for the first assignment, a submission with a test cell deleted and one with an
answer cell deleted; then the feedback HTML is generated. A scan looks for the expected values
in the released notebooks and in the feedback of an untouched submission; the gradebook lists
the written answers as needing manual grading.
"""

from __future__ import annotations

import csv
import re
import subprocess
import sys

import nbformat
import numpy as np
import pytest
from nbgrader.api import Gradebook

from .course_support import ASSIGNMENTS, REPO, copy_course, course_env, grade_id, max_points, nbgrader, source_notebook
from .wrong_answers import BANK, guide_table

pytestmark = pytest.mark.slow

GUIDE = REPO / "docs" / "course" / "instructors-guide.md"


def _cells(assignment):
    return [c for c in source_notebook(assignment).cells if c.metadata.get("nbgrader", {}).get("grade")]


def auto_points(assignment) -> float:
    return sum(float(c.metadata["nbgrader"]["points"]) for c in _cells(assignment) if c.cell_type == "code")


def hidden_points(assignment) -> float:
    return sum(float(c.metadata["nbgrader"]["points"]) for c in _cells(assignment)
               if c.cell_type == "code" and "BEGIN HIDDEN TESTS" in c.source)


def _write(notebook, course, student, assignment):
    folder = course / "submitted" / student / assignment
    folder.mkdir(parents=True, exist_ok=True)
    nbformat.write(notebook, folder / f"{assignment}.ipynb")


def _with_answers(assignment, answers: dict[str, str]):
    notebook = source_notebook(assignment)
    found = set()
    for cell in notebook.cells:
        if grade_id(cell) in answers:
            cell.source = answers[grade_id(cell)].strip()
            found.add(grade_id(cell))
    assert found == set(answers), f"{assignment}: no answer cell {set(answers) - found}"
    return notebook


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    course = copy_course(tmp_path_factory.mktemp("course") / "course")
    for assignment in ASSIGNMENTS:
        result = nbgrader(course, "generate_assignment", assignment, "--force")
        assert result.returncode == 0, result.stderr[-3000:]
    for assignment in ASSIGNMENTS:
        _write(source_notebook(assignment), course, "solution", assignment)
        released = nbformat.read(course / "release" / assignment / f"{assignment}.ipynb", as_version=4)
        _write(released, course, "untouched", assignment)
        for student, _, answers, _ in BANK[assignment]:
            _write(_with_answers(assignment, answers), course, student, assignment)
    first = ASSIGNMENTS[0]
    for student, removed in (("deleted-test", "test_teaching_error"), ("deleted-answer", "teaching_error")):
        notebook = source_notebook(first)
        notebook.cells = [c for c in notebook.cells if grade_id(c) != removed]
        _write(notebook, course, student, first)
    logs = {}
    for assignment in ASSIGNMENTS:   # one run grades every submission of the assignment
        result = nbgrader(course, "autograde", assignment, "--create", timeout=1800)
        logs[assignment] = result.stdout + result.stderr
        assert result.returncode == 0, logs[assignment][-3000:]
    for assignment in ASSIGNMENTS:
        result = nbgrader(course, "generate_feedback", assignment)
        assert result.returncode == 0, (result.stdout + result.stderr)[-3000:]
    scores, manual = {}, {}
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        for assignment in ASSIGNMENTS:
            for submission in gradebook.assignment_submissions(assignment):
                notebook = submission.notebooks[0]
                auto = sum(g.auto_score or 0.0 for g in notebook.grades if g.cell.cell_type == "code")
                scores[(assignment, submission.student.id)] = (auto, submission.max_score)
                manual[(assignment, submission.student.id)] = sorted(
                    g.name for g in notebook.grades if g.needs_manual_grade)
    return {"course": course, "scores": scores, "manual": manual, "logs": logs}


# -- the sources --------------------------------------------------------------------------------

def test_there_are_eight_assignments_each_worth_ten_autograded_points():
    assert len(ASSIGNMENTS) == 8
    assert all(auto_points(a) == 10 for a in ASSIGNMENTS)


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_hidden_tests_hold_at_least_half_of_the_points_in_cells_of_their_own(assignment):
    assert hidden_points(assignment) >= max_points(assignment) / 2
    for cell in _cells(assignment):
        if "BEGIN HIDDEN TESTS" in cell.source:
            # Nothing but a comment outside the hidden block: the cell's points are the hidden tests'.
            outside = re.sub(r"### BEGIN HIDDEN TESTS.*?### END HIDDEN TESTS", "", cell.source, flags=re.S)
            assert all(line.startswith("#") for line in outside.strip().splitlines()), grade_id(cell)
            assert cell.source.rstrip().endswith("### END HIDDEN TESTS"), grade_id(cell)


def test_the_written_answers_are_graded_by_hand():
    written = {a: [grade_id(c) for c in _cells(a) if c.cell_type == "markdown"] for a in ASSIGNMENTS}
    assert all(written[a] for a in ASSIGNMENTS if not a.startswith("a6")), written


def test_values_pasted_without_functions_are_at_most_a_fifth_of_an_assignment():
    for assignment, entries in BANK.items():
        pasted = [score for student, _, _, score in entries if student == "pasted"]
        assert pasted and pasted[0] <= auto_points(assignment) / 5, assignment


def test_the_instructors_guide_states_the_scores_of_the_bank():
    assert guide_table() in GUIDE.read_text(encoding="utf-8")


# -- grading ------------------------------------------------------------------------------------

@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_generated_assignment_hides_the_solutions_and_hidden_tests(graded, assignment):
    released = (graded["course"] / "release" / assignment / f"{assignment}.ipynb").read_text()
    source = (graded["course"] / "source" / assignment / f"{assignment}.ipynb").read_text()
    assert "BEGIN SOLUTION" in source and "BEGIN SOLUTION" not in released
    assert "HIDDEN TESTS" not in released and "BEGIN HIDDEN TESTS" in source
    assert "raise NotImplementedError()" in released
    assert released.count("checks.") >= 3


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_the_instructors_solutions_get_full_marks(graded, assignment):
    auto, total = graded["scores"][(assignment, "solution")]
    assert auto == auto_points(assignment) and total == max_points(assignment)


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_untouched_released_notebooks_get_zero_without_crashing(graded, assignment):
    assert graded["scores"][(assignment, "untouched")][0] == 0.0
    text = (graded["course"] / "autograded" / "untouched" / assignment / f"{assignment}.ipynb").read_text()
    assert "CheckFailed" in text and ("not written yet" in text or "expected" in text)


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_each_wrong_answer_gets_the_score_the_guide_states(graded, assignment):
    got = {student: graded["scores"][(assignment, student)][0] for student, _, _, _ in BANK[assignment]}
    assert got == {student: score for student, _, _, score in BANK[assignment]}


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_written_answers_are_listed_for_manual_grading(graded, assignment):
    written = sorted(grade_id(c) for c in _cells(assignment) if c.cell_type == "markdown")
    assert graded["manual"][(assignment, "solution")] == written


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_feedback_says_what_is_wrong(graded, assignment):
    student = BANK[assignment][0][0]
    html = (graded["course"] / "feedback" / student / assignment / f"{assignment}.html").read_text()
    assert "CheckFailed" in html
    # The check's words (a direction, an error, the by-hand rule, a threshold), not a bare assertion.
    assert any(words in html for words in ("not right", "raised", "uses the package", "not below"))


def test_a_deleted_test_cell_is_put_back_with_a_note_and_graded(graded):
    first = ASSIGNMENTS[0]
    assert graded["scores"][(first, "deleted-test")][0] == 10.0
    assert "Missing grade cell test_teaching_error" in graded["logs"][first]
    html = (graded["course"] / "feedback" / "deleted-test" / first / f"{first}.html").read_text()
    assert "was missing from your submission" in html


def test_a_deleted_answer_cell_costs_only_its_checks_and_grading_goes_on(graded):
    first = ASSIGNMENTS[0]
    # teaching_error (1 + 2) and E_novice (1), which uses it, fail; nothing else does.
    assert graded["scores"][(first, "deleted-answer")][0] == 6.0
    html = (graded["course"] / "feedback" / "deleted-answer" / first / f"{first}.html").read_text()
    assert "NameError" in html and "teaching_error" in html


def test_grading_records_no_progress(graded):
    assert not list(graded["course"].rglob("*.jsonl"))
    assert "MT_WIDGETS_CLASS_FOLDER" not in course_env()


# -- no expected value is shown -------------------------------------------------------------------

def _expected_values() -> dict[str, list[float]]:
    """The numbers each assignment's answers come to on its visible data (computed here, with the library)."""
    from mt_widgets import SKILLS
    from mt_widgets.analysis import analyse_study
    from mt_widgets.classroom import references as ref

    skill = SKILLS["sim-point"]
    out: dict[str, list[float]] = {}
    states = skill.query_states(seed=1)
    Phi = skill.features(states)
    U = 2.0 * (np.array([0.8, 1.2]) - skill.end_effector(states)[0])
    fit = ref.ridge_fit(Phi, U, 0.01)
    out["a1_ridge_learner"] = [ref.teaching_error(fit, skill.theta), *fit.ravel()]
    Phi2 = skill.features(skill.query_states(seed=2))
    out["a2_optimal_demonstration"] = [ref.correction(Phi2, skill.theta, 0.01), ref.correction(Phi2, skill.theta, 1.0),
                                       *ref.optimal_demo(Phi2, skill.theta, 0.01).ravel()]
    states3 = skill.query_states(seed=3)
    Phi3 = skill.features(states3)
    U3 = 2.0 * (np.array([0.8, 1.2]) - skill.end_effector(states3)[0])
    A3, Ub3 = ref.ridge_matrix(Phi3, 0.01), ref.optimal_demo(Phi3, skill.theta, 0.01)
    out["a3_risk_bound"] = [ref.rho1(Phi3, 0.01), ref.rho2(U3, Ub3), ref.error_from_gap(A3, U3, Ub3),
                            *ref.terms(A3, U3, Ub3)]
    good = skill.query_states(seed=4)
    rng = np.random.default_rng(4)
    bad = good[0] + 0.1 * rng.normal(size=(5, 4))
    slip = 0.2 * rng.normal(size=(5, 2))
    out["a4_query_states"] = [v for P in (skill.features(good), skill.features(bad))
                              for v in (ref.condition_number(P), ref.rho1(P, 1e-4),
                                        ref.slip_error(P, skill.theta, 1e-4, slip))]
    episodes = analyse_study(trajectories_for=[]).episodes
    delta = ref.retention(episodes)
    groups = episodes.groupby("participant")["group"].first()
    means = ref.group_means(delta, groups)
    out["a7_reading_a_study"] = [*delta, *means.values(), ref.one_sided_welch_p(delta[groups[delta.index] == "target"],
                                                                              delta[groups[delta.index] == "control"])]
    from mt_widgets.core.learner_teaching import evaluation_states
    ev = evaluation_states(skill, 64)
    X8, X8_eval = (np.concatenate(skill.end_effector(s), axis=-1) for s in (skill.query_states(seed=8), ev))
    S8, Y8 = ref.kernel_smoother(X8, X8_eval, 1.0, 1e-3), skill.target_actions(ev)
    U8 = ref.smoother_teaching_actions(S8, Y8)
    out["a8_kernel_machine_teaching"] = [ref.smoother_risk(S8, U8, Y8),
                                         ref.smoother_risk(S8, skill.target_actions(skill.query_states(seed=8)), Y8),
                                         *U8.ravel()]
    return out


def _forms(value: float) -> set[str]:
    forms = {f"{value:.{digits}g}" for digits in (4, 5, 6)} | {f"{value:.4f}", f"{value:.3f}"}
    return {f for f in forms if len(f.strip("-0.")) >= 3}   # "0.5" or "1.2" say nothing


@pytest.fixture(scope="module")
def expected_values():
    return _expected_values()


@pytest.mark.parametrize("assignment", ASSIGNMENTS)
def test_no_expected_value_in_a_released_notebook_or_an_untouched_feedback(graded, expected_values, assignment):
    released = nbformat.read(graded["course"] / "release" / assignment / f"{assignment}.ipynb", as_version=4)
    released_text = "\n".join(c.source for c in released.cells)
    feedback = (graded["course"] / "feedback" / "untouched" / assignment / f"{assignment}.html").read_text()
    found = [(form, where) for value in expected_values.get(assignment, []) for form in _forms(float(value))
             for where, text in (("release", released_text), ("feedback", feedback)) if form in text]
    assert found == []
    # Nor the reference code: no test cell computes the answer in the open.
    tests = "\n".join(c.source for c in released.cells if c.metadata.get("nbgrader", {}).get("grade"))
    for code in ("np.linalg.solve", "s / (s ** 2", "np.array([[-2", "expected =", "pinv"):
        assert code not in tests, (assignment, code)
    assert "references." in tests


def test_the_scan_finds_an_expected_value_when_one_is_shown(expected_values):
    value = expected_values["a1_ridge_learner"][0]
    assert any(form in f"E_novice: expected {value:.6g}" for form in _forms(value))


def test_the_solution_gets_full_marks_once_its_written_answers_are_graded(graded):
    course = graded["course"]
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        for assignment in ASSIGNMENTS:
            submission = gradebook.find_submission(assignment, "solution")
            for grade in submission.notebooks[0].grades:
                if grade.needs_manual_grade:
                    grade.manual_score = grade.max_score
            gradebook.db.commit()
            submission = gradebook.find_submission(assignment, "solution")
            assert submission.score == submission.max_score == max_points(assignment)
    result = nbgrader(course, "export", "--to", str(course / "grades.csv"))
    assert result.returncode == 0, result.stderr[-2000:]
    rows = (course / "grades.csv").read_text().splitlines()
    assert rows[0].startswith("assignment,") and len(rows) > len(ASSIGNMENTS)
    assert re.search(r"a1_ridge_learner,.*solution", "\n".join(rows))
    # The LMS gradebook: one row per student, one column per assignment, names from the roster.
    roster = course.parent / "roster.csv"
    roster.write_text("login,name,email,role\nsolution,Sol Ution,sol@example.edu,\nabsent,Abe Sent,,\n")
    for lms in ("canvas", "moodle"):
        out = course.parent / f"lms-{lms}.csv"
        result = subprocess.run([sys.executable, "lms_export.py", "--roster", str(roster), "--format", lms,
                                 "--to", str(out)], cwd=course, env=course_env(), capture_output=True, text=True)
        assert result.returncode == 0, result.stderr[-2000:]
        table = list(csv.reader(out.open()))
        total = sum(max_points(a) for a in ASSIGNMENTS)
        assert table[0][4:] == [f"{a} ({max_points(a):g})" for a in ASSIGNMENTS] + [f"Total ({total:g})"]
        by_login = {row[2]: row for row in table[1:]}
        assert by_login["solution"][-1] == f"{total:g}" and by_login["untouched"][-1] == "0"
        assert by_login["absent"][4:] == [""] * (len(ASSIGNMENTS) + 1)   # missing, not 0
        assert (by_login["solution"][0] == "Sol Ution") if lms == "canvas" else \
            (by_login["solution"][:2] == ["Sol", "Ution"] and by_login["solution"][3] == "sol@example.edu")
