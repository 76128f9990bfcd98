"""A full disk under the study logs and the class progress files (issue 46), as a fault, not a happy path.

What a database-grade log promises, checked here: a write the disk refuses (ENOSPC, EDQUOT, EIO) is
never acknowledged and leaves no half line (every file still parses, with exactly what was
acknowledged); the participant's page says that its step could not be saved and holds them there;
the experimenter's listing shows the fault; once there is room again the participant goes on, in
the same kernel, from the last saved step.

The lecture-sized test fills a real filesystem: a 4 MiB tmpfs, mounted where the machine lets this
process mount one (as root); elsewhere it is skipped, and the system-call-level tests below (a write
cut short and then refused, an fsync that fails) stand for it.
"""

from __future__ import annotations

import errno
import os
import shutil
import subprocess

import pytest

from disk_support import fill_filesystem
from mt_widgets.apps import StudyApp
from mt_widgets.classroom.progress import ClassFolderError, ProgressRecorder
from mt_widgets.study import NotSavedError, ParticipantLog, StudyFolder, jsonl, read_events
from mt_widgets.study import log as study_log
from mt_widgets.study.jsonl import read_jsonl

from .scripted import SHORT_PROTOCOL, act, short_protocol

PARTICIPANTS = [f"P{n:02d}" for n in range(1, 13)]


@pytest.fixture
def small_disk(tmp_path, monkeypatch):
    """A real filesystem of 4 MiB (tmpfs), unmounted afterwards; skipped where none can be mounted."""
    folder = tmp_path / "disk"
    folder.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a small tmpfs needs root (the system-call-level tests below stand for it)")
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m,mode=0755", "tmpfs", str(folder)],
                             capture_output=True, text=True, timeout=30)
    if mounted.returncode != 0:
        pytest.skip(f"this machine does not let the tests mount a tmpfs ({mounted.stderr.strip()})")
    # The folder check wants 20 MB free before a participant starts; this disk is smaller on purpose.
    monkeypatch.setattr(study_log, "MIN_FREE_BYTES", 64 * 1024)
    yield folder
    # Lazily: a page's log still open (its kernel would close it at exit) must not keep it mounted.
    subprocess.run(["umount", "--lazy", str(folder)], capture_output=True, timeout=30, check=True)


def _act_until_held(app, most: int = 200) -> int:
    """Acts as the participant until the page holds them (a step not saved); the actions taken."""
    for taken in range(most):
        if app.participant_view.held_by is not None:
            return taken
        try:
            act(app)
        except NotSavedError:
            pass  # a demonstration's callback: the episode keeps the arrow pending, the page holds
        assert app.participant_view.stopped_by is None, app.participant_view.stopped_by
    raise AssertionError(f"{app.session.participant}: no step was refused in {most} actions on a full disk")


def _try_again_button(app):
    body = app.body.children
    assert len(body) == 2 and body[1].description == "Try again", body
    return body[1]


@pytest.mark.slow  # twelve pages: about 4-6 s
def test_a_full_disk_holds_twelve_participants_loses_nothing_acknowledged_and_they_go_on_when_space_returns(
        small_disk, monkeypatch):
    protocol = small_disk / "short.toml"
    protocol.write_text(SHORT_PROTOCOL)
    folder = small_disk / "logs"
    apps = {}
    for number, participant in enumerate(PARTICIPANTS):
        app = StudyApp(protocol=str(protocol), log_folder=folder)
        app.start_participant(participant, group=("target", "control")[number % 2])
        for _ in range(1 + number % 3):  # mid-session, each at their own step
            act(app)
        apps[participant] = app
    assert StudyFolder(folder).storage_problem() is None

    filler = fill_filesystem(small_disk)
    held = {}
    for participant, app in apps.items():
        _act_until_held(app)
        view = app.participant_view
        assert isinstance(view.held_by, NotSavedError) and view.held_by.errno == errno.ENOSPC
        text = app.body.children[0].value
        assert "Your last step could not be saved" in text and "No space left on device" in text
        held[participant] = list(view.session.log.events)  # what the page acknowledged
    # Every log parses and holds exactly what its page acknowledged: nothing missing, nothing half.
    for participant, acknowledged in held.items():
        events, info = read_events(folder / f"{participant}.jsonl")
        assert events == acknowledged and info["torn_tail"] == 0
    # The experimenter's listing says so (the panel of the experimenter's page, the command line's status).
    problem = StudyFolder(folder).storage_problem()
    assert problem is not None and "No space left on device" in problem
    assert StudyFolder(folder).status_report().startswith("STORAGE FAULT: ")
    experimenter = StudyApp(protocol=str(protocol), log_folder=folder)
    experimenter.experimenter.list_button.click()
    assert "Storage fault" in experimenter.experimenter.listing.value
    # Pressing "Try again" while the disk is still full holds the participant again, in words.
    # (Its resume may still fit a line into the log's last page, the next step then failing.)
    _try_again_button(apps["P01"]).click()
    _act_until_held(apps["P01"])
    assert "It still could not be saved" in apps["P01"].body.children[0].value
    events, info = read_events(folder / "P01.jsonl")
    assert events[:len(held["P01"])] == held["P01"] and info["torn_tail"] == 0
    held["P01"] = list(apps["P01"].participant_view.session.log.events)
    assert events == held["P01"]

    os.unlink(filler)
    assert StudyFolder(folder).storage_problem() is None
    for participant, app in apps.items():
        _try_again_button(app).click()
        view = app.participant_view
        assert view.held_by is None and view.stopped_by is None
        for _ in range(3):  # each goes on (whole sessions of twelve would cost many seconds)
            act(app)
            assert view.held_by is None and view.stopped_by is None
        events, info = read_events(folder / f"{participant}.jsonl")
        assert events[:len(held[participant])] == held[participant] and info["torn_tail"] == 0
        assert events == app.session.log.events  # what was acknowledged since, too
        assert events[len(held[participant])]["type"] == "session_resumed"


def _cut_short_then_refused(fd, data):
    """A write the disk takes half of, then refuses: what a filling disk does to a long line."""
    os.write(fd, data[: len(data) // 2])
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _failing_once(fsync, code: int):
    calls = []

    def fsync_failing_once(fd):
        calls.append(fd)
        if len(calls) == 1:
            raise OSError(code, os.strerror(code))
        fsync(fd)

    return fsync_failing_once


def test_a_participant_event_the_disk_refuses_is_not_acknowledged_and_leaves_no_half_line(tmp_path, monkeypatch):
    log = ParticipantLog.create(tmp_path / "P01.jsonl", "short")
    log.append("session_started", group="target")
    before = (tmp_path / "P01.jsonl").read_bytes()
    with monkeypatch.context() as disk:
        disk.setattr(jsonl, "write_all", _cut_short_then_refused)
        with pytest.raises(NotSavedError, match=r"participant 'P01': this step could not be saved \(the disk "
                                                r"holding it is full \(No space left on device\)\)") as refused:
            log.append("screen_done", screen="welcome")
    assert refused.value.errno == errno.ENOSPC
    assert (tmp_path / "P01.jsonl").read_bytes() == before and len(log.events) == 1
    for code in (errno.EIO, errno.EDQUOT):  # an fsync that fails once: the write may not be on disk
        with monkeypatch.context() as disk:
            disk.setattr(os, "fsync", _failing_once(os.fsync, code))
            with pytest.raises(NotSavedError) as refused:
                log.append("screen_done", screen="welcome")
        assert refused.value.errno == code
        assert (tmp_path / "P01.jsonl").read_bytes() == before
    # Room again: the same session goes on, its next event right after the last acknowledged one.
    log.append("screen_done", screen="welcome")
    events, info = read_events(tmp_path / "P01.jsonl")
    assert [event["type"] for event in events] == ["session_started", "screen_done"] and info["torn_tail"] == 0


def test_a_log_that_cannot_even_be_cut_back_is_closed_and_a_resume_repairs_it(tmp_path, monkeypatch):
    log = ParticipantLog.create(tmp_path / "P01.jsonl", "short")
    log.append("session_started", group="target")
    with monkeypatch.context() as disk:
        disk.setattr(jsonl, "write_all", _cut_short_then_refused)
        disk.setattr(os, "ftruncate", lambda fd, length: (_ for _ in ()).throw(OSError(errno.EIO, "I/O error")))
        with pytest.raises(NotSavedError):
            log.append("screen_done", screen="welcome")
    assert log.closed  # nothing more is written through a log holding a half line
    again = ParticipantLog.open(tmp_path / "P01.jsonl")
    assert [event["type"] for event in again.events] == ["session_started"] and again.repaired_torn_bytes > 0
    again.close()


def test_a_class_progress_event_the_disk_refuses_is_a_clear_refusal_and_no_corruption(tmp_path, monkeypatch):
    recorder = ProgressRecorder(tmp_path / "class", student="ann")
    recorder.lesson("tutorial-01")
    before = recorder.path.read_bytes()
    with monkeypatch.context() as disk:
        disk.setattr(jsonl, "write_all", _cut_short_then_refused)
        with pytest.raises(ClassFolderError, match=r"could not be saved: the disk holding it is full .*nothing of "
                                                   r"it was written"):
            recorder.check("exercise-01", "first", passed=True)
    assert recorder.path.read_bytes() == before
    recorder.check("exercise-01", "first", passed=True)
    contents = read_jsonl(recorder.path)
    assert contents.tail is None and [line.value["kind"] for line in contents.lines] == ["lesson", "check"]
    assert "repaired_torn_bytes" not in contents.lines[1].value  # nothing half-written was left to repair


def test_the_study_folders_records_the_disk_refuses_leave_it_readable(tmp_path, monkeypatch):
    study = StudyFolder.create(tmp_path / "logs", short_protocol())
    study.enrol("P01", "target")
    enrolments = tmp_path / "logs" / "_enrolment.jsonl"
    before = enrolments.read_bytes()
    write_all = jsonl.write_all

    def full_for_enrolments(fd, data):
        # The folder's own check writes a probe file first: only the enrolments' disk is full here.
        (_cut_short_then_refused if os.readlink(f"/proc/self/fd/{fd}") == str(enrolments) else write_all)(fd, data)

    with monkeypatch.context() as disk:
        disk.setattr(jsonl, "write_all", full_for_enrolments)
        with pytest.raises(NotSavedError, match="_enrolment.jsonl: this record could not be saved"):
            study.enrol("P02", "control")
    assert enrolments.read_bytes() == before
    assert StudyFolder(tmp_path / "logs").participant_ids() == ["P01"]
    assert study.enrol("P02", "control")["participant"] == "P02"
