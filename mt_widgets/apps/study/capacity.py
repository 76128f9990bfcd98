"""At capacity, a clear page: a new online participant is turned away in words while the study is full.

The server's capacity is configured, not guessed: ``MT_WIDGETS_STUDY_MAX_PARTICIPANTS`` (how many
participants may be taking part at once) and ``MT_WIDGETS_STUDY_MIN_FREE_MIB`` (the memory, MiB,
that must stay available on the machine, read from /proc/meminfo). "Taking part" is read from the
study folder, whatever serves the pages (one process, forked kernels, several servers sharing the
folder): a participant whose log was written within ``ACTIVE_S`` seconds (a page's every step
writes; an abandoned page's kernel is culled after 10 minutes, deploy/voila/voila.py).

Only a new arrival is turned away: a participant already enrolled (a reload, a returning one)
always gets their page, since their place is theirs. A turned-away arrival is told when to come
back, and nothing is recorded for them (not even the study folder is created).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

#: Seconds since their log's last write during which a participant counts as taking part.
ACTIVE_S = 600.0


def available_mib() -> float | None:
    """Memory available on the machine, MiB (Linux's MemAvailable), or None where unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def _limit(name: str, value):
    if value is None:
        return None
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise ValueError(f"{name}: expected a number, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0:
        raise ValueError(f"{name}: expected a number >= 0 or None, got {value!r}")
    return value


@dataclass(frozen=True)
class Capacity:
    """How many participants the server takes at once, and the memory it keeps free.

    Attributes:
        max_participants: participants taking part at once (None: no limit).
        min_free_mib: MiB of memory that must stay available (None: not checked).
        active_s: seconds since a log's last write that still count as taking part.
    """

    max_participants: int | None = None
    min_free_mib: float | None = None
    active_s: float = ACTIVE_S

    def __post_init__(self):
        _limit("max_participants", self.max_participants)
        _limit("min_free_mib", self.min_free_mib)
        if _limit("active_s", self.active_s) is None or self.active_s <= 0:
            raise ValueError(f"active_s: expected seconds > 0, got {self.active_s!r}")

    @classmethod
    def from_environment(cls, environ=None) -> Capacity:
        """From ``MT_WIDGETS_STUDY_MAX_PARTICIPANTS`` and ``MT_WIDGETS_STUDY_MIN_FREE_MIB`` (unset: no limit)."""
        environ = os.environ if environ is None else environ
        most = environ.get("MT_WIDGETS_STUDY_MAX_PARTICIPANTS") or None
        free = environ.get("MT_WIDGETS_STUDY_MIN_FREE_MIB") or None
        most = _limit("MT_WIDGETS_STUDY_MAX_PARTICIPANTS", most)
        return cls(None if most is None else int(most), _limit("MT_WIDGETS_STUDY_MIN_FREE_MIB", free))

    def taking_part(self, study_folder, now: float | None = None) -> int:
        """Participants whose log was written within ``active_s`` seconds."""
        folder = Path(study_folder).expanduser()
        if not folder.is_dir():
            return 0
        now = time.time() if now is None else now
        people = set()
        for path in folder.glob("*.jsonl"):
            if path.name.startswith("_"):
                continue
            try:
                if now - path.stat().st_mtime <= self.active_s:
                    people.add(path.name.split(".")[0])
            except FileNotFoundError:  # erased meanwhile
                continue
        return len(people)

    def busy(self, study_folder, participant_id: str) -> str | None:
        """Why a new arrival must come back later (words for them), or None when there is room.

        ``participant_id`` already has a log in the folder: None (their place is theirs)."""
        folder = Path(study_folder).expanduser()
        if (folder / f"{participant_id}.jsonl").exists():
            return None
        full = self.max_participants is not None and self.taking_part(folder) >= self.max_participants
        free = available_mib() if self.min_free_mib is not None else None
        short = free is not None and free < self.min_free_mib
        if not (full or short):
            return None
        minutes = max(1, round(self.active_s / 60))
        return (f"The study is busy right now: as many people as it can take are taking part at this moment. "
                f"Please come back in about {minutes} minutes and open the same link again; your place in "
                f"the study is not lost. Nothing was recorded.")
