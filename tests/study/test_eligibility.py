"""An answer outside an item's eligible band (an age under 18) screens out with the protocol's words.

The band is protocol data (``eligible_minimum`` / ``eligible_maximum`` on a number item), apart
from the item's valid range: 17 is a valid age, so the form takes it, and the session ends as
``ineligible`` (logged ``screened_out``), the same outcome as a screener's answer.
"""

import re

import pytest

from mt_widgets.study import LogError, ProtocolError, Session, StudyFolder, load_protocol, parse_protocol, read_events
from mt_widgets.study.online import outcome_of

from .scripted import STEPS, _with_steps, run_to_end_one

PAPER = ("paper-sim", "paper-uarm", "paper-sim-followup")
AGE_BAND = 'kind = "number"\nprompt = "Hours of sleep"\nminimum = 0\nmaximum = 24\n'


def _to_demographics(session):
    answers = {"eligibility": {"robotics_background": "no"}}
    while session.current_step().kind != "demographics":
        run_to_end_one(session, answers)


@pytest.mark.parametrize("name", PAPER)
def test_the_paper_protocols_take_any_age_but_keep_adults_only_and_say_why_in_plain_words(name):
    protocol = load_protocol(name)
    age = protocol.step("demographics").item("age")
    assert (age.minimum, age.maximum, age.eligible_minimum, age.eligible_maximum) == (0, 120, 18, None)
    assert age.check(17) == 17  # a valid answer, not refused as a typo
    assert not age.is_eligible(17) and age.is_eligible(18) and age.is_eligible(120)
    words = protocol.texts["ineligible"]
    assert "18 or older" in words and "ends here" in words
    assert not re.search(r"\b(ineligible|eligibility|criteria|screened)\b", words, re.IGNORECASE)


def test_a_17_year_old_is_screened_out_with_the_protocols_message_and_it_is_logged(tmp_path):
    protocol = load_protocol("paper-sim")
    study = StudyFolder.create(tmp_path / "s", protocol)
    session = Session.start(study, "P01")
    _to_demographics(session)
    step = session.submit_answers({"age": 17, "sex": "female"})
    assert step.kind == "ended" and step.text == protocol.texts["ineligible"]
    assert session.ended == "ineligible" and session.finished and not session.completed
    assert outcome_of(session) == "screened_out"  # the online page's completion URL
    session.close()
    events, _ = read_events(study.log_path("P01"))
    done = [e for e in events if e["type"] == "step_done" and e["step"] == "demographics"]
    assert len(done) == 1 and done[0]["eligible"] is False and done[0]["answers"]["age"] == 17
    screened = [e for e in events if e["type"] == "screened_out"]
    assert len(screened) == 1 and screened[0]["step"] == "demographics" and screened[0]["answers"]["age"] == 17
    assert events[-1]["type"] == "screened_out"  # nothing after it: no instructions, no episode
    assert study.outcomes()["P01"]["outcome"] == "ineligible"
    with pytest.raises(LogError, match="screened out"):
        Session.resume(study, "P01")


def test_an_18_year_old_continues_to_the_task(tmp_path):
    study = StudyFolder.create(tmp_path / "s", load_protocol("paper-sim"))
    session = Session.start(study, "P01")
    _to_demographics(session)
    step = session.submit_answers({"age": 18, "sex": "male"})
    assert step.kind == "instructions" and session.ended is None
    session.close()
    events, _ = read_events(study.log_path("P01"))
    done = [e for e in events if e["type"] == "step_done" and e["step"] == "demographics"]
    assert done[0]["eligible"] is True and not any(e["type"] == "screened_out" for e in events)


def test_a_step_without_a_band_logs_no_eligibility(tmp_path):
    study = StudyFolder.create(tmp_path / "s", parse_protocol(_with_steps(STEPS), "steps.toml"))
    session = Session.start(study, "P01")
    answers = {"screen": {"background": "no"}, "about": {"age": 30, "sex": "male"}}
    while session.current_step().kind != "instructions":
        run_to_end_one(session, answers)
    session.close()
    events, _ = read_events(study.log_path("P01"))
    assert "eligible" not in next(e for e in events if e.get("step") == "about" and e["type"] == "step_done")


def _refused(extra: str, pattern: str) -> ProtocolError:
    text = _with_steps(STEPS.replace(AGE_BAND, AGE_BAND + extra) if extra.startswith("eligible_")
                       else extra)
    with pytest.raises(ProtocolError) as caught:
        parse_protocol(text, "bad.toml")
    error = caught.value
    line = next(i for i, row in enumerate(text.splitlines(), start=1) if re.search(pattern, row))
    assert error.line == line and "bad.toml" in str(error)
    return error


@pytest.mark.parametrize("band, field, words", [
    ("eligible_maximum = 30\n", "eligible_maximum", "valid range [0, 24] (minimum, maximum), got 30"),
    ("eligible_minimum = -1\n", "eligible_minimum", "valid range [0, 24] (minimum, maximum), got -1"),
    ("eligible_minimum = 8\neligible_maximum = 6\n", "eligible_maximum", "eligible_maximum >= eligible_minimum"),
    ('eligible_minimum = "six"\n', "eligible_minimum", "number"),
])
def test_an_eligible_band_outside_the_valid_range_is_refused_naming_the_field(band, field, words):
    error = _refused(band, "^" + band.splitlines()[-1].split(" =")[0] + " =")
    assert error.field == f"after[0].items[1].{field}" and words in str(error)


def test_a_band_on_an_item_that_is_not_a_number_is_refused_naming_the_field():
    text = STEPS.replace('eligible = ["no"]\n', 'eligible = ["no"]\neligible_minimum = 18\n')
    error = _refused(text, "^eligible_minimum =")
    assert error.field == "before[3].items[0].eligible_minimum" and "only on a number item" in str(error)
    assert "choice item" in str(error)


def test_a_number_item_of_a_screener_needs_a_band():
    text = STEPS.replace('kind = "choice"\nprompt = "Robotics before?"\noptions = ["no", "yes"]\neligible = ["no"]\n',
                         'kind = "number"\nprompt = "Your age"\nminimum = 0\nmaximum = 120\n')
    error = _refused(text, r"^\[\[before\.items\]\]")  # the item's table: the field it lacks
    assert error.field == "before[3].items[0].eligible_minimum" and "band" in str(error)
    screener = parse_protocol(_with_steps(text.replace("maximum = 120\n", "maximum = 120\neligible_minimum = 18\n")),
                              "ok.toml").step("screen")
    assert screener.item("background").eligible_minimum == 18
