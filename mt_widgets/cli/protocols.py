"""The shipped study protocols from the command line: which there are, and a copy to edit.

A researcher without a clone finds the paper's protocols inside the installed package
(``mt_widgets/study/protocols/``) and the online pilot among the shipped notebooks
(``notebooks/study_online_pilot.toml``); ``mt-widgets study protocols`` lists them with their
files, ``mt-widgets study copy-protocol NAME`` copies one where it can be edited.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mt_widgets.study.protocol import BUILTIN_PROTOCOLS, PROTOCOL_FOLDER, load_protocol

from .shipped import shipped_folder

#: The online pilot's protocol among the shipped notebooks (what ``mt-widgets study serve --online`` serves).
ONLINE_PILOT = "study_online_pilot.toml"


def shipped_protocols() -> dict[str, Path]:
    """{name: file} of every protocol shipped with this installation: ``BUILTIN_PROTOCOLS`` and
    the online pilot (by the name its file gives)."""
    found = {name: PROTOCOL_FOLDER / file for name, file in BUILTIN_PROTOCOLS.items()}
    pilot = shipped_folder("notebooks") / ONLINE_PILOT
    found[load_protocol(pilot).name] = pilot
    return found


def protocols_text() -> str:
    """One paragraph per shipped protocol: its name and title, groups and phases, and its file."""
    lines = []
    for name, path in shipped_protocols().items():
        protocol = load_protocol(path)
        phases = ", ".join(f"{phase.id} ({phase.episodes})" for phase in protocol.all_phases)
        sessions = f", {len(protocol.sessions)} sessions" if len(protocol.sessions) > 1 else ""
        lines += [f"{name}: {protocol.title}",
                  f"    groups {' / '.join(protocol.groups)}; phases (episodes) {phases}{sessions}",
                  f"    {path}"]
    lines += ["", "Copy one to edit: mt-widgets study copy-protocol NAME [FOLDER]"]
    return "\n".join(lines)


def copy_protocol(name: str, folder=".") -> Path:
    """Copies the shipped protocol ``name`` into ``folder`` (made if missing), under its file's name.

    A relative video file it names (paper-sim's instruction video) is still found among the
    package's media when it is not beside the copy.

    Raises:
        ValueError: ``name`` is not a shipped protocol (the shipped ones named).
        FileExistsError: the copy's file exists already (never overwritten: it may hold edits).
        NotADirectoryError: ``folder`` is a file.
    """
    shipped = shipped_protocols()
    if name not in shipped:
        raise ValueError(f"name: expected a shipped protocol, one of {sorted(shipped)}, got {name!r}")
    folder = Path(folder).expanduser()
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"folder: expected a folder for the protocol, got the file {folder}")
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / shipped[name].name
    if target.exists():
        raise FileExistsError(f"{target} exists already; kept as it is (copy to another folder)")
    shutil.copyfile(shipped[name], target)
    return target
