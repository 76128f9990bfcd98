"""Reading a class folder: every student's progress, tolerating what a crash or a race leaves.

Nothing a student's file holds stops the instructor's view: a line torn by a killed kernel
(ended by the next event, which records the repair) is skipped and counted, a file that
cannot be read is reported by name while every other student is read, and only a class
folder that cannot be read at all raises.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mt_widgets.study.jsonl import read_jsonl

from .progress import CLASS_FILE, ClassFolderError, read_class_meta


@dataclass
class StudentProgress:
    """One student's events as read.

    Attributes:
        student: the pseudonym (the file's name without ``.jsonl``).
        events: the events in file order.
        torn_lines: numbers of lines that did not parse (a killed writer's torn line).
        torn_tail: bytes of an unfinished last line (a writer still writing, or killed).
    """

    student: str
    events: list[dict] = field(default_factory=list)
    torn_lines: list[int] = field(default_factory=list)
    torn_tail: int = 0


@dataclass
class ClassProgress:
    """A class folder as read: the students and the problems met on the way."""

    folder: Path
    students: dict[str, StudentProgress]
    problems: list[str]


def read_student(path) -> StudentProgress:
    """Reads one student's ``<pseudonym>.jsonl``; unparsable lines are skipped and listed.

    Raises:
        OSError: the file cannot be read (``read_class`` reports it and goes on).
    """
    path = Path(path)
    contents = read_jsonl(path)
    progress = StudentProgress(path.stem)
    for line in contents.lines:
        if line.blank:
            continue
        if line.value is None or "kind" not in line.value:
            progress.torn_lines.append(line.number)
            continue
        progress.events.append(line.value)
    # What follows the last newline is a line still being written (or killed), or an event
    # complete but for its newline.
    if contents.tail is not None:
        if contents.tail.value is not None and "kind" in contents.tail.value:
            progress.events.append(contents.tail.value)
        else:
            progress.torn_tail = len(contents.tail.raw)
    return progress


def read_class(folder) -> ClassProgress:
    """Reads every student's file in a class folder.

    Raises:
        ClassFolderError: the folder is missing, not a folder, not readable, or holds no class.json.
    """
    folder = Path(folder).expanduser()
    if not folder.exists():
        raise ClassFolderError(f"class folder {folder}: does not exist; check MT_WIDGETS_CLASS_FOLDER")
    if not folder.is_dir():
        raise ClassFolderError(f"class folder {folder}: expected a folder, found a file")
    try:
        paths = sorted(folder.glob("*.jsonl"))
    except OSError as error:
        raise ClassFolderError(f"class folder {folder}: cannot be listed ({error.strerror or error})") from None
    if not (folder / CLASS_FILE).exists() and not paths:
        try:
            next(folder.iterdir(), None)
        except OSError as error:
            raise ClassFolderError(f"class folder {folder}: cannot be read ({error.strerror or error})") from None
    read_class_meta(folder)
    students: dict[str, StudentProgress] = {}
    problems: list[str] = []
    for path in paths:
        try:
            student = read_student(path)
        except OSError as error:
            problems.append(f"{path.name}: cannot be read ({error.strerror or error}); the other students are shown")
            continue
        if student.torn_lines:
            problems.append(f"{path.name}: skipped {len(student.torn_lines)} torn line(s) "
                            f"(line {', '.join(map(str, student.torn_lines))})")
        students[student.student] = student
    return ClassProgress(folder, students, problems)
