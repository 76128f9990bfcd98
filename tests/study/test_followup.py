"""Sessions as protocol data: a participant completes main, comes back within the window for the
follow-up, keeps their group and sees only that session; outside the window the protocol's rule holds."""

import datetime as dt

import pytest

from mt_widgets.study import LogError, ProtocolError, Session, StudyFolder, parse_protocol, read_events
from mt_widgets.study.session import WindowError, timeline
from mt_widgets.study.session_plan import parse_duration

from .scripted import FOLLOWUP_SESSION, SHORT_PROTOCOL, followup_protocol, run, run_all

DAY = dt.timedelta(days=1)


def finished_at(study, participant, session=None):
    events, _ = read_events(study.log_path(participant, session))
    stamp = next(e["time"] for e in events if e["type"] == "session_finished")
    return dt.datetime.fromisoformat(stamp.replace("Z", "+00:00"))


def test_a_protocol_lists_its_sessions_with_their_own_phases_and_windows():
    protocol = followup_protocol()
    assert [s.id for s in protocol.sessions] == ["main", "followup-1w"]
    main, followup = protocol.sessions
    assert [p.id for p in protocol.phases] == [p.id for p in main.phases] == ["A", "B", "C"]
    assert [p.id for p in followup.phases] == ["F1", "F2"]
    assert [p.session for p in protocol.all_phases] == ["main"] * 3 + ["followup-1w"] * 2
    # A follow-up phase draws states at its own seed position, after every main phase.
    assert [p.states_index for p in protocol.all_phases] == [0, 1, 2, 3, 4]
    assert followup.window.earliest_s == 7 * 86400 and followup.window.latest_s == 14 * 86400
    assert followup.bids_label == "followup1w"
    kinds = [slot.kind for slot in timeline(protocol, session="followup-1w")]
    assert "practice" not in kinds and "consent" not in kinds and kinds[:2] == ["welcome", "instructions"]
    assert kinds.count("phase_intro") == 2 and kinds[-2:] == ["step", "thank_you"]
    # A one-session protocol is one session, "main", with the same hash as before sessions existed.
    assert [s.id for s in parse_protocol(SHORT_PROTOCOL).sessions] == ["main"]


def test_a_participant_completes_main_then_the_followup_after_a_simulated_week(tmp_path):
    study = StudyFolder.create(tmp_path / "study", followup_protocol())
    with Session.arrive(study, "P01") as session:
        assert session.plan.id == "main"
        group = session.group
        run_all(session)
        thanks = session.current_step()
        code = thanks.reentry_code
        assert session.completed and code and thanks.next_session["id"] == "followup-1w"
        assert "1 w to 2 w after the previous session" == thanks.next_session["window"]
    ended = finished_at(study, "P01")

    # Too early (a day later): refused, in the protocol's words, and nothing is written.
    with pytest.raises(WindowError, match="Too early: come back on") as refused:
        Session.arrive(study, "P01", now=ended + DAY)
    assert refused.value.check.status == "early" and refused.value.session == "followup-1w"
    assert not study.log_path("P01", "followup-1w").exists()

    # Eight days later, by the re-entry code (typed loosely): the follow-up, same group.
    with Session.arrive(study, reentry_code=code.lower().replace("-", " "), now=ended + 8 * DAY) as followup:
        assert followup.plan.id == "followup-1w" and followup.group == group
        assert followup.window["status"] == "open"
        steps = []
        while not followup.finished:
            steps.append(followup.current_step())
            run(followup, stop_after=1) if steps[-1].kind != "questionnaire" else run_all(followup)
        assert followup.completed
        assert {s.phase for s in steps if s.phase} == {"F1", "F2"}  # only this session's phases
        assert followup.current_step().reentry_code is None  # the last session: no code to come back with
    events, _ = read_events(study.log_path("P01", "followup-1w"))
    assert events[0]["session"] == "followup-1w" and events[0]["group"] == group
    assert events[0]["participant"] == "P01"
    assert [e["phase"] for e in events if e["type"] == "episode_finished"] == ["F1", "F2"]
    # The main log is untouched and the participant counts as completed only now.
    assert study.status()[0]["state"] == "completed"
    # Arriving again after the last session: that session, finished.
    with Session.arrive(study, "P01", now=ended + 9 * DAY) as again:
        assert again.plan.id == "followup-1w" and again.completed


def test_a_reload_mid_followup_resumes_it_and_an_unfinished_main_is_resumed_not_skipped(tmp_path):
    study = StudyFolder.create(tmp_path / "study", followup_protocol())
    with Session.arrive(study, "P01") as session:
        session.advance()
    # Unfinished main: whatever the date, the participant continues main.
    with Session.arrive(study, "P01", now=dt.datetime.now(dt.timezone.utc) + 30 * DAY) as session:
        assert session.plan.id == "main" and session.current_step().kind == "consent"
        run_all(session)
    ended = finished_at(study, "P01")
    with Session.arrive(study, "P01", now=ended + 10 * DAY) as followup:
        followup.advance()
        followup.advance()
        at = followup.current_step().kind
    with Session.arrive(study, "P01", now=ended + 10 * DAY) as again:
        assert again.plan.id == "followup-1w" and again.current_step().kind == at == "phase_intro"


@pytest.mark.parametrize("rule", ["refuse", "flag"])
def test_too_late_is_refused_or_flagged_as_the_protocol_says(tmp_path, rule):
    study = StudyFolder.create(tmp_path / "study", followup_protocol(late=rule))
    with Session.arrive(study, "P01") as session:
        run_all(session)
    ended = finished_at(study, "P01")
    late = ended + 20 * DAY
    if rule == "refuse":
        with pytest.raises(WindowError, match="cannot be run any more") as refused:
            Session.arrive(study, "P01", now=late)
        assert refused.value.check.status == "late"
        assert not study.log_path("P01", "followup-1w").exists()
    else:
        with Session.arrive(study, "P01", now=late) as followup:
            assert followup.window["status"] == "late" and followup.window["action"] == "flag"
        first = read_events(study.log_path("P01", "followup-1w"))[0][0]
        assert first["window"]["status"] == "late" and first["window"]["delay_s"] == pytest.approx(20 * 86400, abs=1)
        assert first["arrived_at"].startswith(late.isoformat()[:16])


def test_groups_stay_hidden_from_the_blinded_participant_list(tmp_path):
    study = StudyFolder.create(tmp_path / "study", followup_protocol())
    for pid in ("P01", "P02"):
        Session.arrive(study, pid).close()
    rows = study.participants()
    assert [r["participant"] for r in rows] == ["P01", "P02"]
    flat = repr(rows)
    for hidden in ("group", "target", "control", "block", "reentry", "index"):
        assert hidden not in flat
    assert rows[0]["sessions"] == {"main": "in progress", "followup-1w": "not started"}
    assert {r["group"] for r in study.participants(blinded=False)} <= {"target", "control"}
    with pytest.raises((TypeError, ValueError), match="blinded"):  # as_bool: ValueError today, TypeError per issue 21
        study.participants(blinded="no")


def test_arrival_refuses_unknown_codes_ids_and_naive_clocks(tmp_path):
    study = StudyFolder.create(tmp_path / "study", followup_protocol())
    Session.arrive(study, "P01").close()
    with pytest.raises(LogError, match="no participant of this study has this code"):
        Session.arrive(study, reentry_code="ABCD-EFGH")
    with pytest.raises(ValueError, match="8-character code"):
        Session.arrive(study, reentry_code="nonsense")
    with pytest.raises(LogError, match="not enrolled"):
        Session.arrive(study, "P09", enrol_new=False)
    with pytest.raises(ValueError, match="naive"):
        Session.arrive(study, "P01", now=dt.datetime(2030, 1, 1))
    with pytest.raises(TypeError, match="now"):
        Session.arrive(study, "P01", now="tomorrow")
    with pytest.raises(ValueError, match="exactly one"):
        Session.arrive(study)
    assert study.participant_ids() == ["P01"]


def test_a_withdrawn_participant_cannot_come_back_for_a_followup(tmp_path):
    study = StudyFolder.create(tmp_path / "study", followup_protocol())
    with Session.arrive(study, "P01") as session:
        session.withdraw("moving away")
    with pytest.raises(LogError, match="withdrew"):
        Session.arrive(study, "P01", now=dt.datetime.now(dt.timezone.utc) + 8 * DAY)


@pytest.mark.parametrize("change, message", [
    ('earliest = "7d"', None),
    ('earliest = "a week"', "sessions\\[0\\].window.earliest: expected a number and a unit"),
    ('latest = "14d"', None),
    ('too_early = "refuse"', None),
])
def test_window_fields_are_checked(change, message):
    key = change.split(" =")[0]
    text = SHORT_PROTOCOL + FOLLOWUP_SESSION.replace("{late}", "flag")
    lines = [line if not line.startswith(key + " =") else change for line in text.splitlines()]
    if message is None:
        parse_protocol("\n".join(lines))
    else:
        with pytest.raises(ProtocolError, match=message):
            parse_protocol("\n".join(lines))


def test_bad_sessions_are_refused_with_the_field_named():
    base = SHORT_PROTOCOL + FOLLOWUP_SESSION.replace("{late}", "flag")
    with pytest.raises(ProtocolError, match="latest: expected latest >= earliest"):
        parse_protocol(base.replace('latest = "14d"', 'latest = "1d"'))
    with pytest.raises(ProtocolError, match="expected a unique phase id"):
        parse_protocol(base.replace('id = "F1"', 'id = "A"'))
    with pytest.raises(ProtocolError, match="session id of its own"):
        parse_protocol(base.replace('id = "followup-1w"', 'id = "ma_in"'))
    with pytest.raises(ProtocolError, match="too_late: expected one of"):
        parse_protocol(base.replace('too_late = "flag"', 'too_late = "later"'))
    with pytest.raises(ProtocolError, match="welcome: missing required field"):
        parse_protocol(base.replace('welcome = "Welcome back."', ''))


def test_durations_read_in_words():
    assert parse_duration("36h") == 36 * 3600 and parse_duration("1w") == 7 * 86400
    assert parse_duration("90s") == 90 and parse_duration("30min") == 1800
    with pytest.raises(ValueError, match="number and a unit"):
        parse_duration("7 days")
    with pytest.raises(TypeError):
        parse_duration(7)
