"""The [online] table: completion URLs and codes per outcome, the URL parameters that identify a
participant, and IDs from a URL refused (with nothing written) when they are not usable."""

import re
from pathlib import Path

import pytest

from mt_widgets.study import ParticipantIdError, ProtocolError, Session, StudyFolder, load_protocol, parse_protocol
from mt_widgets.study.online import OUTCOMES, outcome_of
from mt_widgets.study.participants import validate_url_participant_id

from .scripted import ONLINE, SHORT_PROTOCOL, online_protocol, run


def test_each_outcome_has_its_completion_url_and_code():
    online = online_protocol().online
    assert online.completion_url("completed") == "https://app.prolific.com/submissions/complete?cc=C1MPL3T3"
    assert online.completion_url("screened_out").endswith("cc=SCR33N")
    assert online.completion_url("ineligible") == online.completion_url("screened_out")  # the session's word
    assert online.completion_url("declined").endswith("cc=D3CL1N3D")
    assert online.completion_url("withdrawn") == "https://example.org/left?code=W1THDR4WN&x=1"
    assert len({online.completion(o).code for o in OUTCOMES}) == 4
    assert online.id_parameter == "PROLIFIC_PID" and online.recorded_parameters == ("STUDY_ID", "SESSION_ID")
    with pytest.raises(ValueError, match="outcome: expected one of"):
        online.completion_url("finished")
    assert parse_protocol(SHORT_PROTOCOL).online is None


def test_an_ending_without_a_url_ends_on_the_page_with_its_code_as_the_shipped_pilot_does():
    without = online_protocol(re.sub(r'\nurl = "[^"]*"', "", ONLINE, count=1))   # the first ending's url only
    first = next(o for o in OUTCOMES if without.online.completion(o).url is None)
    assert without.online.completion_url(first) is None and without.online.completion(first).code
    assert "url" not in without.online.as_dict()["completion"][first]
    assert sum(without.online.completion_url(o) is None for o in OUTCOMES) == 1
    pilot = load_protocol(str(Path(__file__).resolve().parents[2] / "notebooks" / "study_online_pilot.toml")).online
    assert [pilot.completion_url(o) for o in OUTCOMES] == [None] * 4   # no dead localhost page
    assert [pilot.completion(o).code for o in OUTCOMES] == ["PILOTDONE", "PILOTSCREEN", "PILOTDECLINE",
                                                            "PILOTWITHDRAW"]


def test_the_url_names_the_participant_and_what_is_recorded_with_them(tmp_path):
    protocol = online_protocol()
    arrival = protocol.online.participant_from_url({"PROLIFIC_PID": ["5f3a9c2e8b1d4a0012345678"],
                                                    "STUDY_ID": ["abc"], "SESSION_ID": ["s1"], "other": ["x"]})
    assert arrival.participant_id == "5f3a9c2e8b1d4a0012345678"
    assert arrival.parameters == {"STUDY_ID": "abc", "SESSION_ID": "s1"}
    study = StudyFolder.create(tmp_path / "study", protocol)
    with Session.arrive(study, arrival.participant_id, parameters=arrival.parameters) as session:
        run(session)
        assert outcome_of(session) == "completed"
    assert study.enrolment(arrival.participant_id)["url_parameters"] == {"STUDY_ID": "abc", "SESSION_ID": "s1"}
    generic = online_protocol(ONLINE.replace('"prolific"', '"participant"')).online
    assert generic.participant_from_url({"participant": "P07"}).participant_id == "P07"


def test_a_withdrawn_session_ends_on_the_withdrawal_url(tmp_path):
    protocol = online_protocol()
    study = StudyFolder.create(tmp_path / "study", protocol)
    with Session.arrive(study, "P01") as session:
        session.withdraw()
        assert protocol.online.completion_url(outcome_of(session)).endswith("W1THDR4WN&x=1")
    with Session.arrive(study, "P02") as running, pytest.raises(ValueError, match="still running"):
        outcome_of(running)


@pytest.mark.parametrize("value, message", [
    (None, "does not say who you are"),
    ("", "empty"),
    ("   ", "empty"),
    ("x" * 65, "65 characters long"),
    ("../../etc/passwd", "file path"),
    ("a/b", "file path"),
    ("C:evil", "file path"),
    (".hidden", "file path"),
    ("~root", "file path"),
    ("P07\n", "control characters"),
    ("P\x0007", "control characters"),
    ("P07\x7f", "control characters"),
    ("P 07", "not a usable ID"),
    ("Pé07", "not a usable ID"),
    ("con", "not a usable ID"),
])
def test_ids_from_a_url_are_refused_with_a_message_and_nothing_is_written(tmp_path, value, message):
    study = StudyFolder.create(tmp_path / "study", online_protocol())
    before = sorted(p.name for p in study.folder.iterdir())
    with pytest.raises(ParticipantIdError, match=message) as refused:
        study.protocol.online.participant_from_url({"PROLIFIC_PID": value, "STUDY_ID": "s"})
    assert "Nothing was recorded" in str(refused.value)
    assert "\n" not in str(refused.value) and "\x00" not in str(refused.value)
    with pytest.raises(ParticipantIdError):
        validate_url_participant_id(value)
    assert sorted(p.name for p in study.folder.iterdir()) == before


def test_recorded_parameters_and_repeated_ids_are_checked_too():
    online = online_protocol().online
    with pytest.raises(ParticipantIdError, match="2 times"):
        online.participant_from_url({"PROLIFIC_PID": ["a1", "b2"]})
    with pytest.raises(ParticipantIdError, match="SESSION_ID.*control characters"):
        online.participant_from_url({"PROLIFIC_PID": "a1", "SESSION_ID": "s\n1"})
    with pytest.raises(TypeError, match="query"):
        online.participant_from_url("PROLIFIC_PID=a1")


@pytest.mark.parametrize("change, message", [
    (('identify = "prolific"', 'identify = "mturk"'), "online.identify: expected one of"),
    (('url = "https://example.org/left', 'url = "ftp://example.org/left'), "expected an https:// URL"),
    (('code = "SCR33N"', 'code = "has space"'), "expected a code of letters"),
    (("[online.completion.declined]", "[online.completion.declinedx]"), "unknown field"),
])
def test_a_bad_online_table_is_refused_naming_the_field(change, message):
    with pytest.raises(ProtocolError, match=message):
        online_protocol(ONLINE.replace(*change))


RETURN = 'identify = "prolific"\nreturn_url = "https://app.prolific.com/submissions"'


def test_the_return_url_is_optional_and_read_back():
    assert online_protocol().online.return_url is None
    online = online_protocol(ONLINE.replace('identify = "prolific"', RETURN)).online
    assert online.return_url == "https://app.prolific.com/submissions"
    assert online.as_dict()["return_url"] == online.return_url
    assert "return_url" not in online_protocol().online.as_dict()


@pytest.mark.parametrize("url", ["http://app.prolific.com/submissions", "javascript:alert(1)", "https://",
                                 "app.prolific.com/submissions", "https://a.org/x' onclick='y", ""])
def test_a_return_url_that_is_not_https_is_refused_naming_the_field(url):
    with pytest.raises(ProtocolError, match=r"online.return_url: (expected an https:// URL|expected)") as caught:
        online_protocol(ONLINE.replace('identify = "prolific"', f'identify = "prolific"\nreturn_url = "{url}"'))
    assert caught.value.field == "online.return_url"


def test_every_outcome_needs_its_url():
    text = ONLINE.split("[online.completion.withdrawn]")[0]
    with pytest.raises(ProtocolError, match="online.completion.withdrawn: missing required table"):
        online_protocol(text)


def test_an_error_in_the_online_table_names_its_line():
    text = SHORT_PROTOCOL + ONLINE.replace('code = "SCR33N"', 'code = "a b"')
    with pytest.raises(ProtocolError) as caught:
        parse_protocol(text, "y.toml")
    assert text.splitlines()[caught.value.line - 1] == 'code = "a b"'
    assert caught.value.field == "online.completion.screened_out.code"
