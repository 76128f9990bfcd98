"""The instructor's checks: a class roster (the hub's) and a class folder (the course's progress)."""

from __future__ import annotations

from pathlib import Path

from mt_widgets.classroom.progress import pseudonym, read_class_meta
from mt_widgets.classroom.reader import read_class
from mt_widgets.classroom.roster import read_roster


def hub_check(roster_path) -> str:
    """What ``deploy/jupyterhub/class_admin.py check`` says of a roster: who is on it.

    Raises:
        RosterError: the roster cannot be read or an entry is wrong (every problem named).
    """
    roster = read_roster(Path(roster_path).expanduser())
    admins = ", ".join(entry.login for entry in roster.admins) or "none"
    return f"{roster_path}: {len(roster.students)} students, {len(roster.admins)} instructors/TAs ({admins})"


def course_check(class_folder, roster_path=None) -> tuple[str, bool]:
    """A class folder's state: its students' progress files and the problems met reading them; with
    a roster, which of its students have no progress file yet. Returns (report, everything fine).

    Raises:
        ClassFolderError: the folder is missing or holds no readable class.json.
    """
    meta = read_class_meta(class_folder)
    progress = read_class(class_folder)
    lines = [f"{progress.folder}: {len(progress.students)} students with a progress file"]
    lines += [f"problem: {problem}" for problem in progress.problems]
    fine = not progress.problems
    if roster_path is not None:
        roster = read_roster(Path(roster_path).expanduser())
        missing = [entry.login for entry in roster.students
                   if pseudonym(entry.login, meta["salt"]) not in progress.students]
        lines.append(f"roster {roster_path}: {len(roster.students)} students, "
                     f"{len(roster.students) - len(missing)} with a progress file")
        if missing:
            lines.append(f"no progress file yet: {', '.join(missing)}")
    return "\n".join(lines), fine
