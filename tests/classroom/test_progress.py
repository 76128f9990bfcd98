"""The class progress recorder: what it writes, where, and what it survives."""

from __future__ import annotations

import datetime as dt
import json
import multiprocessing

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.classroom import (
    CLASS_FOLDER_ENV,
    CheckFailed,
    ClassFolderError,
    ExerciseChecks,
    ProgressRecorder,
    create_class_folder,
    pseudonym,
    read_class,
    read_student,
    summarise,
)
from mt_widgets.classroom.summary import episode_errors
from mt_widgets.widgets import EpisodeWidget


def test_without_a_class_folder_nothing_is_written_anywhere(tmp_path, monkeypatch):
    monkeypatch.delenv(CLASS_FOLDER_ENV, raising=False)
    monkeypatch.chdir(tmp_path)
    recorder = ProgressRecorder(student="alice")
    assert not recorder.enabled
    assert recorder.record("lesson", lesson="01") is None
    checks = ExerciseChecks("a1_ridge_learner", recorder)
    checks.true("one", True, "never shown")
    episode = EpisodeWidget("sim-point", guidance=False, duration=0.5)
    recorder.attach(episode, "a5")
    for action in episode.optimal:
        episode.demonstrate(action)
    assert episode.result is not None
    assert list(tmp_path.rglob("*")) == []


def test_the_environment_variable_sets_the_class_folder_and_files_hold_pseudonyms_only(tmp_path, monkeypatch):
    monkeypatch.setenv(CLASS_FOLDER_ENV, str(tmp_path / "class"))
    monkeypatch.setenv("MT_WIDGETS_STUDENT", "alice.smith")
    recorder = ProgressRecorder()
    recorder.lesson("01_ridge", step="start")
    files = sorted(p.name for p in (tmp_path / "class").iterdir())
    assert files == sorted([".locks", f"{recorder.student}.jsonl", "class.json"])
    text = (tmp_path / "class" / f"{recorder.student}.jsonl").read_text()
    assert "alice" not in text and "alice" not in recorder.student
    assert json.loads(text)["lesson"] == "01_ridge"
    # The same student gets the same file from any kernel; another class (salt) another name.
    assert ProgressRecorder(tmp_path / "class", "alice.smith").student == recorder.student
    assert ProgressRecorder(tmp_path / "other", "alice.smith").student != recorder.student
    assert pseudonym("alice.smith", "x") != pseudonym("bob", "x")


@pytest.mark.parametrize("make", ["file", "under-a-file"])
def test_a_class_folder_that_cannot_be_written_is_refused_by_name(tmp_path, make):
    blocker = tmp_path / "blocker"
    blocker.write_text("not a folder")
    folder = blocker if make == "file" else blocker / "class"
    with pytest.raises(ClassFolderError, match=r"class folder .*blocker"):
        ProgressRecorder(folder, "alice")


def test_a_class_folder_that_cannot_be_read_says_why(tmp_path):
    with pytest.raises(ClassFolderError, match="does not exist"):
        read_class(tmp_path / "missing")
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ClassFolderError, match="expected a folder, found a file"):
        read_class(tmp_path / "afile")
    (tmp_path / "plain").mkdir()
    with pytest.raises(ClassFolderError, match="holds no class.json"):
        read_class(tmp_path / "plain")
    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / "class.json").write_text("{not json")
    with pytest.raises(ClassFolderError, match="not JSON"):
        read_class(tmp_path / "damaged")


def test_a_student_file_that_cannot_be_read_is_named_and_everyone_else_is_shown(tmp_path):
    ProgressRecorder(tmp_path, "alice").lesson("01")
    create_class_folder(tmp_path)
    (tmp_path / "s-broken.jsonl").mkdir()  # reading it raises IsADirectoryError
    progress = read_class(tmp_path)
    assert len(progress.students) == 1
    assert any("s-broken.jsonl: cannot be read" in p for p in progress.problems)


def test_a_line_torn_by_a_killed_kernel_is_ended_by_the_next_event_and_nothing_else_is_lost(tmp_path):
    recorder = ProgressRecorder(tmp_path, "alice")
    recorder.lesson("01")
    recorder.check("a1", "fit", True)
    with open(recorder.path, "ab") as file:  # a kernel killed half-way through its line
        file.write(b'{"kind":"check","time":"2025-01-01T00:00')
    torn = read_student(recorder.path)
    assert [e["kind"] for e in torn.events] == ["lesson", "check"] and torn.torn_tail > 0
    event = recorder.check("a1", "error", False, "E: expected 2.4, got 5.8")
    assert event["repaired_torn_bytes"] == len(b'{"kind":"check","time":"2025-01-01T00:00')
    repaired = read_student(recorder.path)
    assert [e.get("check") for e in repaired.events] == [None, "fit", "error"]
    assert repaired.torn_lines == [3] and repaired.torn_tail == 0
    progress = read_class(tmp_path)
    assert progress.problems == [f"{recorder.path.name}: skipped 1 torn line(s) (line 3)"]


def _write_many(folder, count, barrier):
    recorder = ProgressRecorder(folder, "alice")
    barrier.wait()
    for number in range(count):
        recorder.record("demonstration", lesson="04", index=number, payload="x" * 3000)


@pytest.mark.slow
def test_two_kernels_of_one_student_writing_at_once_lose_nothing(tmp_path):
    create_class_folder(tmp_path)
    context = multiprocessing.get_context("fork")
    barrier = context.Barrier(2)
    workers = [context.Process(target=_write_many, args=(tmp_path, 150, barrier)) for _ in range(2)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(60)
        assert worker.exitcode == 0
    files = list(tmp_path.glob("*.jsonl"))
    assert len(files) == 1  # one student, one file
    student = read_student(files[0])
    assert student.torn_lines == [] and student.torn_tail == 0
    by_kernel = {}
    for event in student.events:
        by_kernel.setdefault(event["kernel"], []).append(event["n"])
    assert len(by_kernel) == 2
    assert all(numbers == list(range(150)) for numbers in by_kernel.values())


def test_an_episode_widget_is_followed_through_its_public_callbacks(tmp_path):
    recorder = ProgressRecorder(tmp_path, "alice")
    episode = EpisodeWidget("sim-point", seed=3, guidance=True, duration=1.0)
    detach = recorder.attach(episode, "04_one_full_episode")
    for action in episode.optimal + 0.5:
        episode.demonstrate(action)
        episode.next()
    events = read_student(recorder.path).events
    assert [e["kind"] for e in events] == ["demonstration"] * 5 + ["episode"]
    assert events[-1]["theta_error"] == pytest.approx(episode.result.theta_error)
    assert events[-1]["skill"] == "sim-point" and events[2]["index"] == 2
    np.testing.assert_allclose(events[0]["optimal_action"], episode.optimal[0])
    detach()
    again = EpisodeWidget("sim-point", seed=4, guidance=False, duration=1.0)
    recorder.attach(again, "04_one_full_episode")
    detach()  # detaching the first widget's callbacks leaves the second's alone
    for action in again.optimal:
        again.demonstrate(action)
    assert len(read_student(recorder.path).events) == 12


def test_a_recorder_that_cannot_write_keeps_the_demonstration_pending(tmp_path):
    recorder = ProgressRecorder(tmp_path / "class", "alice")
    episode = EpisodeWidget("sim-point", seed=3, guidance=False, duration=1.0)
    recorder.attach(episode, "04")
    recorder.path.mkdir(parents=True)  # the student's file can no longer be opened for writing
    with pytest.raises(ClassFolderError, match="was not recorded"):
        episode.demonstrate(episode.optimal[0])
    assert episode.demonstrations == [] and episode.state_index == 0


def test_bad_arguments_are_refused_by_name(tmp_path):
    recorder = ProgressRecorder(tmp_path, "alice")
    with pytest.raises(TypeError, match="passed: expected a bool"):
        recorder.check("a1", "fit", 1)
    with pytest.raises(ValueError, match="kind: expected a non-empty string"):
        recorder.record("")
    with pytest.raises(ValueError, match="student: expected a non-empty name"):
        ProgressRecorder(tmp_path, "  ")
    with pytest.raises(TypeError, match="episode: expected an EpisodeWidget"):
        recorder.attach(object(), "04")
    with pytest.raises(ValueError, match="stuck_after_s: expected a positive number"):
        summarise(read_class(tmp_path), stuck_after_s=True)


def test_checks_say_in_words_what_is_wrong_and_are_recorded(tmp_path):
    recorder = ProgressRecorder(tmp_path, "alice")
    checks = ExerciseChecks("a1_ridge_learner", recorder)
    with pytest.raises(CheckFailed, match=r"theta_hat: expected shape \(2, 5\), got shape \(5, 2\) "
                                          r"\(the transpose.s shape: transpose it\)\. transpose"):
        checks.close("fit", "theta_hat", np.zeros((5, 2)), np.zeros((2, 5)), hint="transpose")
    with pytest.raises(CheckFailed, match=r"E: not right: it is too large\.$") as failed:
        checks.close("error", "E", 5.8, 2.4)
    assert "2.4" not in str(failed.value)          # the expected number is never shown
    with pytest.raises(CheckFailed, match="not answered yet"):
        checks.close("error", "E", None, 2.4)

    def ridge_fit(Phi, U, lam):
        raise NotImplementedError()

    with pytest.raises(CheckFailed, match="ridge_fit: not written yet"):
        checks.call("fit", ridge_fit, 1, 2, 3)
    checks.close("error", "E", 2.4 + 1e-12, 2.4)
    events = read_student(recorder.path).events
    assert [(e["kind"], e.get("check"), e.get("passed")) for e in events] == [
        ("lesson", None, None), ("check", "fit", False), ("check", "error", False), ("check", "error", False),
        ("check", "fit", False), ("check", "error", True)]
    summary = summarise(read_class(tmp_path))
    assert summary.students[0].checks == {"a1_ridge_learner": {"fit": False, "error": True}}
    assert summary.students[0].last_failure.startswith("a1_ridge_learner/fit: ridge_fit: not written yet")


def test_who_is_stuck_is_measured_from_their_last_progress_not_their_last_failure(tmp_path):
    working = ProgressRecorder(tmp_path, "working")
    stuck = ProgressRecorder(tmp_path, "stuck")
    working.lesson("a1")
    stuck.lesson("a1")
    stuck.check("a1", "fit", True)
    later = dt.datetime.now(dt.timezone.utc) + dt.timedelta(minutes=20)
    # Failing the same check again and again is activity, not progress.
    for _ in range(3):
        stuck.check("a1", "error", False, "E: expected 2.4, got 5.8")
    summary = summarise(read_class(tmp_path), now=later, stuck_after_s=600)
    rows = {row.student: row for row in summary.students}
    assert rows[stuck.student].stuck and rows[working.student].stuck
    assert rows[stuck.student].last_failure == "a1/error: E: expected 2.4, got 5.8"
    working.record("episode", lesson="a5", error=1.25)
    summary = summarise(read_class(tmp_path), now=later - dt.timedelta(minutes=15), stuck_after_s=600)
    rows = {row.student: row for row in summary.students}
    assert not rows[working.student].stuck and rows[working.student].theta_errors == [1.25]
    assert rows[working.student].place == "a5"
    assert summary.at_place() == {"a1": [rows[stuck.student].student], "a5": [working.student]}


def test_the_summary_follows_each_students_errors_over_episodes(tmp_path):
    recorders = [ProgressRecorder(tmp_path, name) for name in ("a", "b", "c")]
    for number, recorder in enumerate(recorders):
        for error in (3.0 - number, 2.0 - number / 2, 1.0):
            recorder.record("episode", lesson="08_guided", theta_error=error, policy_risk=error / 2)
    summary = summarise(read_class(tmp_path))
    assert sorted(s.theta_errors for s in summary.students) == sorted([[3.0, 2.0, 1.0], [2.0, 1.5, 1.0],
                                                                        [1.0, 1.0, 1.0]])
    assert SKILLS  # the paper's registry is untouched by the recorder


def test_a_by_hand_check_refuses_the_package_and_names_the_direction_without_the_number():
    from mt_widgets import RidgeLearner
    from mt_widgets.classroom import references

    checks = ExerciseChecks("a1_ridge_learner", ProgressRecorder())
    rng = np.random.default_rng(0)
    Phi, U = rng.normal(size=(6, 4)), rng.normal(size=(6, 2))

    def by_numpy(Phi, U, lam):
        return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[1]), Phi.T @ U).T

    def helper(Phi, U, lam):
        return RidgeLearner(lam).fit(Phi, U).theta

    def through_a_helper(Phi, U, lam):      # the package hidden one call away
        return helper(Phi, U, lam)

    def transposed(Phi, U, lam):
        return by_numpy(Phi, U, lam).T

    checks.function("fit", by_numpy, [("a 6 x 4 Phi", (Phi, U, 0.3))], references.ridge_fit, by_hand=True)
    with pytest.raises(CheckFailed, match="uses the package's helper|uses the package's RidgeLearner"):
        checks.function("fit", through_a_helper, [("a 6 x 4 Phi", (Phi, U, 0.3))], references.ridge_fit, by_hand=True)
    with pytest.raises(CheckFailed, match=r"expected shape \(2, 4\), got shape \(4, 2\)"):
        checks.function("fit", transposed, [("x", (Phi, U, 0.3))], references.ridge_fit, by_hand=True)
    with pytest.raises(CheckFailed, match="times a constant factor") as failed:
        checks.close("fit", "theta_hat", 2 * by_numpy(Phi, U, 0.3), by_numpy(Phi, U, 0.3))
    expected = by_numpy(Phi, U, 0.3)
    assert not any(f"{v:.4g}" in str(failed.value) for v in expected.ravel())
    # In a notebook's namespace: a substitute stands in for the student's helper during the call only, so a
    # function is graded on its own; the package's objects there raise while a by-hand answer runs.
    notebook = {"np": np, "RidgeLearner": RidgeLearner}
    exec("def helper(Phi, U, lam):\n    return None\n"
         "def fit(Phi, U, lam):\n    return helper(Phi, U, lam)\n"
         "def sneaky(Phi, U, lam):\n    return globals()['RidgeLearner'](lam).fit(Phi, U)\n", notebook)
    checks.function("fit", notebook["fit"], [("x", (Phi, U, 0.3))], references.ridge_fit, by_hand=True,
                    substitute={"helper": by_numpy})
    assert notebook["helper"] is not by_numpy and notebook["RidgeLearner"] is RidgeLearner
    with pytest.raises(CheckFailed, match="uses the package's RidgeLearner"):
        checks.function("fit", notebook["sneaky"], [("x", (Phi, U, 0.3))], references.ridge_fit, by_hand=True)


def test_a_progress_file_written_before_theta_error_had_its_name_still_reads(tmp_path):
    # Before issue 42 an episode event held one `error`: every lesson that recorded episodes then taught
    # the ridge learner, whose `error` was Theta's error. A record written so is read as the theta_error.
    recorder = ProgressRecorder(tmp_path, "ada")
    recorder.record("episode", lesson="a5_teach_in_widget", skill="sim-point", error=0.75,
                    demonstrations=[[0.0, 1.0]], diverged=False, lam=0.01)
    # A learner without a Theta records its policy risk only: it joins no curve of Theta's errors.
    recorder.record("episode", lesson="14_learners", skill="uarm-point", theta_error=None, policy_risk=0.25)
    recorder.record("episode", lesson="08_one_full_episode", skill="sim-point", theta_error=0.5, policy_risk=0.1)
    row = summarise(read_class(tmp_path)).students[0]
    assert row.theta_errors == [0.75, 0.5] and row.episode_lessons == ["a5_teach_in_widget", "08_one_full_episode"]
    assert row.policy_risks == [0.25, 0.1]
    assert episode_errors({"kind": "episode", "error": 0.75}) == (0.75, None)
    assert episode_errors({"kind": "episode", "theta_error": None, "policy_risk": 0.25}) == (None, 0.25)
