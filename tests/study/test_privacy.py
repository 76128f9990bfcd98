"""Open data that names no one: an online study's BIDS export holds no Prolific identity, the key
from ID to code stays in the study folder (0600) and is stable, and an erasure request removes a
participant everywhere while keeping (and saying) what must be kept."""

import json
import os
import re
import stat
import subprocess
import sys

import pytest
from bids_validator import BIDSValidator

from mt_widgets.study import LogError, Session, StudyFolder, UnknownParticipantError, erase_participant, export_bids
from mt_widgets.study.erasure import erased_record
from mt_widgets.study.pseudonyms import KEY_FILE, code_of, read_key

from .scripted import online_protocol, run

# Prolific-like identities: 24 hexadecimal characters each, as the pool hands them out.
PEOPLE = {
    "5f3a9c2e8b1d4a0012345678": ("60aa00000000000000000001", "70bb00000000000000000001"),
    "5f3a9c2e8b1d4a00123456a9": ("60aa00000000000000000001", "70bb00000000000000000002"),
    "6244deadbeef000011112222": ("60aa00000000000000000001", "70bb00000000000000000004"),
    "61c0ffee0000111122223333": ("60aa00000000000000000001", "70bb00000000000000000003"),
}
WITHDRAWS = "61c0ffee0000111122223333"
REPLACEMENT = "65aa11112222333344445555"


def _arrive(study, pid, study_id="60aa00000000000000000001", session_id="70bb00000000000000000009"):
    arrival = study.protocol.online.participant_from_url({"PROLIFIC_PID": [pid], "STUDY_ID": [study_id],
                                                          "SESSION_ID": [session_id]})
    return Session.arrive(study, arrival.participant_id, parameters=arrival.parameters)


def _online_study(folder):
    study = StudyFolder.create(folder, online_protocol())
    for pid, (study_id, session_id) in PEOPLE.items():
        with _arrive(study, pid, study_id, session_id) as session:
            if pid == WITHDRAWS:
                run(session, stop_after=6)
                session.withdraw("no time")
            else:
                run(session)
    # The withdrawn participant's place goes to the next arrival, whose enrolment names whom it replaces.
    with _arrive(study, REPLACEMENT) as session:
        run(session)
    assert study.enrolment(REPLACEMENT)["replaces"] == WITHDRAWS
    return study


def _identities():
    return {*PEOPLE, REPLACEMENT, *(v for pair in PEOPLE.values() for v in pair), "70bb00000000000000000009"}


def _found(root, needles) -> list[str]:
    """Every file or folder under ``root`` whose name or bytes hold one of ``needles``."""
    hits = []
    for path in sorted(root.rglob("*")):
        text = path.name + ("\n" + path.read_bytes().decode("utf-8", "replace") if path.is_file() else "")
        hits += [f"{path.relative_to(root)}: {n}" for n in needles if n in text or n.upper() in text]
    return hits


@pytest.fixture(scope="module")
def online(tmp_path_factory):
    root = tmp_path_factory.mktemp("privacy")
    return _online_study(root / "study"), root


def test_an_export_of_an_online_study_names_no_one_and_the_validator_passes(online):
    study, root = online
    out = export_bids(study.folder, root / "first")
    # The study folder does hold the identities (the fixture is not vacuous) ...
    assert _found(study.folder, _identities())
    # ... and no name or byte of the dataset does.
    assert _found(out, _identities()) == []
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert [f for f in files if not BIDSValidator().is_bids(f)] == []
    labels = sorted(p.name for p in out.glob("sub-*"))
    codes = read_key(study.folder)["codes"]
    kept = [pid for pid in (*PEOPLE, REPLACEMENT) if pid != WITHDRAWS]
    assert labels == sorted(f"sub-{codes[pid]}" for pid in kept) and WITHDRAWS not in codes
    rows = (out / "participants.tsv").read_text().splitlines()[1:]
    assert [r.split("\t")[0] for r in rows] == labels  # in code order, not ID or enrolment order
    # No clock time or date in any table: onsets count from the session's start.
    tables = "".join(p.read_text() for p in out.rglob("*.tsv"))
    assert "onset" in tables and not re.search(r"\d{4}-\d\d-\d\d|\d\d:\d\d:\d\d", tables)


def test_the_key_stays_in_the_study_folder_for_its_owner_only_and_reexports_reuse_it(online, tmp_path):
    study, root = online
    key = study.folder / KEY_FILE
    first = export_bids(study.folder, tmp_path / "a")
    codes = dict(read_key(study.folder)["codes"])
    assert stat.S_IMODE(os.stat(key).st_mode) == 0o600
    assert not any(p.name == KEY_FILE for p in first.rglob("*"))
    # Codes are random: not derived from the ID (a second study of the same people gets others).
    other = _online_study(tmp_path / "other")
    export_bids(other.folder, tmp_path / "o")
    assert all(codes[pid] != code_of(other.folder, pid) for pid in codes)
    assert not any(pid.upper().find(code) >= 0 for pid, code in codes.items())
    # A loosened mode is tightened again at the next export; the codes stay.
    os.chmod(key, 0o644)
    second = export_bids(study.folder, tmp_path / "b")
    assert read_key(study.folder)["codes"] == codes and stat.S_IMODE(os.stat(key).st_mode) == 0o600
    assert (first / "participants.tsv").read_bytes() == (second / "participants.tsv").read_bytes()
    # A newcomer gets a new code; everyone else keeps theirs.
    with _arrive(study, "66bb00000000000000000000") as session:
        run(session)
    export_bids(study.folder, tmp_path / "c")
    after = read_key(study.folder)["codes"]
    assert {k: after[k] for k in codes} == codes and after["66bb00000000000000000000"] not in codes.values()


def test_erasure_removes_a_participant_everywhere_and_says_what_is_kept(tmp_path):
    study = _online_study(tmp_path / "study")
    export_bids(study.folder, tmp_path / "before")
    others = [pid for pid in (*PEOPLE, REPLACEMENT) if pid != WITHDRAWS]
    gone = others[0]
    code = code_of(study.folder, gone)
    logs_before = {p.name: p.read_bytes() for p in study.folder.glob("*.jsonl") if not p.name.startswith("_")}
    groups_before = {r["participant"]: r["group"] for r in study.enrolments()}

    report = erase_participant(study.folder, gone)

    text = str(report)
    assert report.exported_code == code and f"sub-{code}" in text
    assert "Removed:" in text and f"{gone}.jsonl" in text and "Kept:" in text and "why:" in text
    assert "completion code C1MPL3T3" in text and report.left_over == []
    # Gone from every name and byte of the study folder (the hash of the ID is not the ID).
    assert [hit for hit in _found(study.folder, [gone]) if not hit.startswith("study.json")] == []
    assert gone not in study.participant_ids() and gone not in read_key(study.folder)["codes"]
    # What is kept: the enrolment slot without identity, and the erasure record the payment check reads.
    tomb = next(r for r in study.enrolments() if r.get("erased"))
    assert set(tomb) == {"format", "index", "group", "method", "block_slot", "protocol_hash", "participant",
                         "erased"} and tomb["group"] == groups_before[gone]
    record = erased_record(study.folder, gone)
    assert record["outcome"] == "completed" and record["completion_code"] == "C1MPL3T3"
    assert erased_record(study.folder, others[1]) is None
    # Others untouched: their logs byte for byte, their codes, their rows of a new export.
    for name, data in logs_before.items():
        if name.split(".")[0] != gone:
            assert (study.folder / name).read_bytes() == data, name
    after = export_bids(study.folder, tmp_path / "after")
    assert not (after / f"sub-{code}").exists() and _found(after, [gone, code]) == []
    assert sorted(p.name for p in after.glob("sub-*")) == sorted(f"sub-{code_of(study.folder, p)}" for p in others[1:])
    # The same link reopened records nothing; the next arrival takes the freed place (same group).
    with pytest.raises(LogError, match="erased"):
        _arrive(study, gone)
    newcomer = "67cc00000000000000000000"
    _arrive(study, newcomer).close()
    assert study.enrolment(newcomer)["group"] == groups_before[gone]
    assert study.enrolment(newcomer)["method"] == "replacement"


def test_erasing_a_withdrawn_participant_scrubs_the_log_of_whoever_replaced_them(tmp_path):
    study = _online_study(tmp_path / "study")
    replacement_log = study.log_path(REPLACEMENT)
    size = replacement_log.stat().st_size
    report = erase_participant(study.folder, WITHDRAWS)
    assert any(REPLACEMENT in item for item in report.removed)
    assert _found(study.folder, [WITHDRAWS]) == [] and replacement_log.stat().st_size == size
    started = json.loads(replacement_log.read_text().splitlines()[0])
    assert started["enrolment"]["replaces"].startswith("_erased-")
    assert study.enrolment(REPLACEMENT)["replaces"].startswith("_erased-")
    counts = study.group_status()
    assert sum(c["withdrawn"] for c in counts.values()) == 1 and sum(c["enrolled"] for c in counts.values()) == 5


def test_an_unknown_or_already_erased_id_is_refused_with_nothing_changed(tmp_path):
    study = _online_study(tmp_path / "study")
    snapshot = {p: p.read_bytes() for p in study.folder.rglob("*") if p.is_file()}
    with pytest.raises(UnknownParticipantError, match="is not enrolled in study 'short'.*nothing was erased"):
        erase_participant(study.folder, "5f0000000000000000000000")
    with pytest.raises(UnknownParticipantError, match="did you mean '5f3a9c2e8b1d4a0012345678'"):
        erase_participant(study.folder, "5F3A9C2E8B1D4A0012345678")
    with pytest.raises(TypeError, match="participant_id: expected"):
        erase_participant(study.folder, None)
    assert {p: p.read_bytes() for p in study.folder.rglob("*") if p.is_file()} == snapshot
    erase_participant(study.folder, REPLACEMENT)
    with pytest.raises(UnknownParticipantError, match="erased from study 'short' already"):
        erase_participant(study.folder, REPLACEMENT)


def test_the_command_line_answers_an_erasure_request(tmp_path):
    study = _online_study(tmp_path / "study")
    command = [sys.executable, "-m", "mt_widgets.study", "erase", str(study.folder)]
    unknown = subprocess.run(command + ["nobody"], capture_output=True, text=True, timeout=120)
    assert unknown.returncode == 2 and "'nobody' is not enrolled" in unknown.stderr
    done = subprocess.run(command + [REPLACEMENT], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and f"Erased participant '{REPLACEMENT}'" in done.stdout and "Kept:" in done.stdout
    assert REPLACEMENT not in study.participant_ids()
