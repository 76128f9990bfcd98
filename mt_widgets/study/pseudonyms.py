"""The key of a study's open data: each participant's random code, kept in the study folder only.

An exported dataset (``mt_widgets.study.bids``) names a participant ``sub-<code>``, where the code
is drawn at random (``secrets``) the first time the participant is exported: nothing of it comes
from their ID, which online is their Prolific ID (personal data: Prolific's guidance is to remove
it before sharing data openly). The key from ID to code lives in the study folder, never in the
dataset, in ``_pseudonyms.json``, readable and writable by its owner only (mode 0600), so:

- a re-export gives every participant the code they had (a published dataset and its corrections
  agree), and new participants get new codes;
- answering a participant's question about their data, or their erasure request
  (``mt_widgets.study.erasure``), goes through the key; deleting their entry unlinks them from
  every dataset already exported.

The file also holds the study's secret ``salt``: the erasure record keeps a keyed hash of an
erased ID (``id_digest``), never the ID, so a returning link can still be recognised.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import secrets
from pathlib import Path

from . import jsonl
from .jsonl import Lock, LogError
from .log import LOCK_FOLDER

KEY_FILE = "_pseudonyms.json"
#: One line per erased participant (``mt_widgets.study.erasure``): a keyed hash of the ID, never the ID.
ERASURE_FILE = "_erasures.jsonl"
#: Letters and digits of a code (no look-alikes 0/O, 1/I/L), 8 of them: 40 bits, a valid BIDS label.
CODE_ALPHABET = "ABCDEFGHJKMNPQRSTUVWXYZ23456789"
CODE_LENGTH = 8


def _lock(folder: Path) -> Lock:
    return Lock(folder / LOCK_FOLDER / "_pseudonyms.lock", f"the pseudonym key of {folder}", timeout_s=10.0)


def new_code(taken=()) -> str:
    """A fresh random code (``CODE_LENGTH`` characters of ``CODE_ALPHABET``) not in ``taken``."""
    taken = set(taken)
    while True:
        code = "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_LENGTH))
        if code not in taken:
            return code


def read_key(study_folder) -> dict:
    """The key file's contents: {"salt": hex, "codes": {participant ID: code}} (empty codes and a
    fresh salt when the study has none yet; nothing is written)."""
    path = Path(study_folder) / KEY_FILE
    if not path.exists():
        return {"salt": None, "codes": {}}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except ValueError:
        raise LogError(f"{path}: not a pseudonym key (it does not parse as JSON); restore it from a backup, "
                       f"or exported datasets lose their link to the study") from None
    if not isinstance(data, dict) or not isinstance(data.get("codes"), dict):
        raise LogError(f"{path}: expected {{'salt': ..., 'codes': {{ID: code}}}}, got something else")
    return data


def _write_key(folder: Path, data: dict) -> None:
    """Writes the key atomically (a new file, 0600 from its creation, then renamed over the old)."""
    path = folder / KEY_FILE
    temporary = folder / (KEY_FILE + ".tmp")
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        os.fchmod(fd, 0o600)  # the mode of a leftover temporary file too, whatever the umask was
        jsonl.write_all(fd, (json.dumps(data, indent=1, sort_keys=True) + "\n").encode())
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(temporary, path)
    jsonl.fsync_folder(folder)


def codes_for(study_folder, participant_ids) -> dict[str, str]:
    """{ID: code} for ``participant_ids``, drawing and storing codes for those without one.

    Codes already given are kept (re-exports agree); the key file is (re)written with mode 0600.
    """
    folder = Path(study_folder)
    ids = list(participant_ids)
    with _lock(folder):
        data = read_key(folder)
        codes = dict(data["codes"])
        missing = [pid for pid in ids if pid not in codes]
        for pid in missing:
            codes[pid] = new_code(codes.values())
        salt = data.get("salt") or secrets.token_hex(16)
        path = folder / KEY_FILE
        if missing or not data.get("salt") or not path.exists() or (path.stat().st_mode & 0o777) != 0o600:
            _write_key(folder, {"salt": salt, "codes": codes})
    return {pid: codes[pid] for pid in ids}


def forget(study_folder, participant_id: str) -> str | None:
    """Removes a participant's entry from the key; returns the code they had (None if none)."""
    folder = Path(study_folder)
    with _lock(folder):
        data = read_key(folder)
        code = data["codes"].pop(participant_id, None)
        if code is not None:
            _write_key(folder, data)
    return code


def id_digest(study_folder, participant_id: str) -> str:
    """A keyed hash (HMAC-SHA256 with the study's secret salt) of an ID: it recognises the ID
    again without storing it (the salt is created with the key when there is none)."""
    folder = Path(study_folder)
    data = read_key(folder)
    if not data.get("salt"):
        codes_for(folder, [])
        data = read_key(folder)
    return hmac.new(bytes.fromhex(data["salt"]), participant_id.encode(), hashlib.sha256).hexdigest()


def code_of(study_folder, participant_id: str) -> str | None:
    """The code a participant has in the study's key (None before their first export)."""
    return read_key(study_folder)["codes"].get(participant_id)


def erased_record(study_folder, participant_id) -> dict | None:
    """The erasure record (``ERASURE_FILE``) of ``participant_id``, or None if never erased."""
    folder = Path(study_folder)
    path = folder / ERASURE_FILE
    if not path.exists() or not isinstance(participant_id, str):
        return None
    records = [line.value for line in jsonl.read_jsonl(path).lines if line.value is not None]
    if not records:
        return None
    digest = id_digest(folder, participant_id)
    return next((r for r in records if r.get("id_digest") == digest), None)
