"""The instructor's command for a class hub in a learning platform: the roster from NRPS, grades back with AGS.

Run it as root with the hub's settings (the same environment variables as ``jupyterhub_config.py``
with ``MT_HUB_LOGIN=lti``, plus ``MT_HUB_LTI_TOKEN_URL``, the platform's OAuth 2 token URL)::

    python deploy/jupyterhub/lti_admin.py sync                          # the roster from the course's members
    python deploy/jupyterhub/lti_admin.py sync --names /home/dana/class-names.json --names-owner lti-...
    python deploy/jupyterhub/lti_admin.py grades --dry-run              # what would be posted
    python deploy/jupyterhub/lti_admin.py grades                        # nbgrader's totals to the gradebook

The course's service URLs come from the last instructor's launch (the hub keeps them in
``$MT_HUB_STATE/lti-services.json``), or ``--memberships-url`` and ``--lineitems-url``.

``sync`` adds every active member of the course to the roster (name and e-mail for instructors
only) and drops the platform logins who left: a dropped student's running server and kernels are
ended and the hub logs them out at its next check (5 minutes at most); their home and files stay
for the instructor. ``--names`` also writes the class view's names file (readable by
``--names-owner`` only). ``grades`` posts each student's nbgrader total of every assignment in
``$MT_HUB_COURSE/gradebook.db`` (lti_grades.py): only what the platform does not already have, so
running it twice posts nothing the second time. Why a command of the hub and not of ``mt-widgets``:
it signs with the tool's private key, which only the hub's user (root) may read.
"""

from __future__ import annotations

import argparse
import fcntl
import json
import os
import pwd
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import class_admin  # noqa: E402
from lti_grades import grade_plan, read_gradebook, score_message  # noqa: E402
from lti_services import (  # noqa: E402
    LOGIN_PREFIX,
    PlatformClient,
    ToolKey,
    read_platform_ids,
    synced_roster,
    write_private_json,
)

from mt_widgets.classroom.names import write_names  # noqa: E402
from mt_widgets.classroom.roster import read_roster, write_roster  # noqa: E402


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    env = os.environ.get
    parser.add_argument("--roster", default=env("MT_HUB_ROSTER"), help="the roster CSV (default: $MT_HUB_ROSTER)")
    parser.add_argument("--state", default=env("MT_HUB_STATE", "mt-hub-state"),
                        help="the hub's state folder: the tool's key, platform ids (default: $MT_HUB_STATE)")
    parser.add_argument("--issuer", default=env("MT_HUB_LTI_ISSUER"), help="default: $MT_HUB_LTI_ISSUER")
    parser.add_argument("--client-id", default=env("MT_HUB_LTI_CLIENT_ID"), help="default: $MT_HUB_LTI_CLIENT_ID")
    parser.add_argument("--token-url", default=env("MT_HUB_LTI_TOKEN_URL"), help="default: $MT_HUB_LTI_TOKEN_URL")
    parser.add_argument("--login-prefix", default=env("MT_HUB_LTI_LOGIN_PREFIX", LOGIN_PREFIX))
    parser.add_argument("--memberships-url", help="NRPS: default, the one of the last instructor's launch")
    parser.add_argument("--lineitems-url", help="AGS: default, the one of the last instructor's launch")
    commands = parser.add_subparsers(dest="command", required=True)
    sync = commands.add_parser("sync", help="add and drop students as the platform's course lists them")
    sync.add_argument("--names", help="also write the class view's names file here (0600)")
    sync.add_argument("--names-owner", help="the instructor login who owns the names file")
    grades = commands.add_parser("grades", help="post nbgrader's totals as the platform's scores")
    grades.add_argument("--course", default=env("MT_HUB_COURSE"), help="nbgrader's course folder ($MT_HUB_COURSE)")
    grades.add_argument("--dry-run", action="store_true", help="show what would be posted; post nothing")
    return parser


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    missing = [flag for flag, value in (("--roster", args.roster), ("--issuer", args.issuer),
                                        ("--client-id", args.client_id), ("--token-url", args.token_url))
               if not value]
    if missing:
        print(f"lti_admin: expected {', '.join(missing)} (or their MT_HUB_ settings), got nothing", file=sys.stderr)
        return 2
    state = Path(args.state)
    services_file = state / "lti-services.json"
    services = json.loads(services_file.read_text()) if services_file.exists() else {}
    client = PlatformClient(args.client_id, args.token_url, ToolKey.load_or_create(state / "lti-tool-key.pem"))
    ids_path = state / "lti-platform-ids.json"

    if args.command == "sync":
        url = args.memberships_url or services.get("memberships_url")
        if not url:
            print("lti_admin: no memberships URL: launch the tool once as the instructor, or give "
                  "--memberships-url", file=sys.stderr)
            return 2
        members = client.members(url)
        with open(state / "lti.lock", "a") as lock:  # the hub writes the roster at launches too
            fcntl.flock(lock, fcntl.LOCK_EX)
            result = synced_roster(read_roster(args.roster), members, args.issuer, args.login_prefix,
                                   read_platform_ids(ids_path))
            write_roster(result.roster, args.roster)
            write_private_json(ids_path, result.platform_ids)
        for login in result.dropped:
            ended = class_admin._end_processes(login) if os.geteuid() == 0 else 0
            print(f"dropped {login} ({ended} running processes ended; their home is kept)")
        for login in result.added:
            print(f"added {login} as {result.roster.entry(login).role}")
        if args.names:
            folder = os.environ.get("MT_WIDGETS_CLASS_FOLDER")
            if not folder:
                print("lti_admin: --names needs MT_WIDGETS_CLASS_FOLDER (the class folder)", file=sys.stderr)
                return 2
            out = write_names(args.roster, folder, args.names)
            if args.names_owner:
                owner = pwd.getpwnam(args.names_owner)
                os.chown(out, owner.pw_uid, owner.pw_gid)
        students = len(result.roster.students)
        print(f"{len(members)} platform members; roster: {students} students, {len(result.roster.admins)} "
              f"instructors/TAs ({len(result.added)} added, {len(result.dropped)} dropped)")
        return 0

    if args.command == "grades":
        url = args.lineitems_url or services.get("lineitems_url")
        if not url or not args.course:
            print("lti_admin: grades needs the line items URL (an instructor's launch, or --lineitems-url) and "
                  "--course (or $MT_HUB_COURSE)", file=sys.stderr)
            return 2
        grades = read_gradebook(args.course)
        made, plan, items = grade_plan(client, url, grades, read_platform_ids(ids_path), create=not args.dry_run)
        verb = "would make" if args.dry_run else "made"
        for assignment in made:
            print(f"{verb} line item {assignment!r}")
        posted = 0
        for post in plan:
            action = ("would post" if args.dry_run else "posted") if post.post else "left"
            print(f"{action} {post.assignment} {post.login}: {post.score:g}/{post.max_score:g} ({post.why})")
            if post.post and not args.dry_run:
                client.post_score(items[post.assignment]["id"], score_message(post))
                posted += 1
        print(f"{sum(p.post for p in plan)} scores to post, {posted} posted" if not args.dry_run
              else f"dry run: {sum(p.post for p in plan)} scores would be posted, nothing sent")
        return 0
    return 2


if __name__ == "__main__":
    sys.exit(main())
