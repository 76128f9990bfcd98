"""The instructor's command for the class hub: the roster, accounts and passwords.

Run it as root with the hub's settings (the same environment variables as
``jupyterhub_config.py``, or the options)::

    python deploy/jupyterhub/class_admin.py check                        # is the roster valid?
    python deploy/jupyterhub/class_admin.py set-password instructor      # an admin's password (asked twice)
    python deploy/jupyterhub/class_admin.py add ann --name "Ann Lee" --email ann@example.edu
    python deploy/jupyterhub/class_admin.py add tom --role ta
    python deploy/jupyterhub/class_admin.py reset-password ann           # ann sets a new one at her next login
    python deploy/jupyterhub/class_admin.py remove ann                   # refused from now on; home kept
    python deploy/jupyterhub/class_admin.py sync                         # system users for the whole roster

``add`` and ``remove`` rewrite the roster atomically; the running hub re-reads it at the next
login (no restart). ``remove`` also clears the password and ends the person's running server
and kernels; ``--delete-account`` removes their system user and home too (their work goes).
With ``MT_WIDGETS_CLASS_FOLDER`` set (as for the hub), ``add`` and ``sync`` also make each
student's progress files in the class folder. ``set-password --stdin`` reads the password
from standard input, for scripts.
"""

from __future__ import annotations

import argparse
import getpass
import os
import pwd
import signal
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import class_hub  # noqa: E402
from roster_authenticator import PasswordStore, hash_password  # noqa: E402

from mt_widgets.classroom.roster import ROLES, RosterEntry, RosterError, read_roster, write_roster  # noqa: E402

MIN_PASSWORD_LENGTH = 10


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roster", default=os.environ.get("MT_HUB_ROSTER"),
                        help="the roster CSV (default: $MT_HUB_ROSTER)")
    parser.add_argument("--state", default=os.environ.get("MT_HUB_STATE", "mt-hub-state"),
                        help="the hub's state folder, which holds passwords.json (default: $MT_HUB_STATE)")
    parser.add_argument("--homes", default=os.environ.get("MT_HUB_HOMES", "/home"),
                        help="where homes are made (default: $MT_HUB_HOMES or /home)")
    parser.add_argument("--instructors-group", default=os.environ.get("MT_HUB_INSTRUCTORS_GROUP", "mt-instructors"))
    commands = parser.add_subparsers(dest="command", required=True)
    commands.add_parser("check", help="read the roster and say who is on it")
    add = commands.add_parser("add", help="add (or update) a person on the roster and make their account")
    add.add_argument("login")
    add.add_argument("--name", default="")
    add.add_argument("--email", default="")
    add.add_argument("--role", default="student", choices=ROLES)
    remove = commands.add_parser("remove", help="take a person off the roster")
    remove.add_argument("login")
    remove.add_argument("--delete-account", action="store_true", help="also remove their system user and home")
    setpw = commands.add_parser("set-password", help="set a person's password (admins: the only way)")
    setpw.add_argument("login")
    setpw.add_argument("--stdin", action="store_true", help="read the password from standard input")
    reset = commands.add_parser("reset-password", help="clear a student's password: they set one at next login")
    reset.add_argument("login")
    commands.add_parser("sync", help="make the system user and home of everyone on the roster")
    return parser


def _end_processes(login: str) -> int:
    """Ends every process of ``login``'s system user (their server and kernels); returns how many."""
    try:
        uid = pwd.getpwnam(login).pw_uid
    except KeyError:
        return 0
    ended = 0
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            if entry.stat().st_uid == uid:
                os.kill(int(entry.name), signal.SIGKILL)
                ended += 1
        except (FileNotFoundError, ProcessLookupError):
            continue
    return ended


def _prepare(entry, homes: Path, group: str) -> None:
    """``entry``'s system user and home, and for a student their progress files in the class folder."""
    gid = class_hub.ensure_group(group)
    class_hub.ensure_system_user(entry.login, homes / entry.login, group, entry.is_admin)
    folder = os.environ.get("MT_WIDGETS_CLASS_FOLDER")
    if folder and not entry.is_admin and Path(folder, "class.json").exists():
        class_hub.ensure_progress_files(Path(folder), entry.login, gid)


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if not args.roster:
        print("class_admin: --roster or MT_HUB_ROSTER: expected the roster CSV, got nothing", file=sys.stderr)
        return 2
    roster_path = Path(args.roster)
    try:
        roster = read_roster(roster_path)
    except RosterError as error:
        print(error, file=sys.stderr)
        return 1
    store = PasswordStore(Path(args.state) / "passwords.json")
    homes = Path(args.homes)

    if args.command == "check":
        print(f"{roster_path}: {len(roster.students)} students, {len(roster.admins)} instructors/TAs "
              f"({', '.join(e.login for e in roster.admins) or 'none'})")
        unset = [e.login for e in roster.admins if store.get(e.login) is None]
        if unset:
            print(f"without a password yet (set-password): {', '.join(unset)}")
        return 0

    if args.command in ("set-password", "reset-password", "remove") and args.login not in roster:
        print(f"class_admin: {args.login!r} is not on the roster {roster_path} ({len(roster)} logins)",
              file=sys.stderr)
        return 1

    if args.command == "add":
        try:
            entry = RosterEntry(args.login, args.name, args.email, args.role)
        except ValueError as error:
            print(f"class_admin: {error}", file=sys.stderr)
            return 1
        was = "updated" if args.login in roster else "added"
        write_roster(roster.with_entry(entry), roster_path)
        if os.geteuid() == 0:
            _prepare(entry, homes, args.instructors_group)
        print(f"{entry.login} {was} as {entry.role}"
              + ("; set their password with set-password before they log in" if entry.is_admin else ""))
        return 0

    if args.command == "remove":
        write_roster(roster.without(args.login), roster_path)
        store.set(args.login, None)
        ended = _end_processes(args.login) if os.geteuid() == 0 else 0
        deleted = args.delete_account and class_hub.remove_system_user(args.login, remove_home=True)
        print(f"{args.login} removed from the roster; {ended} running processes ended"
              + ("; system user and home deleted" if deleted else "; their home is kept"))
        return 0

    if args.command == "set-password":
        if args.stdin:
            password = sys.stdin.readline().rstrip("\n")
        else:
            password = getpass.getpass(f"new password for {args.login}: ")
            if getpass.getpass("again: ") != password:
                print("class_admin: the two passwords differ; nothing changed", file=sys.stderr)
                return 1
        if len(password) < MIN_PASSWORD_LENGTH:
            print(f"class_admin: a password needs at least {MIN_PASSWORD_LENGTH} characters, got {len(password)}; "
                  "nothing changed", file=sys.stderr)
            return 1
        store.set(args.login, hash_password(password))
        print(f"password of {args.login} set")
        return 0

    if args.command == "reset-password":
        if roster.entry(args.login).is_admin:
            print(f"class_admin: {args.login} is an admin, who cannot set a password at login: use set-password",
                  file=sys.stderr)
            return 1
        changed = store.set(args.login, None)
        print(f"password of {args.login} cleared: they choose a new one at their next login"
              if changed else f"{args.login} had no password yet")
        return 0

    if args.command == "sync":
        for entry in roster.entries:
            _prepare(entry, homes, args.instructors_group)
        print(f"{len(roster)} accounts ready under {homes}")
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
