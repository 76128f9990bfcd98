"""Real names beside pseudonyms, for the instructor's eyes only.

A class folder holds pseudonyms (``s-<hash>`` of a login and the class's salt,
``mt_widgets/classroom/progress.py``), never names, and the students can read it. The roster
(``mt_widgets/classroom/roster.py``: login, name, e-mail, role) is the instructor's. This
module joins the two: ``write_names`` computes each roster student's pseudonym with the class's
salt and writes ``{pseudonym: name}`` to a file outside the class folder that only its owner
may read (mode 0600, created exclusively or replaced atomically); ``read_names`` reads it back
and refuses a file that others could read, so a names file copied carelessly is noticed rather
than used. The class view shows the names when ``MT_WIDGETS_CLASS_NAMES`` names such a file;
nothing on disk in the class folder changes.

Command line (the instructor, once per roster change)::

    python -m mt_widgets.classroom.names ROSTER.csv CLASS_FOLDER NAMES.json
"""

from __future__ import annotations

import argparse
import json
import os
import stat
import tempfile
from pathlib import Path

from .progress import pseudonym, read_class_meta
from .roster import Roster, read_roster

#: The environment variable the class view reads the names file from.
NAMES_ENV = "MT_WIDGETS_CLASS_NAMES"


class NamesFileError(ValueError):
    """A names file that is in the wrong place, readable by others, or not a names file."""


def class_names(roster: Roster, class_folder) -> dict[str, str]:
    """{pseudonym: name (or the login when the roster gives no name)} for the roster's students."""
    if not isinstance(roster, Roster):
        raise TypeError(f"roster: expected a Roster, got {type(roster).__name__}")
    salt = read_class_meta(class_folder)["salt"]
    return {pseudonym(entry.login, salt): entry.name or entry.login for entry in roster.students}


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(Path(folder).resolve())
        return True
    except ValueError:
        return False


def write_names(roster_path, class_folder, out) -> Path:
    """Writes the pseudonym-to-name mapping of the roster at ``roster_path`` to ``out`` (mode 0600).

    Raises:
        NamesFileError: ``out`` is inside the class folder (which the students can read).
    """
    out = Path(out)
    if _inside(out, Path(class_folder)):
        raise NamesFileError(f"out: expected a file outside the class folder {class_folder} (students can read "
                             f"it), got {out}")
    names = class_names(read_roster(roster_path), class_folder)
    out.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=out.parent, prefix=".names-", suffix=".tmp")
    try:
        os.fchmod(descriptor, 0o600)
        with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
            json.dump({"format": 1, "names": names}, handle, indent=1, sort_keys=True)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, out)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return out


def read_names(path) -> dict[str, str]:
    """The {pseudonym: name} of a names file that only its owner can read.

    Raises:
        NamesFileError: the file is readable or writable by its group or others, or not a names file.
    """
    path = Path(path)
    mode = path.stat().st_mode
    if mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise NamesFileError(f"{path}: others may read it (mode {stat.filemode(mode)}); a names file must be "
                             f"readable by its owner only: chmod 600 {path}")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        names = data["names"]
    except (ValueError, KeyError, TypeError):
        raise NamesFileError(f"{path}: not a names file (write one with python -m mt_widgets.classroom.names)") \
            from None
    if not isinstance(names, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in names.items()):
        raise NamesFileError(f"{path}: not a names file (its 'names' is not a mapping of text to text)")
    return dict(names)


def names_from_env() -> dict[str, str]:
    """The names of ``$MT_WIDGETS_CLASS_NAMES``, or {} when it is unset."""
    value = os.environ.get(NAMES_ENV, "").strip()
    return read_names(Path(value).expanduser()) if value else {}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mt_widgets.classroom.names", description=__doc__.split("\n")[0])
    parser.add_argument("roster", help="the class roster CSV (login,name,email,role)")
    parser.add_argument("class_folder", help="the class folder (its class.json holds the salt)")
    parser.add_argument("out", help="the names file to write, outside the class folder")
    args = parser.parse_args(argv)
    out = write_names(args.roster, args.class_folder, args.out)
    print(f"wrote {out} (mode 600); set {NAMES_ENV}={out} for the class view")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
