"""Grades back to the learning platform (deploy/jupyterhub/lti_admin.py grades, lti_grades.py) against the test
platform: nbgrader's totals as AGS line items and scores, read back from the platform; a dry run posts nothing;
a second run posts nothing; a changed grade is posted again alone.

Slow (about 5 s): nbgrader's gradebook (its import and its database migrations).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from .course_support import REPO
from .lti_platform import LTIPlatform, Member

sys.path.insert(0, str(REPO / "deploy" / "jupyterhub"))
import lti_admin  # noqa: E402
from lti_services import ToolKey, login_for, write_private_json  # noqa: E402
from nbgrader.api import Gradebook  # noqa: E402

pytestmark = pytest.mark.slow

ANN, BO = "sub-ann", "sub-bo"


def _gradebook(course: Path, ann: str, bo: str, bo_manual: float | None) -> None:
    """a1 (10 points: a 4-point autograded cell, a 6-point manually graded one) for Ann and Bo."""
    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        if not gradebook.assignments:
            gradebook.add_assignment("a1")
            gradebook.add_notebook("ridge", "a1")
            gradebook.add_grade_cell("fit", "ridge", "a1", max_score=4, cell_type="code")
            gradebook.add_grade_cell("why", "ridge", "a1", max_score=6, cell_type="markdown")
            for login in (ann, bo):
                gradebook.add_student(login)
                gradebook.add_submission("a1", login)
        for login, auto, manual in ((ann, 4, 3.5), (bo, 2, bo_manual)):
            fit, why = (gradebook.find_grade(cell, "ridge", "a1", login) for cell in ("fit", "why"))
            fit.auto_score, fit.needs_manual_grade = auto, False
            why.manual_score, why.needs_manual_grade = manual, manual is None
        gradebook.db.commit()


def test_grades_are_posted_once_and_read_back_from_the_platforms_line_item(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PATH", f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")  # nbgrader's alembic
    state, course = tmp_path / "state", tmp_path / "course"
    state.mkdir()
    course.mkdir()
    key = ToolKey.load_or_create(state / "lti-tool-key.pem")
    with LTIPlatform() as platform:
        platform.enrol(Member(ANN, "Ann Lee"))
        platform.enrol(Member(BO, "Bo Chen"))
        tool = platform.register_tool(["https://hub/hub/lti13/oauth_callback"], "https://hub/", jwks=key.jwks())
        ann, bo = login_for(platform.url, ANN), login_for(platform.url, BO)
        write_private_json(state / "lti-platform-ids.json", {ann: ANN, bo: BO})
        write_private_json(state / "lti-services.json", {"lineitems_url": platform.lineitems_url})
        roster = tmp_path / "roster.csv"
        roster.write_text(f"login,role\n{ann},student\n{bo},student\n")
        _gradebook(course, ann, bo, bo_manual=None)
        command = ["--roster", str(roster), "--state", str(state), "--issuer", platform.url,
                   "--client-id", tool.client_id, "--token-url", platform.token_url, "grades", "--course", str(course)]

        assert lti_admin.main([*command, "--dry-run"]) == 0
        dry = capsys.readouterr().out
        assert "would make line item 'a1'" in dry and f"would post a1 {ann}: 7.5/10" in dry
        assert platform.line_items() == [] and platform.scores_received == []

        assert lti_admin.main(command) == 0
        [item] = platform.line_items()
        assert (item["label"], item["scoreMaximum"], item["resourceId"], item["tag"]) == (
            "a1", 10.0, "nbgrader:a1", "mt-widgets")
        ann_result, bo_result = platform.result_of(item["id"], ANN), platform.result_of(item["id"], BO)
        assert (ann_result["scoreGiven"], ann_result["scoreMaximum"], ann_result["gradingProgress"]) == (
            7.5, 10.0, "FullyGraded")
        # Bo's written answer is not graded yet: 2 of 10 so far, which the platform shows as not final.
        assert (bo_result["scoreGiven"], bo_result["gradingProgress"]) == (2.0, "PendingManual")
        assert "2 scores to post, 2 posted" in capsys.readouterr().out

        # Twice changes nothing: the platform has every score, nothing is sent.
        received = len(platform.scores_received)
        assert lti_admin.main(command) == 0
        assert len(platform.scores_received) == received and len(platform.line_items()) == 1
        assert "0 scores to post, 0 posted" in capsys.readouterr().out

        # Bo's answer graded: only his new total goes.
        _gradebook(course, ann, bo, bo_manual=5.0)
        assert lti_admin.main(command) == 0
        assert [score["userId"] for score in platform.scores_received[received:]] == [BO]
        bo_result = platform.result_of(item["id"], BO)
        assert (bo_result["scoreGiven"], bo_result["gradingProgress"]) == (7.0, "FullyGraded")
    assert json.loads((state / "lti-platform-ids.json").read_text()) == {ann: ANN, bo: BO}
