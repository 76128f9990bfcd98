"""The instructor's class view in Voila and Chromium: a class of 12, one stuck, refreshed live."""

from __future__ import annotations

import datetime as dt
import json
import shutil

import pytest

from browser_support import REPO, local_page, voila
from mt_widgets.classroom import ProgressRecorder, create_class_folder, pseudonym
from mt_widgets.classroom.names import write_names

pytestmark = pytest.mark.browser


def _class_of_twelve(folder):
    """Twelve students at different places; eleven working now, one who stopped 30 minutes ago."""
    for number in range(11):
        recorder = ProgressRecorder(folder, f"student{number:02d}")
        recorder.lesson("a1_ridge_learner")
        recorder.check("a1_ridge_learner", "ridge-fit", True)
        recorder.check("a1_ridge_learner", "teaching-error", number % 3 != 0, "E: expected 0.316, got 0.1")
        for episode in range(1 + number % 4):
            recorder.record("episode", lesson="a5_teach_in_widget", skill="sim-point",
                            error=2.5 / (1 + episode) + 0.05 * number)
        if number % 2:
            recorder.lesson("a6_own_skill")
    salt = create_class_folder(folder)["salt"]
    stuck = pseudonym("student11", salt)
    old = (dt.datetime.now(dt.timezone.utc) - dt.timedelta(minutes=30)).isoformat(timespec="milliseconds")
    old = old.replace("+00:00", "Z")
    lines = [{"kind": "lesson", "lesson": "a3_risk_bound", "time": old, "student": stuck, "kernel": "k", "n": 0},
             {"kind": "check", "exercise": "a3_risk_bound", "check": "rho1", "passed": False, "time": old,
              "message": "rho1: expected 3.14, got 0.05", "student": stuck, "kernel": "k", "n": 1}]
    (folder / f"{stuck}.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    return stuck


def _salt(server):
    return json.loads((server.folder / "class.json").read_text())["salt"]


@pytest.fixture(scope="module")
def class_page(tmp_path_factory):
    root = tmp_path_factory.mktemp("class-view")
    (root / "notebooks").mkdir()
    shutil.copy(REPO / "notebooks" / "class_view.ipynb", root / "notebooks" / "class_view.ipynb")
    folder = root / "class"
    stuck = _class_of_twelve(folder)
    # The instructor's roster names 11 of the 12 (student05 is not on it); the names file lives outside the class.
    roster = root / "instructor" / "roster.csv"
    roster.parent.mkdir()
    roster.write_text("login,name,email,role\n" + "".join(f"student{n:02d},Student Number {n},,student\n"
                                                           for n in range(12) if n != 5))
    names = write_names(roster, folder, root / "instructor" / "names.json")
    server = voila(root, env={"MT_WIDGETS_CLASS_FOLDER": str(folder), "MT_WIDGETS_CLASS_REFRESH_S": "1",
                              "MT_WIDGETS_CLASS_STUCK_MIN": "10", "PYTHONPATH": str(REPO),
                              "MT_WIDGETS_CLASS_NAMES": str(names)})
    server.folder, server.stuck = folder, stuck
    yield server
    server.stop()


def test_the_class_view_shows_every_student_who_is_stuck_and_refreshes_live(browser, class_page, artifacts):
    context, page = local_page(browser, 1400, 1300)
    try:
        page.goto(class_page.url("/voila/render/class_view.ipynb"), timeout=90_000)
        page.wait_for_function("() => (document.querySelector('.class-status') || {}).textContent"
                               "?.includes('12 students, 1 stuck')", timeout=90_000)
        rows = page.locator("tr.student-row")
        assert rows.count() == 12
        first = rows.nth(0)
        assert first.get_attribute("data-student") == class_page.stuck  # stuck students come first
        assert "stuck" in first.inner_text() and "rho1: expected 3.14, got 0.05" in first.inner_text()
        # The roster's names beside the pseudonyms; a student not on the roster is said to be so.
        assert "Student Number 11" in first.inner_text()
        assert page.locator("td.student-name").count() == 11
        assert "not on the roster" in page.locator(f"tr[data-student='{pseudonym('student05', _salt(class_page))}']"
                                                   ).inner_text()
        # The class folder stays pseudonymous: no name and no login in any of its files.
        on_disk = "".join(p.read_text() for p in class_page.folder.glob("*.jsonl"))
        assert "Student Number" not in on_disk and "student05" not in on_disk
        page.wait_for_function("() => [...document.querySelectorAll('img')].filter(i => i.naturalWidth > 300)"
                               ".length >= 2", timeout=30_000)
        page.screenshot(path=artifacts("twelve"), full_page=True)

        # A thirteenth student starts: the page shows them without a reload.
        newcomer = ProgressRecorder(class_page.folder, "student12")
        newcomer.lesson("a1_ridge_learner")
        newcomer.record("episode", lesson="a5_teach_in_widget", skill="sim-point", error=0.42)
        page.wait_for_function("() => document.querySelector('.class-status').textContent"
                               ".includes('13 students')", timeout=30_000)
        # The two events are two writes: a refresh between them shows the lesson without the episode
        # (a row "working", no error yet), and the next refresh shows both.
        row = f"tr[data-student='{newcomer.student}']"
        page.wait_for_function("(row) => (document.querySelector(row)?.innerText.match(/0\\.420/g) || []).length >= 2",
                               arg=row, timeout=30_000)
        assert page.locator(row).inner_text().count("0.420") == 2
        page.screenshot(path=artifacts("thirteen"), full_page=True)
    finally:
        context.close()
