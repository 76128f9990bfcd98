"""The synthetic studies shipped with the package, and how they are (re)made.

``EXAMPLE_STUDY``: 8 synthetic teachers run through the paper's simulation protocol by the
session engine (``mt_widgets.in_silico.sessions.run_through_sessions``); ``EXAMPLE_UARM_STUDY``:
the same on the physical protocol. ``python -m mt_widgets.analysis.example_studies``
regenerates both (see ``data/README.md``).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mt_widgets.core.validation import as_bool
from mt_widgets.in_silico.sessions import run_through_sessions

#: The synthetic study shipped with the package.
EXAMPLE_STUDY = Path(__file__).parent / "data" / "synthetic-sim"

#: How the shipped study was made (``write_example_study`` uses these).
EXAMPLE_SETTINGS = {"n_participants": 8, "protocol": "paper-sim", "seed": 2024}

#: The synthetic uArm study shipped with the package: the same, on the physical protocol.
EXAMPLE_UARM_STUDY = Path(__file__).parent / "data" / "synthetic-uarm"
EXAMPLE_UARM_SETTINGS = {"n_participants": 8, "protocol": "paper-uarm", "seed": 2024}


def write_example_study(folder=EXAMPLE_STUDY, overwrite: bool = False, **settings) -> Path:
    """(Re)generates the shipped synthetic study through the session engine.

    Args:
        folder: where (default: the package's ``data/synthetic-sim``).
        overwrite: replace an existing folder.
        **settings: override ``EXAMPLE_SETTINGS`` (n_participants, protocol, seed).

    Returns:
        The folder.
    """
    # Checked before anything else: a truthy non-bool ("no") must never reach the rmtree below.
    overwrite = as_bool("overwrite", overwrite)
    folder = Path(folder)
    if folder.exists():
        if not overwrite:
            raise FileExistsError(f"folder: {folder} exists; pass overwrite=True to regenerate it")
        shutil.rmtree(folder)
    options = {**EXAMPLE_SETTINGS, **settings}
    run_through_sessions(folder, options["n_participants"], protocol=options["protocol"], seed=options["seed"])
    # Once every session is closed the engine's lock folder holds only empty, released lock
    # files; a shipped dataset has no use for them.
    locks = folder / ".locks"
    if locks.is_dir() and all(p.suffix == ".lock" and p.stat().st_size == 0 for p in locks.iterdir()):
        shutil.rmtree(locks)
    return folder


if __name__ == "__main__":  # python -m mt_widgets.analysis.example_studies  regenerates the shipped studies
    print(write_example_study(overwrite=True))
    print(write_example_study(EXAMPLE_UARM_STUDY, overwrite=True, **EXAMPLE_UARM_SETTINGS))
