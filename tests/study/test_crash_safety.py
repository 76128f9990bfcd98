"""Crash safety: a session SIGKILL-ed at many random points and resumed each time logs exactly
what an uninterrupted run logs: the same demonstrations, none lost, none duplicated.

Each attempt is a forked child process (everything already imported, so an attempt costs
milliseconds instead of a second of imports) that resumes the participant and is killed with
SIGKILL: by itself inside a log write (before it, half-way through a line, or after the
bytes but before fsync), or by the parent after a random delay.
"""

import os
import signal
import time

import numpy as np
import pytest

from mt_widgets.study import LogError, Session, StudyFolder, read_events
from mt_widgets.study import jsonl as jsonl_module

from .scripted import demonstrations, run, short_protocol


def _child(folder, participant, kill_at, mode):
    """Runs in the forked child: resume (or start) and drive; never returns."""
    status = 1
    try:
        if kill_at is not None:
            real_write = jsonl_module.write_all
            count = [0]

            def dying_write(fd, data):
                count[0] += 1
                if count[0] == kill_at:
                    if mode == "torn":
                        real_write(fd, data[: max(1, len(data) // 2)])
                    elif mode == "unsynced":
                        real_write(fd, data)
                    os.kill(os.getpid(), signal.SIGKILL)
                real_write(fd, data)
            jsonl_module.write_all = dying_write
        study = StudyFolder(folder)
        if study.log_path(participant).exists() or participant in study.participant_ids():
            session = Session.resume(study, participant, lock_timeout_s=5.0)
        else:
            session = Session.start(study, participant, group="target")
        run(session)
        session.close()
        status = 0
    finally:
        os._exit(status)


def _attempt(folder, participant, kill_at=None, mode=None, kill_after_s=None) -> bool:
    """One forked attempt; True when it ran to the end, False when it was killed."""
    pid = os.fork()
    if pid == 0:
        _child(folder, participant, kill_at, mode)
    if kill_after_s is not None:
        time.sleep(kill_after_s)
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        assert os.WTERMSIG(status) == signal.SIGKILL
        return False
    assert os.WEXITSTATUS(status) == 0, "the scripted session failed (not killed) in the child"
    return True


def _summary(events):
    finished = [(e["phase"], e["episode"], tuple(np.ravel(e["theta_hat"]))) for e in events
                if e["type"] == "episode_finished"]
    starts = [(e["phase"], e["episode"], tuple(np.ravel(e["query_states"]))) for e in events
              if e["type"] == "episode_started"]
    return demonstrations(events), finished, starts


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    folder = tmp_path_factory.mktemp("reference")
    study = StudyFolder.create(folder, short_protocol())
    session = Session.start(study, "P01", group="target")
    run(session)
    session.close()
    return _summary(session.events)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_killed_and_resumed_sessions_log_exactly_the_uninterrupted_demonstrations(tmp_path, reference, seed):
    StudyFolder.create(tmp_path, short_protocol())
    rng = np.random.default_rng(seed)
    kills, modes_seen = 0, set()
    for attempt in range(200):
        if rng.random() < 0.7:
            mode = ("before", "torn", "unsynced")[attempt % 3]
            done = _attempt(tmp_path, "P01", kill_at=int(rng.integers(1, 7)), mode=mode)
            modes_seen.add(mode)
        else:
            done = _attempt(tmp_path, "P01", kill_after_s=float(rng.uniform(0.0, 0.03)))
        if done:
            break
        kills += 1
    assert done, "the session never finished"
    assert kills >= 8 and modes_seen == {"before", "torn", "unsynced"}
    events, info = read_events(tmp_path / "P01.jsonl")
    # Exactly one end (a kill just after it, before the process exited, makes one more resume).
    assert [e["type"] for e in events].count("session_finished") == 1
    demos, finished, starts = _summary(events)
    assert demos == reference[0], "demonstrations lost, duplicated or changed"
    assert finished == reference[1] and starts == reference[2]
    keys = [d[:3] for d in demos]
    assert len(keys) == len(set(keys))
    resumes = [e for e in events if e["type"] == "session_resumed"]
    assert 1 <= len(resumes) <= kills
    assert any(e["repaired_torn_line"] for e in resumes), "no torn line was produced and repaired"
    assert info["repaired_lines"]


def _enrol_and_die(folder, participant, mode):
    """Forks a child that enrols ``participant`` and is SIGKILL-ed inside the enrolment write."""
    pid = os.fork()
    if pid == 0:
        try:
            real_write = jsonl_module.write_all

            def dying_write(fd, data):
                if b'"participant"' not in data:  # the folder's write probe, not the record
                    return real_write(fd, data)
                if mode == "torn":
                    real_write(fd, data[: len(data) // 2])
                elif mode == "unterminated":
                    real_write(fd, data[:-1])  # every byte but the newline
                os.kill(os.getpid(), signal.SIGKILL)
            jsonl_module.write_all = dying_write
            StudyFolder(folder).enrol(participant)
        finally:
            os._exit(1)
    _, status = os.waitpid(pid, 0)
    assert os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL


def test_a_kill_during_enrolment_loses_neither_that_slot_nor_the_next_participant(tmp_path):
    study = StudyFolder.create(tmp_path, short_protocol())
    study.enrol("P01")
    _enrol_and_die(tmp_path, "P02", "torn")  # half a line, no newline: P02 never started
    session = Session.start(study, "P03")
    session.close()
    _enrol_and_die(tmp_path, "P04", "torn")
    _enrol_and_die(tmp_path, "P05", "torn")  # two tears in a row, repaired by the next enrolment
    study.enrol("P06")
    records = study.enrolments()
    assert [r["participant"] for r in records] == ["P01", "P03", "P06"]
    # Enrolment numbers and block slots are handed out once each, in order: randomisation holds.
    assert [r["index"] for r in records] == [0, 1, 2] and [r["block_slot"] for r in records] == [0, 1, 2]
    assert study.enrolment("P03") == session.enrolment
    Session.resume(study, "P03").close()
    # The torn enrolment's ID was never used: it can still be enrolled.
    assert study.enrol("P02")["index"] == 3


def test_an_enrolment_missing_only_its_newline_is_kept_and_the_next_starts_a_line(tmp_path):
    study = StudyFolder.create(tmp_path, short_protocol())
    _enrol_and_die(tmp_path, "P01", "unterminated")
    assert study.participant_ids() == ["P01"]
    study.enrol("P02")
    assert study.participant_ids() == ["P01", "P02"]


def test_damage_in_the_middle_of_the_enrolment_file_is_reported_not_skipped(tmp_path):
    study = StudyFolder.create(tmp_path, short_protocol())
    for participant in ("P01", "P02", "P03", "P04"):
        study.enrol(participant)
    path = tmp_path / "_enrolment.jsonl"
    p01, p02, p03, p04, _ = path.read_bytes().split(b"\n")
    # What the old enrol() wrote after a kill: P03 glued onto half of P02, then P04 as usual.
    path.write_bytes(b"\n".join([p01, p02[:20] + p03, p04, b""]))
    with pytest.raises(LogError, match=r"_enrolment.jsonl, line 2: not an enrolment record"):
        study.enrolments()
    with pytest.raises(LogError, match="line 2"):
        study.enrol("P05")
