"""The study folder's command line: ``python -m mt_widgets.study COMMAND ...``.

Commands::

    erase STUDY_FOLDER PARTICIPANT_ID    answer an erasure request (mt_widgets.study.erasure): says
                                         what was removed, what is kept and why
    export-bids STUDY_FOLDER OUT_FOLDER  the pseudonymised BIDS dataset (mt_widgets.study.bids)
    status STUDY_FOLDER                  the per-group counts (holds groups: the experimenter's)

Exit status 0 on success, 2 with a one-line message on a refused request (an unknown ID, a folder
that is not a study).
"""

from __future__ import annotations

import argparse
import sys

from .bids import export_bids
from .erasure import erase_participant
from .jsonl import LogError
from .study_folder import StudyFolder


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mt_widgets.study", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    erase = commands.add_parser("erase", help="erase a participant on their request (by the ID the study knows, "
                                              "online their Prolific ID)")
    erase.add_argument("study_folder")
    erase.add_argument("participant_id")
    export = commands.add_parser("export-bids", help="write the pseudonymised BIDS dataset")
    export.add_argument("study_folder")
    export.add_argument("out_folder")
    status = commands.add_parser("status", help="per-group counts")
    status.add_argument("study_folder")
    args = parser.parse_args(argv)
    try:
        if args.command == "erase":
            print(erase_participant(args.study_folder, args.participant_id))
        elif args.command == "export-bids":
            print(f"Wrote {export_bids(args.study_folder, args.out_folder)} (participants as random codes; the key "
                  f"stays in {args.study_folder})")
        else:
            print(StudyFolder(args.study_folder).status_report())
    except (LogError, ValueError, TypeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
