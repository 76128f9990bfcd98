"""A class roster: who may log in to the class hub, and as what.

The instructor keeps the class list as a CSV file with a header row. Columns:

- ``login`` (required): the person's login, which the hub also uses as their system user
  name, so it must be safe as a POSIX user name (``^[a-z_][a-z0-9_-]{0,31}$``) and not a
  system account's (``root``, ``daemon``, ``nobody``, ``admin``...);
- ``name``, ``email`` (optional): for the instructors' eyes only, never shown to students;
- ``role`` (optional): ``student`` (the default when empty or absent), ``ta`` or
  ``instructor``; TAs and instructors are the hub's admins.

For example::

    login,name,email,role
    instructor,Dana Scully,dana@example.edu,instructor
    ann,Ann Lee,ann@example.edu,
    bo,Bo Chen,,student

Reading is all-or-nothing: one bad line refuses the whole roster (nothing half-applied), and
the ``RosterError`` lists every bad line with its number and reason, so the instructor fixes
the file once. A ``Roster`` is immutable: ``with_entry`` and ``without`` give a new one, and
``write_roster`` replaces the file atomically (a temporary file renamed over it, mode 0600,
since it holds names and e-mails).

This module is plain standard-library Python and touches no file but the roster's: creating
system users and accounts from it is the hub's business (``deploy/jupyterhub/class_admin.py``).
"""

from __future__ import annotations

import csv
import io
import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

#: The columns a roster may have, in the order ``write_roster`` writes them.
COLUMNS = ("login", "name", "email", "role")
#: The roles a roster line may give; the first is the default.
ROLES = ("student", "ta", "instructor")
#: Roles that make a person a hub admin.
ADMIN_ROLES = frozenset({"ta", "instructor"})
#: A login the hub can create as a system user everywhere (the portable subset of useradd's
#: rule: lower case, no leading digit or dash, at most 32 characters).
LOGIN_PATTERN = re.compile(r"[a-z_][a-z0-9_-]{0,31}")
#: System and service accounts (Debian's base-passwd and common daemons) and names that would
#: mislead: a student must never become one of them, or be taken for one.
RESERVED_LOGINS = frozenset({
    "root", "daemon", "bin", "sys", "sync", "games", "man", "lp", "mail", "news", "uucp",
    "proxy", "www-data", "backup", "list", "irc", "gnats", "nobody", "nogroup", "_apt",
    "systemd-network", "systemd-resolve", "systemd-timesync", "systemd-journal",
    "messagebus", "sshd", "syslog", "uuidd", "polkitd", "avahi", "ntp", "postfix", "dnsmasq",
    "admin", "administrator", "adm", "wheel", "sudo", "staff", "users", "operator", "shadow",
    "utmp", "tty", "disk", "kmem", "dialout", "cdrom", "floppy", "audio", "video", "plugdev",
    "netdev", "input", "render", "kvm", "src", "voice", "tape", "fax", "sasl", "crontab",
    "docker", "lxd", "postgres", "mysql", "redis", "nginx", "apache", "httpd", "ftp", "git",
    "jupyter", "jupyterhub", "guest", "test", "user", "nbgrader",
})
#: A plausible e-mail address: something, one '@', a domain with a dot, no spaces.
_EMAIL_PATTERN = re.compile(r"[^@\s,;<>]+@[^@\s,;<>]+\.[^@\s,;<>]+")


class RosterError(ValueError):
    """A roster refused whole; ``problems`` lists every bad line as (line number, reason)."""

    def __init__(self, source: str, problems):
        self.source = str(source)
        self.problems = tuple(problems)
        lines = "\n".join(f"  {self.source}, line {line}: {reason}" for line, reason in self.problems)
        count = len(self.problems)
        super().__init__(
            f"roster {self.source} refused, nothing applied ({count} bad line{'s' if count != 1 else ''}):\n{lines}")


def login_problem(login) -> str | None:
    """Why ``login`` cannot be a roster login, or None when it can."""
    if not isinstance(login, str):
        return f"login must be a string, got {type(login).__name__}"
    if not login:
        return "missing login"
    if login in RESERVED_LOGINS:
        return f"login {login!r} is reserved for a system account"
    if not LOGIN_PATTERN.fullmatch(login):
        hint = " (logins are lower case)" if LOGIN_PATTERN.fullmatch(login.lower()) else ""
        return (f"unsafe login {login!r}: a login must be usable as a system user name, "
                f"1-32 characters of a-z, 0-9, '_' and '-', not starting with a digit or '-'{hint}")
    return None


def _text_problem(column: str, value) -> str | None:
    if not isinstance(value, str):
        return f"{column} must be a string, got {type(value).__name__}"
    if any(ord(c) < 32 or ord(c) == 127 for c in value):
        return f"{column} {value!r} holds a control character"
    if value != value.strip():
        return f"{column} {value!r} has leading or trailing spaces"
    return None


def _entry_problems(login, name, email, role) -> list[str]:
    problems = [p for p in (login_problem(login), _text_problem("name", name), _text_problem("email", email))
                if p]
    if isinstance(email, str) and email and not _EMAIL_PATTERN.fullmatch(email):
        problems.append(f"email {email!r} is not an e-mail address (expected name@domain)")
    if role not in ROLES:
        problems.append(f"unknown role {role!r}: expected one of {', '.join(ROLES)}")
    return problems


@dataclass(frozen=True)
class RosterEntry:
    """One person of the class: their ``login``, and for instructors their ``name`` and ``email``.

    Args:
        login: the hub login and system user name (see ``LOGIN_PATTERN``, ``RESERVED_LOGINS``).
        name: the person's name, '' when not given.
        email: their e-mail address, '' when not given.
        role: 'student', 'ta' or 'instructor'.
    """

    login: str
    name: str = ""
    email: str = ""
    role: str = "student"

    def __post_init__(self):
        problems = _entry_problems(self.login, self.name, self.email, self.role)
        if problems:
            raise ValueError("RosterEntry: " + "; ".join(problems))

    @property
    def is_admin(self) -> bool:
        """True for instructors and TAs, whom the hub makes admins."""
        return self.role in ADMIN_ROLES


@dataclass(frozen=True)
class Roster:
    """The class list: entries in file order, one per login."""

    entries: tuple[RosterEntry, ...] = ()

    def __post_init__(self):
        entries = tuple(self.entries)
        for entry in entries:
            if not isinstance(entry, RosterEntry):
                raise TypeError(f"entries: expected RosterEntry items, got {type(entry).__name__}")
        seen = set()
        for entry in entries:
            if entry.login in seen:
                raise ValueError(f"entries: login {entry.login!r} appears twice")
            seen.add(entry.login)
        object.__setattr__(self, "entries", entries)

    @property
    def students(self) -> tuple[RosterEntry, ...]:
        """The entries whose role is 'student'."""
        return tuple(e for e in self.entries if e.role == "student")

    @property
    def admins(self) -> tuple[RosterEntry, ...]:
        """The instructors and TAs."""
        return tuple(e for e in self.entries if e.is_admin)

    @property
    def logins(self) -> tuple[str, ...]:
        """Every login, in file order."""
        return tuple(e.login for e in self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def __iter__(self):
        return iter(self.entries)

    def __contains__(self, login) -> bool:
        return any(e.login == login for e in self.entries)

    def entry(self, login: str) -> RosterEntry:
        """The entry of ``login``; KeyError when the roster has none."""
        for entry in self.entries:
            if entry.login == login:
                return entry
        raise KeyError(f"login {login!r} is not on the roster ({len(self.entries)} logins)")

    def with_entry(self, entry: RosterEntry) -> Roster:
        """This roster with ``entry`` added at the end, or in place of the entry of the same login."""
        if not isinstance(entry, RosterEntry):
            raise TypeError(f"entry: expected a RosterEntry, got {type(entry).__name__}")
        if entry.login in self:
            return Roster(tuple(entry if e.login == entry.login else e for e in self.entries))
        return Roster(self.entries + (entry,))

    def without(self, login: str) -> Roster:
        """This roster without ``login``'s entry; KeyError when the roster has none."""
        self.entry(login)
        return Roster(tuple(e for e in self.entries if e.login != login))


def parse_roster(text: str, source: str = "<roster>") -> Roster:
    """The roster in CSV ``text``; RosterError listing every bad line (named by ``source``)."""
    if not isinstance(text, str):
        raise TypeError(f"text: expected the roster's CSV text as a str, got {type(text).__name__}")
    text = text.removeprefix("\ufeff")  # spreadsheet programs start UTF-8 CSV with a byte-order mark
    # One physical line at a time, so each problem has its own line number and a broken
    # quote cannot swallow the lines after it: no roster field legitimately holds a line break.
    lines = text.splitlines()
    problems: list[tuple[int, str]] = []
    numbered = [(number, line) for number, line in enumerate(lines, start=1) if line.strip()]
    if not numbered:
        raise RosterError(source, [(1, "empty roster: expected a header row naming the columns "
                                       f"({', '.join(COLUMNS)}; login is required)")])
    header_line, header_text = numbered[0]
    header = _split(header_text)
    if header is None:
        raise RosterError(source, [(header_line, "malformed header row")])
    columns = [c.strip().lower() for c in header]
    for column in columns:
        if column not in COLUMNS:
            problems.append((header_line, f"unknown column {column!r}: expected some of {', '.join(COLUMNS)}"))
    for column in sorted({c for c in columns if columns.count(c) > 1}):
        problems.append((header_line, f"column {column!r} appears twice"))
    if "login" not in columns:
        problems.append((header_line, "the header has no 'login' column"))
    if problems:
        raise RosterError(source, problems)

    entries = []
    first_line_of: dict[str, int] = {}
    for number, line in numbered[1:]:
        fields = _split(line)
        if fields is None:
            problems.append((number, "malformed line (a quote is not closed, or text follows a closing quote)"))
            continue
        if len(fields) != len(columns):
            problems.append((number, f"wrong number of fields: {len(fields)} where the header has "
                                     f"{len(columns)} ({', '.join(columns)})"))
            continue
        values = {column: value.strip() for column, value in zip(columns, fields)}
        login = values.get("login", "")
        # Role words are matched regardless of case ("TA"); a word that is no role is shown as typed.
        typed_role = values.get("role", "")
        role = typed_role.lower() if typed_role.lower() in ROLES else typed_role or ROLES[0]
        line_problems = _entry_problems(login, values.get("name", ""), values.get("email", ""), role)
        if login in first_line_of:
            line_problems.append(f"duplicate login {login!r} (first on line {first_line_of[login]})")
        elif login:
            first_line_of[login] = number
        if line_problems:
            problems.extend((number, p) for p in line_problems)
            continue
        entries.append(RosterEntry(login, values.get("name", ""), values.get("email", ""), role))
    if problems:
        raise RosterError(source, problems)
    return Roster(tuple(entries))


def _split(line: str) -> list[str] | None:
    try:
        return next(csv.reader([line], strict=True))
    except csv.Error:
        return None


def read_roster(path) -> Roster:
    """The roster in the CSV file at ``path`` (UTF-8); RosterError naming the file and its bad lines."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path (str or os.PathLike), got {type(path).__name__}")
    data = Path(path).read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise RosterError(str(path), [(line, "not UTF-8 text (save the CSV as UTF-8)")]) from None
    return parse_roster(text, source=str(path))


def format_roster(roster: Roster) -> str:
    """The CSV text of ``roster``, which ``parse_roster`` reads back as the same roster."""
    if not isinstance(roster, Roster):
        raise TypeError(f"roster: expected a Roster, got {type(roster).__name__}")
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    for entry in roster.entries:
        writer.writerow([entry.login, entry.name, entry.email, entry.role])
    return buffer.getvalue()


def write_roster(roster: Roster, path) -> Path:
    """Replace the file at ``path`` with ``roster`` atomically (mode 0600); returns the path.

    The text goes to a temporary file beside it, is fsynced, and is renamed over the old file,
    so a reader (the hub) sees either the old roster or the new one, never half of one.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path (str or os.PathLike), got {type(path).__name__}")
    text = format_roster(roster)
    target = Path(path)
    descriptor, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    try:
        os.fchmod(descriptor, 0o600)
        with os.fdopen(descriptor, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, target)
    except BaseException:
        try:
            os.unlink(temporary)
        except FileNotFoundError:
            pass
        raise
    folder = os.open(target.parent, os.O_RDONLY)
    try:
        os.fsync(folder)
    finally:
        os.close(folder)
    return target
