"""The command line: argparse's parser of every subcommand, and ``main``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import mt_widgets
from mt_widgets.classroom.progress import ClassFolderError
from mt_widgets.classroom.roster import RosterError
from mt_widgets.study.erasure import erase_participant
from mt_widgets.study.jsonl import LogError

from . import classroom, protocols, servers, study

DEFAULT_LAB_FOLDER = "mt-widgets-tutorials"


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port from 1 to 65535, got {port}")
    return port


def _server_options(parser: argparse.ArgumentParser, server: str) -> None:
    parser.add_argument("--port", type=_port, help=f"the port to serve on (default: {server}'s own)")
    parser.epilog = f"Options after -- go to {server} as they are, e.g. -- --ServerApp.ip=0.0.0.0"


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mt-widgets", description="Teach novices to teach robots: the tutorials, the demo, the studies, a class.")
    parser.add_argument("--version", action="version", version=f"mt-widgets {mt_widgets.__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    lab = commands.add_parser("lab", help="copy the tutorials into a folder and open JupyterLab there",
                              description="Copies the tutorials and notebooks into FOLDER/tutorials and "
                              "FOLDER/notebooks (files already there are kept) and opens JupyterLab at "
                              "tutorials/00_start_here.ipynb. Without a screen it prints the URL to open.")
    lab.add_argument("folder", nargs="?", default=DEFAULT_LAB_FOLDER,
                     help=f"where the notebooks go (default: ./{DEFAULT_LAB_FOLDER})")
    lab.add_argument("--no-browser", action="store_true", help="do not open a browser; print the URL")
    lab.add_argument("--copy-only", action="store_true", help="copy the notebooks, do not start JupyterLab")
    _server_options(lab, "jupyterlab")

    demo = commands.add_parser("demo", help="serve the visitors' demo page with Voila (a kiosk, a class)",
                               description="Serves notebooks/demo.ipynb with Voila and the kiosk settings "
                               "(a closed page ends its kernel, a preheated kernel waits). Open "
                               "http://localhost:8866/ (or --port).")
    _server_options(demo, "voila")

    study_parser = commands.add_parser("study", help="serve a study, or read and change a study folder",
                                       description="A study's pages and its folder.")
    study_commands = study_parser.add_subparsers(dest="study_command", required=True, metavar="ACTION")
    serve = study_commands.add_parser(
        "serve", help="serve the study pages with Voila",
        description="Serves the lab page (notebooks/study_sim.ipynb), or with --online the online participant "
        "page (/voila/render/study_online.ipynb?PROLIFIC_PID=...) and the experimenter's page. The "
        f"experimenter's panel opens with ${servers.EXPERIMENTER_CODE_ENV} (made up and printed when unset).")
    serve.add_argument("--online", action="store_true", help="serve the online participant page")
    _server_options(serve, "voila")
    study_commands.add_parser(
        "protocols", help="list the shipped protocols and their files",
        description="Lists the protocols shipped with mt-widgets (the paper's, the follow-up's, the online "
        "pilot): name, title, groups, phases and the file, to read or to copy with copy-protocol.")
    copy = study_commands.add_parser(
        "copy-protocol", help="copy a shipped protocol into a folder to edit it",
        description="Copies the shipped protocol NAME (see: mt-widgets study protocols) into FOLDER "
        "(default: the current folder), never over an existing file. Edit the copy, then load it with "
        "mt_widgets.study.load_protocol(PATH).")
    copy.add_argument("name", help="a shipped protocol's name (mt-widgets study protocols)")
    copy.add_argument("folder", nargs="?", default=".", help="where the copy goes (default: here)")
    status = study_commands.add_parser("status", help="each group's and participant's state (the groups shown)",
                                       description="Prints each group's counts and each participant's state.")
    status.add_argument("folder", help="the study folder (it holds study.json)")
    export = study_commands.add_parser("export", help="export the study as a BIDS-style behavioural dataset",
                                       description="Writes the study's BIDS-style dataset to OUT "
                                       "(withdrawn and excluded participants left out).")
    export.add_argument("folder", help="the study folder")
    export.add_argument("out", help="the dataset folder to write")
    withdraw = study_commands.add_parser(
        "withdraw", help="record that a participant withdrew, with the protocol's data policy",
        description="Records that PARTICIPANT withdrew; the protocol's policy says whether their log "
        "is kept out of the analysis (exclude) or deleted (delete).")
    withdraw.add_argument("folder", help="the study folder")
    withdraw.add_argument("participant", help="the participant's ID")
    withdraw.add_argument("--reason", default="", help="why, in the participant's words (optional)")
    erase = study_commands.add_parser(
        "erase", help="answer a participant's erasure request: remove their data, say what is kept",
        description="Erases PARTICIPANT from the study folder (mt_widgets/study/erasure.py): their logs, "
        "their ID in the enrolment and outcome records, their pseudonym and the tidy CSVs' rows; keeps "
        "a keyed hash of the ID and how they ended (the pool's payment, the proof of the answer). "
        "Prints the report to send back. Exits 1, changing nothing, on an ID the study does not hold.")
    erase.add_argument("folder", help="the study folder")
    erase.add_argument("participant", help="the ID the study knows them by (online: their Prolific ID), exactly")

    course = commands.add_parser("course", help="check a class folder", description="The course's checks.")
    course_commands = course.add_subparsers(dest="course_command", required=True, metavar="ACTION")
    course_check = course_commands.add_parser(
        "check", help="read a class folder's progress files; with --roster, who has none yet",
        description="Reads every progress file of a class folder and reports the problems met; with a "
        "roster, names the students without a progress file. Exits 1 when a file is damaged.")
    course_check.add_argument("class_folder", help="the class folder (it holds class.json)")
    course_check.add_argument("--roster", help="the class roster CSV (login,name,email,role)")

    hub = commands.add_parser("hub", help="check a class hub's roster", description="The class hub's checks.")
    hub_commands = hub.add_subparsers(dest="hub_command", required=True, metavar="ACTION")
    hub_check = hub_commands.add_parser(
        "check", help="read the roster and say who is on it",
        description="Reads the hub's roster (every wrong entry named) and counts students and instructors.")
    hub_check.add_argument("roster", help="the roster CSV (login,name,email,role)")
    return parser


def _split_server_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """(the command's own arguments, what follows ``--`` for the server)."""
    if "--" in argv:
        at = argv.index("--")
        return argv[:at], argv[at + 1:]
    return argv, []


def run(args: argparse.Namespace, server_args: list[str]) -> int:
    if args.command == "lab":
        if args.copy_only:
            copied, kept = servers.copy_notebooks(args.folder)
            print(servers.copy_report(Path(args.folder).resolve(), copied, kept))
            return 0
        command, url = servers.lab_command(args.folder, args.port, not args.no_browser, server_args)
        if url:
            print(f"== open {url}", flush=True)
        servers.replace_process(command, Path(args.folder).expanduser().resolve())
    if args.command == "demo":
        notebook = servers.shipped_folder("notebooks") / "demo.ipynb"
        servers.replace_process(servers.voila_command(notebook, args.port, server_args), notebook.parent)
    if args.command == "study":
        if args.study_command == "serve":
            servers.experimenter_code()
            if args.online:
                return servers.serve_online(args.port, server_args)
            notebook = servers.shipped_folder("notebooks") / "study_sim.ipynb"
            servers.replace_process(servers.voila_command(notebook, args.port, server_args), notebook.parent)
        if args.study_command == "protocols":
            print(protocols.protocols_text())
        elif args.study_command == "copy-protocol":
            print(f"wrote {protocols.copy_protocol(args.name, args.folder)}")
        elif args.study_command == "status":
            print(study.status_text(args.folder))
        elif args.study_command == "export":
            print(f"wrote {study.export(args.folder, args.out)}")
        elif args.study_command == "withdraw":
            record = study.withdraw(args.folder, args.participant, args.reason)
            print(f"{args.participant}: withdrawn (data: {record['data']})")
        elif args.study_command == "erase":
            print(erase_participant(args.folder, args.participant))
        return 0
    if args.command == "course":
        report, fine = classroom.course_check(args.class_folder, args.roster)
        print(report)
        return 0 if fine else 1
    if args.command == "hub":
        print(classroom.hub_check(args.roster))
        return 0
    raise AssertionError(f"unhandled command {args.command!r}")  # argparse allows only the ones above


def main(argv: list[str] | None = None) -> int:
    """Runs the command; returns its exit status (2: a wrong argument, 1: the work failed)."""
    parser = build_parser()
    own, server_args = _split_server_args(list(sys.argv[1:] if argv is None else argv))
    args = parser.parse_args(own)
    if server_args and args.command not in ("lab", "demo") and getattr(args, "study_command", "") != "serve":
        parser.error(f"options after -- go to a server; {args.command} starts none")
    try:
        return run(args, server_args)
    except (LogError, RosterError, ClassFolderError, FileNotFoundError, FileExistsError, NotADirectoryError,
            ValueError) as error:
        print(f"mt-widgets: {error}", file=sys.stderr)
        return 1
