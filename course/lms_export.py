"""Writes the course's grades as a gradebook CSV an LMS imports (Canvas or Moodle).

nbgrader's own export (``nbgrader export --to grades.csv``) has one row per student and
assignment; an LMS wants one row per student and one column per assignment. This reads the
gradebook (``gradebook.db``, manual grades included) and writes that table, with each
assignment's maximum in its column name, a total, and the students' names and e-mails from the
class roster (``mt_widgets/classroom/roster.py``: login,name,email,role) when one is given.
nbgrader's student ids are the hub logins.

    python lms_export.py --to lms-gradebook.csv                      # from this folder's gradebook.db
    python lms_export.py --gradebook gradebook.db --roster ~/private/roster.csv --format moodle --to grades.csv

Canvas: columns ``Student, ID, SIS Login ID, Section``, then one per assignment ("Grades >
Import"); Moodle: ``First name, Last name, Username, Email address``, then one per assignment
("Grades > Import > CSV file", mapping Username). A student with no submission gets an empty
cell (not 0), so the LMS marks it missing.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from nbgrader.api import Gradebook

from mt_widgets.classroom.roster import read_roster

FORMATS = ("canvas", "moodle")


def gradebook_table(gradebook_path, roster_path=None, lms: str = "canvas") -> list[list[str]]:
    """The rows (header first) of the LMS gradebook for the gradebook at ``gradebook_path``."""
    if lms not in FORMATS:
        raise ValueError(f"lms: expected one of {', '.join(FORMATS)}, got {lms!r}")
    if not Path(gradebook_path).is_file():
        raise FileNotFoundError(f"gradebook: {gradebook_path} does not exist (run nbgrader autograde first)")
    people = {e.login: e for e in read_roster(roster_path).students} if roster_path else {}
    with Gradebook(f"sqlite:///{Path(gradebook_path).resolve()}") as gradebook:
        assignments = sorted(gradebook.assignments, key=lambda a: a.name)
        maxima = {a.name: a.max_score for a in assignments}
        scores: dict[str, dict[str, float]] = {}
        for assignment in assignments:
            for submission in gradebook.assignment_submissions(assignment.name):
                scores.setdefault(submission.student.id, {})[assignment.name] = submission.score
        students = sorted({s.id for s in gradebook.students} | set(people))
    columns = [f"{name} ({maxima[name]:g})" for name in maxima]
    total = f"Total ({sum(maxima.values()):g})"
    if lms == "canvas":
        header = ["Student", "ID", "SIS Login ID", "Section", *columns, total]
    else:
        header = ["First name", "Last name", "Username", "Email address", *columns, total]
    rows = [header]
    for login in students:
        entry = people.get(login)
        name = entry.name if entry and entry.name else login
        got = scores.get(login, {})
        cells = [f"{got[a]:g}" if a in got else "" for a in maxima]
        total_cell = f"{sum(got.values()):g}" if got else ""
        if lms == "canvas":
            rows.append([name, login, login, "", *cells, total_cell])
        else:
            first, _, last = name.partition(" ")
            rows.append([first, last, login, entry.email if entry else "", *cells, total_cell])
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--gradebook", default=str(Path(__file__).resolve().parent / "gradebook.db"))
    parser.add_argument("--roster", default=None, help="the class roster CSV (names and e-mails)")
    parser.add_argument("--format", choices=FORMATS, default="canvas")
    parser.add_argument("--to", required=True, help="the CSV file to write")
    args = parser.parse_args(argv)
    rows = gradebook_table(args.gradebook, args.roster, args.format)
    with open(args.to, "w", newline="", encoding="utf-8") as handle:
        csv.writer(handle).writerows(rows)
    print(f"wrote {args.to}: {len(rows) - 1} students, {len(rows[0]) - 5} assignments ({args.format})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
