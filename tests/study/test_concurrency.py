"""Two participants run at the same time in two processes into one study folder."""

import subprocess
import sys
import time
from pathlib import Path

import pytest

from mt_widgets.study import StudyFolder, read_events
from mt_widgets.study.participants import block_assignment

from .scripted import short_protocol

# Each test runs sessions in subprocesses: seconds each.
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]

CHILD = """
import sys, time
from pathlib import Path
from mt_widgets.study import Session, StudyFolder, LogError, ParticipantIdError
from tests.study.scripted import run
folder, participant, go = sys.argv[1], sys.argv[2], Path(sys.argv[3])
(Path(folder) / f"ready-{participant}-{sys.argv[4]}").write_text("")
while not go.exists():
    time.sleep(0.005)
try:
    session = Session.start(StudyFolder(folder), participant)
except (LogError, ParticipantIdError) as error:
    print("REFUSED", error)
    sys.exit(3)
run(session)
session.close()
print("DONE")
"""


def _launch(folder, go, participants):
    processes = [subprocess.Popen([sys.executable, "-c", CHILD, str(folder), pid, str(go), str(n)], cwd=REPO,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for n, pid in enumerate(participants)]
    deadline = time.monotonic() + 60
    while len(list(Path(folder).glob("ready-*"))) < len(participants):
        assert time.monotonic() < deadline, "children did not start"
        assert all(p.poll() is None for p in processes), [p.communicate() for p in processes]
        time.sleep(0.01)
    go.write_text("")
    return [(p.wait(timeout=60), *p.communicate()) for p in processes]


def test_two_participants_in_two_processes_get_complete_separate_logs(tmp_path):
    folder = tmp_path / "study"
    protocol = short_protocol()
    StudyFolder.create(folder, protocol)
    results = _launch(folder, tmp_path / "go", ["P01", "P02"])
    assert [r[0] for r in results] == [0, 0], results
    study = StudyFolder(folder)
    records = {r["participant"]: r for r in study.enrolments()}
    assert sorted(r["index"] for r in records.values()) == [0, 1]
    for pid in ("P01", "P02"):
        events, info = read_events(study.log_path(pid))
        assert {e["participant"] for e in events} == {pid}
        assert events[0]["group"] == records[pid]["group"] == block_assignment(
            records[pid]["index"], protocol.groups, protocol.block_size, protocol.assignment_seed)
        assert [e["type"] for e in events].count("demonstration") == 15
        assert events[-1]["type"] == "session_finished" and info["torn_tail"] == 0


def test_the_same_new_participant_started_twice_at_once_runs_only_once(tmp_path):
    folder = tmp_path / "study"
    StudyFolder.create(folder, short_protocol())
    results = _launch(folder, tmp_path / "go", ["P01", "P01"])
    assert sorted(r[0] for r in results) == [0, 3], results
    assert "REFUSED" in next(r[1] for r in results if r[0] == 3)
    events, _ = read_events(folder / "P01.jsonl")
    assert [e["type"] for e in events].count("session_started") == 1
    assert len(StudyFolder(folder).enrolments()) == 1
