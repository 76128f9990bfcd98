"""Grades back to the learning platform: nbgrader's totals as Assignment and Grade Services 2.0 scores.

Each nbgrader assignment is one line item of the course (``resourceId`` ``nbgrader:<name>``, tag
``mt-widgets``, its maximum the assignment's); each student's total (autograded and manually
graded, nbgrader's ``submission.score``) is posted as a score unless the platform's result for
them is already that score, so posting twice changes nothing. A plan is made first
(``grade_plan``): the dry run shows it, the real run posts what it says. A score still waiting
for manual grading is posted with ``gradingProgress`` ``PendingManual`` (the platform shows it
as not final). The CSV export (``nbgrader export``) stays for platforms without these services.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from lti_services import PlatformClient
from nbgrader.api import Gradebook


@dataclass(frozen=True)
class Grade:
    """One student's score of one assignment, as nbgrader's gradebook has it."""

    assignment: str
    login: str
    score: float
    max_score: float
    needs_manual_grade: bool = False


def read_gradebook(course_folder) -> list[Grade]:
    """Every submitted assignment's total (autograded and manually graded) in ``course_folder``'s gradebook.db."""
    database = Path(course_folder) / "gradebook.db"
    if not database.exists():
        raise FileNotFoundError(f"course_folder: no gradebook.db in {course_folder} (run nbgrader autograde first)")
    grades = []
    with Gradebook(f"sqlite:///{database}") as gradebook:
        for assignment in gradebook.assignments:
            for submission in assignment.submissions:
                grades.append(Grade(assignment.name, submission.student.id, float(submission.score),
                                    float(assignment.max_score), bool(submission.needs_manual_grade)))
    return grades


@dataclass(frozen=True)
class ScorePost:
    """A score the tool would post (``post`` True) or leaves because the platform has it already."""

    assignment: str
    login: str
    user_id: str
    score: float
    max_score: float
    post: bool
    why: str
    pending_manual: bool = False


def grade_plan(client: PlatformClient, lineitems_url: str, grades, platform_ids: dict,
               create: bool) -> tuple[list[str], list[ScorePost], dict]:
    """What posting ``grades`` would do: (line items to make, each score's post or reason to leave it,
    {assignment: line item}). With ``create`` the missing line items are made (a dry run makes none)."""
    items, made = {}, []
    for assignment in sorted({grade.assignment for grade in grades}):
        resource = f"nbgrader:{assignment}"
        found = [item for item in client.line_items(lineitems_url, resource) if item.get("resourceId") == resource]
        if found:
            items[assignment] = found[0]
        else:
            made.append(assignment)
            if create:
                maximum = max(grade.max_score for grade in grades if grade.assignment == assignment)
                items[assignment] = client.create_line_item(lineitems_url, assignment, maximum, resource)
    plan = []
    for assignment, item in items.items():
        results = {result.get("userId"): result for result in client.results(item["id"])}
        for grade in sorted((g for g in grades if g.assignment == assignment), key=lambda g: g.login):
            user_id = platform_ids.get(grade.login)
            if user_id is None:
                plan.append(ScorePost(assignment, grade.login, "", grade.score, grade.max_score, False,
                                      "not a platform user (no launch or sync gave their id)"))
                continue
            kept = results.get(user_id)
            same = (kept is not None and kept.get("resultScore") is not None and kept.get("resultMaximum")
                    and abs(kept["resultScore"] / kept["resultMaximum"] - grade.score / grade.max_score) < 1e-9)
            plan.append(ScorePost(assignment, grade.login, user_id, grade.score, grade.max_score, not same,
                                  "the platform has this score" if same else "new or changed",
                                  grade.needs_manual_grade))
    for assignment in made:
        if not create:
            for grade in sorted((g for g in grades if g.assignment == assignment), key=lambda g: g.login):
                user_id = platform_ids.get(grade.login, "")
                plan.append(ScorePost(assignment, grade.login, user_id, grade.score, grade.max_score, bool(user_id),
                                      "new line item" if user_id else "not a platform user", grade.needs_manual_grade))
    return made, plan, items


def score_message(post: ScorePost) -> dict:
    """The AGS score object of ``post`` (a timestamp with microseconds: no two posts of a user share one)."""
    return {"userId": post.user_id, "scoreGiven": post.score, "scoreMaximum": post.max_score,
            "timestamp": datetime.now(timezone.utc).isoformat(timespec="microseconds"),
            "activityProgress": "Completed",
            "gradingProgress": "PendingManual" if post.pending_manual else "FullyGraded"}
