"""A student's novice baseline: P1 and P2 of the paper's protocol, taken in tutorial 00 before any theory.

The paper's participants were novices at P1 and P2. A student who runs the whole protocol in
tutorial 10 does so after tutorials 01-09 have taught the optimal rule, so their P1 is no longer
a novice's. Tutorial 00 therefore takes the baseline first: the same two episodes (skill 1 and
skill 2, no guidance, the capstone's own query states from ``mt_widgets.in_silico.plan``), and
each finished episode's teaching error is kept in ``~/mt-widgets-lessons/baseline.json`` (one
small JSON file of the student's own, rewritten atomically). Tutorial 11 reads it and sets the novice
baseline beside the capstone's P1 and P4.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

#: The phases the baseline takes (the paper's two baselines).
BASELINE_PHASES = ("P1", "P2")


def lessons_folder() -> Path:
    """Where the lessons keep a student's own results (tutorial 10's capstone folder is beside it)."""
    return Path.home() / "mt-widgets-lessons"


def baseline_path(folder=None) -> Path:
    return Path(folder if folder is not None else lessons_folder()) / "baseline.json"


def read_baseline(path=None) -> dict[str, float]:
    """{phase: teaching error} of the baseline episodes finished so far ({} when none)."""
    path = baseline_path() if path is None else Path(path)
    if not path.is_file():
        return {}
    data = json.loads(path.read_text(encoding="utf-8"))
    return {phase: float(error) for phase, error in data.get("errors", {}).items() if phase in BASELINE_PHASES}


def save_baseline(phase: str, error: float, path=None) -> dict[str, float]:
    """Keeps one finished baseline episode's teaching error (the first one of each phase: a novice's)."""
    if phase not in BASELINE_PHASES:
        raise ValueError(f"phase: expected one of {', '.join(BASELINE_PHASES)}, got {phase!r}")
    if isinstance(error, bool) or not isinstance(error, (int, float, np.floating)) or not np.isfinite(error) \
            or error < 0:
        raise ValueError(f"error: expected a teaching error >= 0, got {error!r}")
    path = baseline_path() if path is None else Path(path)
    errors = read_baseline(path)
    errors.setdefault(phase, float(error))    # retaking it later, with the theory known, is not a baseline
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=".baseline-", suffix=".tmp")
    with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
        json.dump({"format": 1, "errors": errors}, handle)
    os.replace(temporary, path)
    return errors


def baseline_changes(baseline: dict[str, float], capstone: dict[str, float]) -> dict[str, float]:
    """Changes from the novice baseline (later minus earlier, negative = better) to the capstone's episodes.

    Args:
        baseline: {"P1": E, "P2": E} from tutorial 00.
        capstone: the capstone's first-episode errors by phase ({"P1": ..., "P4": ..., "P5": ...}).
    """
    changes = {}
    for name, before, after in (("P1(00)_to_P1", "P1", "P1"), ("P1(00)_to_P4", "P1", "P4"),
                                ("P2(00)_to_P5", "P2", "P5")):
        if before in baseline and after in capstone:
            changes[name] = float(capstone[after] - baseline[before])
    return changes
