"""The class progress recorder: one append-only JSON-lines file per student in a class folder.

An instructor sets the class folder (``MT_WIDGETS_CLASS_FOLDER``, or the ``class_folder``
argument); with none set, nothing is written anywhere. In the folder:

- ``class.json``: the class's salt for pseudonyms, created once (exclusive creation) by the
  first recorder or by ``create_class_folder``; a student's file is named by a hash of their
  login and this salt, so the folder never holds a login name.
- ``<pseudonym>.jsonl``: that student's progress, one JSON object a line: lessons opened,
  exercise checks run (passed or not, with the words shown), demonstrations and finished
  episodes (with theta_error, Theta's error where the learner has a Theta, and policy_risk).
- ``.locks/``: one lock file per student (``fcntl.flock``, released when its process dies).

Crash safety comes from the study log's own mechanisms (``mt_widgets/study/log.py``: its lock,
its all-bytes write, fsync of the file and of a new file's folder, ISO times, JSON
conversion), not copies of them. What differs is the concurrency rule: a study log refuses a
stale session, while a student may have two kernels open (a tutorial and an exercise) and both
must be kept. So each event is one line written under the student's lock, after ending a line
that a killed writer left torn, which that event then records (``repaired_torn_bytes``);
events carry the writing kernel's id and that kernel's own counter instead of a global
sequence number.
"""

from __future__ import annotations

import getpass
import hashlib
import json
import os
import secrets
from collections.abc import Callable
from pathlib import Path

from mt_widgets.study import jsonl
from mt_widgets.study.jsonl import Lock, LogError, append_line, encode
from mt_widgets.study.log import LOCK_FOLDER, LogFolderError, check_folder_writable, to_jsonable, utc_now

#: The environment variable an instructor (or a hub's spawner) sets to the class folder.
CLASS_FOLDER_ENV = "MT_WIDGETS_CLASS_FOLDER"
#: The environment variable naming the student; else JupyterHub's user, else the login.
STUDENT_ENV = "MT_WIDGETS_STUDENT"
CLASS_FILE = "class.json"
#: Seconds a writer waits for the other kernel of the same student to finish its line.
LOCK_TIMEOUT_S = 10.0


class ClassFolderError(LogError):
    """A class folder that cannot be read or written as asked."""


def class_folder_from_env() -> Path | None:
    """The class folder the instructor set in ``MT_WIDGETS_CLASS_FOLDER``, or None."""
    value = os.environ.get(CLASS_FOLDER_ENV, "").strip()
    return Path(value).expanduser() if value else None


def student_name() -> str:
    """Who is working: ``MT_WIDGETS_STUDENT``, else ``JUPYTERHUB_USER``, else the login name."""
    for variable in (STUDENT_ENV, "JUPYTERHUB_USER"):
        value = os.environ.get(variable, "").strip()
        if value:
            return value
    return getpass.getuser()


def pseudonym(name: str, salt: str) -> str:
    """A stable pseudonym for ``name`` in the class whose salt is ``salt`` (e.g. 's-3f9a0c1b7d2e')."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    if not isinstance(salt, str) or not salt:
        raise ValueError(f"salt: expected a non-empty string, got {salt!r}")
    return "s-" + hashlib.sha256(f"{salt}:{name}".encode()).hexdigest()[:12]


def _writable(folder) -> Path:
    try:
        return check_folder_writable(folder)
    except LogFolderError as error:
        raise ClassFolderError(str(error).replace("log folder", "class folder", 1)) from None


def create_class_folder(folder) -> dict:
    """Makes ``folder`` a class folder (idempotent) and returns its ``class.json`` data.

    Raises:
        ClassFolderError: the folder cannot be created or written, or its class.json is damaged.
    """
    folder = _writable(folder)
    path = folder / CLASS_FILE
    meta = {"salt": secrets.token_hex(16), "created_at": utc_now(), "format": 1}
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
    except FileExistsError:
        return read_class_meta(folder)
    try:
        jsonl.write_all(fd, json.dumps(meta).encode())
        os.fsync(fd)
    finally:
        os.close(fd)
    jsonl.fsync_folder(folder)
    return meta


def read_class_meta(folder) -> dict:
    """The class folder's ``class.json``.

    Raises:
        ClassFolderError: naming the folder, when it is missing, unreadable or damaged.
    """
    path = Path(folder).expanduser() / CLASS_FILE
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ClassFolderError(f"class folder {path.parent}: holds no {CLASS_FILE}; is it a class folder? "
                               f"(create it with create_class_folder)") from None
    except OSError as error:
        raise ClassFolderError(f"class folder {path.parent}: {CLASS_FILE} cannot be read "
                               f"({error.strerror or error})") from None
    except ValueError:
        raise ClassFolderError(f"{path}: not JSON; the class file is damaged") from None
    if not isinstance(meta, dict) or not isinstance(meta.get("salt"), str) or not meta["salt"]:
        raise ClassFolderError(f"{path}: expected an object with a 'salt' string, got {meta!r:.80}")
    return meta


class ProgressRecorder:
    """Writes one student's progress to the class folder; writes nothing without a class folder.

    Args:
        class_folder: the class folder; None uses ``MT_WIDGETS_CLASS_FOLDER`` and, when that is
            unset too, the recorder is disabled (every method is a no-op that returns None).
        student: the student's name (never written: only its pseudonym is); default
            ``student_name()``.

    Raises:
        ClassFolderError: the class folder cannot be created, written or read.
    """

    def __init__(self, class_folder=None, student: str | None = None):
        folder = class_folder_from_env() if class_folder is None else Path(class_folder).expanduser()
        if student is not None and (not isinstance(student, str) or not student.strip()):
            raise ValueError(f"student: expected a non-empty name, got {student!r}")
        self.folder: Path | None = None
        self.path: Path | None = None
        self.student: str | None = None
        self.kernel = secrets.token_hex(4)
        self.count = 0
        if folder is None:
            return
        meta = create_class_folder(folder)
        self.folder = Path(folder).expanduser()
        self.student = pseudonym((student or student_name()).strip(), meta["salt"])
        self.path = self.folder / f"{self.student}.jsonl"

    @property
    def enabled(self) -> bool:
        """True when a class folder is set (events are written)."""
        return self.path is not None

    def __repr__(self) -> str:
        return f"ProgressRecorder({self.path})" if self.enabled else "ProgressRecorder(disabled: no class folder)"

    # -- writing -------------------------------------------------------------------------------------
    def record(self, kind: str, **fields) -> dict | None:
        """Appends one event and returns once it is on disk; None (nothing written) when disabled.

        Args:
            kind: "lesson", "check", "demonstration", "episode" or your own word.
            **fields: the event's data (numpy arrays become lists).

        Raises:
            ClassFolderError: the line could not be written (the folder went away, the disk is full).
        """
        if not isinstance(kind, str) or not kind:
            raise ValueError(f"kind: expected a non-empty string, got {kind!r}")
        if not self.enabled:
            return None
        event = {"kind": kind, "time": utc_now(), "student": self.student, "kernel": self.kernel, "n": self.count}
        event.update(to_jsonable(fields))
        try:
            with Lock(self.folder / LOCK_FOLDER / f"{self.student}.lock", f"student {self.student!r}",
                      LOCK_TIMEOUT_S):
                append_line(self.path, lambda torn: encode(_repairing(event, torn)))
        except LogError as error:  # the other kernel held the lock for too long
            raise ClassFolderError(f"class folder {self.folder}: {error}") from None
        except OSError as error:
            raise ClassFolderError(f"class folder {self.folder}: cannot write {self.path.name} "
                                   f"({error.strerror or error}); this progress event was not recorded") from None
        self.count += 1
        return event

    def lesson(self, lesson: str, step: str | None = None) -> dict | None:
        """Records that the student opened ``lesson`` (a tutorial or an exercise), at ``step``."""
        return self.record("lesson", lesson=_name("lesson", lesson), step=step)

    def check(self, exercise: str, check: str, passed: bool, message: str | None = None) -> dict | None:
        """Records one run of an exercise's check, with the words shown to the student."""
        if not isinstance(passed, bool):
            raise TypeError(f"passed: expected a bool, got {type(passed).__name__}")
        return self.record("check", exercise=_name("exercise", exercise), check=_name("check", check),
                           passed=passed, message=message)

    # -- following an episode widget ------------------------------------------------------------------
    def attach(self, episode, lesson: str) -> Callable[[], None]:
        """Records the demonstrations and the finished episodes of an ``EpisodeWidget``.

        Subscribes through the widget's public callbacks ``on_demonstration`` and ``on_finished``;
        an error writing the event reaches the widget, which then keeps the arrow pending (so
        nothing is counted that is not recorded). Does nothing when disabled.

        Args:
            episode: an ``mt_widgets.widgets.EpisodeWidget`` (anything with those two methods).
            lesson: the tutorial or exercise the episode belongs to.

        Returns:
            A function that unsubscribes.
        """
        lesson = _name("lesson", lesson)
        for method in ("on_demonstration", "on_finished"):
            if not callable(getattr(episode, method, None)):
                raise TypeError(f"episode: expected an EpisodeWidget (with {method}), got {type(episode).__name__}")
        if not self.enabled:
            return lambda: None

        def demonstrated(record):
            self.record("demonstration", lesson=lesson, episode_index=record.episode_index, index=record.index,
                        action=record.action, optimal_action=record.optimal_action,
                        guidance_shown=record.guidance_shown, method=record.method)

        def finished(result):
            self.record("episode", lesson=lesson, skill=result.skill_key,
                        theta_error=result.theta_error, policy_risk=result.policy_risk,
                        demonstrations=result.demonstrations, diverged=result.diverged, lam=result.lam)

        episode.on_demonstration(demonstrated)
        episode.on_finished(finished)

        def detach():
            episode.on_demonstration(demonstrated, remove=True)
            episode.on_finished(finished, remove=True)

        return detach


def _repairing(event: dict, torn: int) -> dict:
    """``event``, saying (in place) that it ends a torn line of ``torn`` bytes a killed writer left."""
    if torn:
        event["repaired_torn_bytes"] = torn
    return event


def _name(argument: str, value) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{argument}: expected a non-empty name, got {value!r}")
    return value.strip()
