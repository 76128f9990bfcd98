"""Versioned logs: a study folder written by today's format-1 code (tests/data/study-v1, commit
eeb8693) is read through the explicit migration; a newer format is refused; new files carry theirs."""

import json
import shutil
from pathlib import Path

import pytest

from mt_widgets.study import LogError, Session, StudyFolder, export_bids, read_events, read_log, read_study
from mt_widgets.study.pseudonyms import code_of
from mt_widgets.study.schema import FORMAT_1_GUIDANCE_MODALITY, LOG_FORMAT, migrate_events
from mt_widgets.study.tidy import episode_errors

from .scripted import run_all, short_protocol

V1 = Path(__file__).resolve().parents[1] / "data" / "study-v1"


@pytest.fixture
def v1(tmp_path):
    folder = tmp_path / "study-v1"
    shutil.copytree(V1, folder)
    return folder


def test_the_fixture_is_format_1_as_written():
    meta = json.loads((V1 / "study.json").read_text())
    assert meta["format"] == 1
    raw, _ = read_events(V1 / "P01.jsonl")
    assert "format" not in raw[0] and "session" not in raw[0]
    assert all("format" not in json.loads(line) for line in (V1 / "_enrolment.jsonl").read_text().splitlines())


def test_a_format_1_study_reads_through_the_migration(v1):
    study = StudyFolder(v1)
    assert study.meta["format"] == LOG_FORMAT and study.meta["migrated_from"] == 1
    assert [r["format"] for r in study.enrolments()] == [2, 2, 2]
    assert study.outcomes()["P02"]["outcome"] == "withdrawn" and study.outcomes()["P02"]["migrated_from"] == 1
    events = read_log(v1 / "P01.jsonl")
    assert events[0]["session"] == "main" and events[0]["format"] == 2 and events[0]["migrated_from"] == 1
    started = [e for e in events if e["type"] == "episode_started"]
    assert len(started) == 5 and {e["guidance_modality"] for e in started} == {"arrows+words"}
    episodes, demonstrations = read_study(v1)
    assert {r["participant"] for r in episodes} <= {"P01", "P03"}  # P02 withdrew: left out
    assert len([r for r in episodes if r["participant"] == "P01"]) == 5
    assert {r["session"] for r in episodes} == {"main"}
    assert len(demonstrations) >= 5 * 2
    assert [r["state"] for r in study.status()] == ["completed", "withdrawn", "in progress"]


def test_a_format_1_log_is_continued_and_only_its_old_events_are_migrated(v1):
    study = StudyFolder(v1)
    with Session.resume(study, "P03") as session:
        run_all(session)
        assert session.completed
    raw, _ = read_events(v1 / "P03.jsonl")
    resumed = next(e for e in raw if e["type"] == "session_resumed")
    assert resumed["format"] == LOG_FORMAT and "format" not in raw[0]
    events = read_log(v1 / "P03.jsonl")
    assert events[0]["session"] == "main" and sum(e["type"] == "episode_finished" for e in events) == 5
    assert len([r for r in read_study(v1)[0] if r["participant"] == "P03"]) == 5


def test_a_format_1_study_exports_to_bids(v1, tmp_path):
    out = export_bids(v1, tmp_path / "bids")
    code = code_of(v1, "P01")
    assert (out / f"sub-{code}" / "beh" / f"sub-{code}_task-short_beh.tsv").is_file()


def test_the_missing_guidance_modality_of_old_logs_is_the_migrations_one_stated_value():
    events = [{"seq": 0, "type": "session_started", "group": "target"},
              {"seq": 1, "type": "episode_started", "phase_index": 0, "episode": 1}]
    migrated = migrate_events(events, "main", "old.jsonl")
    assert migrated[1]["guidance_modality"] == FORMAT_1_GUIDANCE_MODALITY == "arrows+words"
    assert "guidance_modality" not in events[1]  # the events read are not changed in place


def test_a_newer_format_is_refused_naming_the_file(v1, tmp_path):
    meta = json.loads((v1 / "study.json").read_text())
    meta["format"] = 99
    (v1 / "study.json").write_text(json.dumps(meta))
    with pytest.raises(LogError, match="format 99.*update mt-widgets"):
        StudyFolder(v1)
    log = tmp_path / "X.jsonl"
    log.write_text(json.dumps({"seq": 0, "type": "session_started", "format": 3, "participant": "X"}) + "\n")
    with pytest.raises(LogError, match="X.jsonl, seq 0: written with schema format 3"):
        read_log(log)


def test_new_files_carry_the_current_format(tmp_path):
    study = StudyFolder.create(tmp_path / "study", short_protocol())
    Session.start(study, "P01").close()
    assert json.loads((study.folder / "study.json").read_text())["format"] == LOG_FORMAT
    assert json.loads((study.folder / "_enrolment.jsonl").read_text())["format"] == LOG_FORMAT
    first = read_events(study.log_path("P01"))[0][0]
    assert first["format"] == LOG_FORMAT and first["session"] == "main" and "migrated_from" not in first


def test_a_log_written_with_the_one_teaching_error_still_reads_as_theta_error(v1):
    # Logs before issue 42 hold one teaching_error: Theta's error for ridge (it has a theta_hat).
    logged = [e for e in read_log(v1 / "P01.jsonl") if e["type"] == "episode_finished"]
    assert logged and all("teaching_error" in e and "policy_risk" not in e for e in logged)
    rows = [r for r in read_study(v1)[0] if r["participant"] == "P01"]
    assert [r["theta_error"] for r in rows] == [e["teaching_error"] for e in logged]
    assert all(r["policy_risk"] is None for r in rows)


def test_an_old_error_is_the_policy_risk_where_the_episode_has_no_theta():
    assert episode_errors({"teaching_error": 0.5, "theta_hat": None}) == (None, 0.5)
    assert episode_errors({"teaching_error": 0.5, "theta_hat": [[1.0]]}) == (0.5, None)
    assert episode_errors({"theta_error": None, "policy_risk": 0.25, "theta_hat": None}) == (None, 0.25)
