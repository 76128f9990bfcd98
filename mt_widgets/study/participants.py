"""Participants: pseudonymous IDs and balanced, seeded, recorded group assignment.

No names are stored: a participant is a short code the experimenter types ("P07"). The code
names the participant's log file, so it is checked strictly: plain ASCII letters, digits,
'-' and '_', starting with a letter or digit, at most 64 characters, no path separators and
no "..", not a reserved device name on Windows, and unique in a study ignoring case (two
codes differing only in case would share one file on macOS and Windows).

Assignment is block randomisation: enrolments are grouped in blocks of ``block_size``; each
block holds every group equally often, in an order drawn from a numpy ``SeedSequence`` of the
protocol's assignment seed and the block number. So the k-th enrolment always gets the same
group for a given protocol (reproducible), and after every complete block the groups are
exactly balanced.

IDs from a URL (an online participant, ``mt_widgets.study.online``) are checked by
``validate_url_participant_id`` first: the message is for the participant (who did not type
the ID), says that nothing was recorded, and never echoes control characters back.

A returning participant (a protocol with more than one session) is recognised by their ID or
by the re-entry code shown at the end of their previous session: ``new_reentry_code`` draws
one (``XXXX-XXXX`` from an alphabet without look-alike characters), ``normalise_reentry_code``
reads one typed back (case, spaces and the dash do not matter).
"""

from __future__ import annotations

import re
import secrets
import unicodedata

import numpy as np

MAX_ID_LENGTH = 64
_PLAIN_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")
# Names Windows reserves whatever the extension; a log named so could not be copied there.
_RESERVED = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)), *(f"lpt{i}" for i in range(10))}


class ParticipantIdError(ValueError):
    """A participant ID that cannot be used, with a message meant for the experimenter."""


def validate_participant_id(participant_id, existing=()) -> str:
    """Checks a pseudonymous participant ID and returns it.

    Args:
        participant_id: the code typed by the experimenter.
        existing: IDs already enrolled in the study (compared ignoring case).

    Raises:
        ParticipantIdError: saying what is wrong, e.g. empty, a path separator, "..",
            characters that are not plain text, or already used.
    """
    if not isinstance(participant_id, str):
        raise ParticipantIdError(f"participant_id: expected text, got {type(participant_id).__name__} "
                                 f"{participant_id!r}"[:200])
    shown = repr(participant_id)[:80]
    if participant_id.strip() == "":
        raise ParticipantIdError("participant_id: expected a code such as 'P07', got an empty ID")
    if participant_id != participant_id.strip():
        raise ParticipantIdError(f"participant_id: expected no spaces at the start or end, got {shown}")
    if "/" in participant_id or "\\" in participant_id or ":" in participant_id:
        raise ParticipantIdError(f"participant_id: expected no path separators ('/', '\\', ':'), got {shown}")
    if ".." in participant_id:
        raise ParticipantIdError(f"participant_id: expected no '..', got {shown}")
    bad = [ch for ch in participant_id if not (ch.isascii() and (ch.isalnum() or ch in "-_"))]
    if bad:
        names = ", ".join(sorted({unicodedata.name(ch, f"U+{ord(ch):04X}") for ch in bad}))
        raise ParticipantIdError(f"participant_id: expected plain text (ASCII letters, digits, '-' and '_'), "
                                 f"got {shown} containing {names}")
    if not _PLAIN_ID.match(participant_id):
        raise ParticipantIdError(f"participant_id: expected it to start with a letter or a digit, got {shown}")
    if len(participant_id) > MAX_ID_LENGTH:
        raise ParticipantIdError(f"participant_id: expected at most {MAX_ID_LENGTH} characters, "
                                 f"got {len(participant_id)}")
    if participant_id.lower() in _RESERVED:
        raise ParticipantIdError(f"participant_id: {shown} is a reserved device name on Windows; choose another")
    taken = {other.lower(): other for other in existing}
    if participant_id.lower() in taken:
        same = taken[participant_id.lower()]
        detail = "" if same == participant_id else f" (as {same!r}; IDs are compared ignoring case)"
        raise ParticipantIdError(f"participant_id: {shown} is already enrolled in this study{detail}; "
                                 f"resume that participant or choose a new ID")
    return participant_id


def block_assignment(index: int, groups, block_size: int, seed: int) -> str:
    """The group of the ``index``-th enrolment (0-based) under seeded block randomisation.

    Args:
        index: enrolment number in the study, 0-based.
        groups: the group names.
        block_size: a multiple of ``len(groups)``.
        seed: the protocol's assignment seed.
    """
    groups = list(groups)
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
        raise ValueError(f"index: expected a non-negative integer, got {index!r}")
    if not groups:
        raise ValueError("groups: expected at least one group, got none")
    if isinstance(block_size, bool) or not isinstance(block_size, int) or block_size < 1 or block_size % len(groups):
        raise ValueError(f"block_size: expected a positive multiple of {len(groups)} groups, got {block_size!r}")
    block, position = divmod(int(index), block_size)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(block,)))
    order = rng.permutation(np.repeat(np.arange(len(groups)), block_size // len(groups)))
    return groups[int(order[position])]


#: Letters and digits of a re-entry code: no 0/O, 1/I/L, so a code read off a screen is typed back right.
REENTRY_ALPHABET = "ABCDEFGHJKMNPQRSTUVWXYZ23456789"
_REENTRY = re.compile(r"^[" + REENTRY_ALPHABET + r"]{8}$")


def validate_url_participant_id(value, parameter: str = "participant") -> str:
    """Checks a participant ID that came in a URL, before anything is written for it.

    Args:
        value: the parameter's value (None when the URL lacks it).
        parameter: the parameter's name, for the message ("PROLIFIC_PID").

    Returns:
        The ID, which also passes ``validate_participant_id`` (it names a log file).

    Raises:
        ParticipantIdError: missing, empty, over-long, path-like ('/', '\\', ':', '..', a
            leading '.' or '~'), control characters, or otherwise not a plain code; the
            message is meant for the participant and says that nothing was recorded.
    """
    tail = " Please open the study with the link exactly as you were given it. Nothing was recorded."
    if value is None:
        raise ParticipantIdError(f"{parameter}: this link does not say who you are (no {parameter} in it).{tail}")
    if not isinstance(value, str):
        raise ParticipantIdError(f"{parameter}: expected text, got {type(value).__name__}.{tail}")
    if value.strip() == "":
        raise ParticipantIdError(f"{parameter}: this link gives an empty {parameter}.{tail}")
    if len(value) > MAX_ID_LENGTH:
        raise ParticipantIdError(f"{parameter}: this link's {parameter} is {len(value)} characters long, expected "
                                 f"at most {MAX_ID_LENGTH}.{tail}")
    if any(ord(ch) < 32 or 127 <= ord(ch) < 160 for ch in value):
        raise ParticipantIdError(f"{parameter}: this link's {parameter} holds control characters.{tail}")
    if any(ch in value for ch in "/\\:") or ".." in value or value[0] in ".~":
        raise ParticipantIdError(f"{parameter}: this link's {parameter} looks like a file path, not an ID.{tail}")
    try:
        return validate_participant_id(value)
    except ParticipantIdError as error:
        reason = str(error).split(": ", 1)[-1]
        raise ParticipantIdError(f"{parameter}: this link's {parameter} is not a usable ID ({reason}).{tail}") \
            from None


def new_reentry_code() -> str:
    """A fresh re-entry code, e.g. "K7QM-3XRD" (40 bits from ``secrets``)."""
    raw = "".join(secrets.choice(REENTRY_ALPHABET) for _ in range(8))
    return raw[:4] + "-" + raw[4:]


def normalise_reentry_code(code) -> str:
    """A re-entry code as stored ("K7QM-3XRD") from what a participant typed ("k7qm 3xrd").

    Raises:
        TypeError: not text.
        ValueError: not a code of this form, with a message for the participant.
    """
    if not isinstance(code, str):
        raise TypeError(f"code: expected text, got {type(code).__name__}")
    plain = re.sub(r"[\s-]", "", code).upper()
    if not _REENTRY.match(plain):
        raise ValueError("code: expected the 8-character code shown at the end of your last session (like "
                         "K7QM-3XRD), got something else; check it and type it again")
    return plain[:4] + "-" + plain[4:]
