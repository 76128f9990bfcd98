"""The participant-only pages, kernel-free: the online page (enrolled from its URL, resumed on a
reload, ended on its outcome's completion URL) and the lab page (the panel behind the
experimenter's code; a participant's reload resumes them, never the panel)."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import parse_qs, urlencode

import pytest
from ipywidgets.widgets.widget import _instances as live_widgets  # every widget the kernel holds

from blinding_support import participant_texts
from mt_widgets.apps.study import ExperimenterPanel, LabStudyPage, OnlineStudyPage, StudyApp
from mt_widgets.apps.study.lab_page import MAX_ATTEMPTS
from mt_widgets.apps.study.navigation import PageAddress
from mt_widgets.study import Session, StudyFolder, load_protocol, read_events

from .support import PILOT, act, buttons_in, pilot_with_completion_urls, prolific

GROUP_WORDS = re.compile(r"\b(target|control|group|groups|condition)\b", re.IGNORECASE)


def new_widgets(build):
    before = set(live_widgets)
    result = build()
    return result, [w for key, w in live_widgets.items() if key not in before]


def page_addresses(page, action: str) -> list[str]:
    """Where the page's navigation widgets (``PageAddress``) send the browser ("go") or what they
    put in its address ("query")."""
    found = []

    def walk(node):
        if isinstance(node, PageAddress) and node.action == action:
            found.append(node.address)
        for child in getattr(node, "children", ()) or ():
            walk(child)

    walk(page)
    return found


def redirect_of(page):
    """The completion URL the page's navigation widget sends the browser to."""
    found = page_addresses(page, "go")
    assert len(found) <= 1, found
    return found[0] if found else None


# -- the online page -------------------------------------------------------------------------------------

def test_a_prolific_link_enrols_randomises_and_records_the_pool_s_ids(tmp_path):
    page = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("5f0a1b2c3d4e5f6a7b8c9d0e", "ST1", "SE1"))
    assert page.session is not None and page.session.participant == "5f0a1b2c3d4e5f6a7b8c9d0e"
    enrolment = StudyFolder(tmp_path / "logs").enrolment("5f0a1b2c3d4e5f6a7b8c9d0e")
    assert enrolment["method"] == "block" and enrolment["group"] in ("target", "control")
    assert enrolment.get("url_parameters") == {"STUDY_ID": "ST1", "SESSION_ID": "SE1"}


def test_no_widget_of_an_online_page_holds_the_panel_or_another_participant(tmp_path):
    # Someone else took part already (in another kernel: only their log and enrolment are here).
    other = Session.start(StudyFolder.create(tmp_path / "logs", load_protocol(PILOT)), "AAAA1111")
    other.close()
    before = set(live_widgets)

    def reachable():  # every widget of this page the browser could ask the state of
        return [w for key, w in live_widgets.items() if key not in before and w.comm is not None]
    page = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("BBBB2222"))
    steps = 0
    while not page.session.finished:
        widgets = reachable()
        texts = " ".join(t for w in widgets for t in participant_texts(w))
        assert "AAAA1111" not in texts and not GROUP_WORDS.search(texts)
        assert not any(isinstance(w, (ExperimenterPanel, StudyApp)) for w in widgets)
        act(page.view)
        steps += 1
    assert steps > 20 and page.completion.outcome == "completed"


@pytest.mark.parametrize("query, words", [
    ("", "does not say who you are"), ("PROLIFIC_PID=", "empty"), ("PROLIFIC_PID=..%2Fetc", "file path"),
    ("PROLIFIC_PID=" + "a" * 200, "characters long"), ("PROLIFIC_PID=P%01x", "control characters"),
    ("PROLIFIC_PID=A1&PROLIFIC_PID=B2", "2 times"),
])
def test_an_unusable_id_in_the_link_is_refused_in_words_and_nothing_is_written(tmp_path, query, words):
    page = OnlineStudyPage(PILOT, tmp_path / "logs", query)
    text = " ".join(participant_texts(page))
    assert page.session is None and words in text and "Nothing was recorded" in text
    assert not (tmp_path / "logs").exists()


def test_a_reload_resumes_the_participant_where_they_were(tmp_path):
    first = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("R1"))
    while first.session.current_step().kind != "demonstration" or first.session.current_step().index < 2:
        act(first.view)
    group = first.session.group
    first.session.close()  # the old kernel goes with its page
    again = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("R1"))
    step = again.session.current_step()
    assert (step.kind, step.phase, step.index) == ("demonstration", "P1", 2) and again.session.group == group
    assert again.view.episode.state_index == 2
    assert any(e["type"] == "session_resumed" for e in again.session.events)


@pytest.mark.parametrize("ending, code", [("completed", "PILOTDONE"), ("withdrawn", "PILOTWITHDRAW"),
                                          ("declined", "PILOTDECLINE"), ("screened_out", "PILOTSCREEN")])
def test_each_ending_of_the_pilot_shows_its_own_code_and_sends_no_one_anywhere(tmp_path, ending, code):
    # The pilot gives no completion URL (it used to send everyone to http://localhost/prolific/complete,
    # which nothing serves): the page ends with the code, in words, and no redirect.
    page = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("E1"), redirect_delay_s=0)
    answers = {"robotics_background": "yes" if ending == "screened_out" else "no"}
    while not page.session.finished:
        step = page.session.current_step()
        if ending == "withdrawn" and step.kind == "demonstration":
            page.view.withdraw_button.click()
            yes = [b for b in buttons_in(page.view.withdraw_box) if b.description == "Yes, withdraw"][0]
            yes.click()
            yes.click()
        elif ending == "declined" and step.kind == "consent":
            [b for b in buttons_in(page.view.body) if b.description == "I do not agree"][0].click()
        else:
            act(page.view, answers)
    assert page.completion.code == code
    assert redirect_of(page) is None
    said = re.sub(r"<[^>]+>", "", " ".join(participant_texts(page)))
    assert f"Your completion code is {code}. This is the end of the study" in said and "taken back" not in said
    # Coming back with the same link: sent on again, nothing more written.
    page.session.close()
    log = tmp_path / "logs" / "E1.jsonl"
    logged = len(read_events(log)[0]) if log.exists() else 0
    back = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("E1"), redirect_delay_s=0)
    assert redirect_of(back) is None and code in " ".join(participant_texts(back))
    assert (len(read_events(log)[0]) if log.exists() else 0) == logged + (ending == "completed")


def test_a_protocol_with_the_pool_s_completion_urls_sends_the_participant_there(tmp_path):
    # What docs/user/study.md says to do for the real study: each ending given the pool's url.
    protocol = pilot_with_completion_urls(tmp_path)
    page = OnlineStudyPage(protocol, tmp_path / "logs", prolific("U1"), redirect_delay_s=0)
    while page.session.current_step().kind != "consent":
        act(page.view)
    [b for b in buttons_in(page.view.body) if b.description == "I do not agree"][0].click()
    assert redirect_of(page) == "https://app.prolific.com/submissions/complete?cc=PILOTDECLINE"
    said = re.sub(r"<[^>]+>", "", " ".join(participant_texts(page)))
    assert "Your completion code is PILOTDECLINE. You will be taken back to the study's website" in said


def test_a_protocol_without_an_online_table_is_refused_for_the_researcher(tmp_path):
    with pytest.raises(ValueError, match=r"\[online\] table"):
        OnlineStudyPage("paper-sim", tmp_path / "logs", prolific("X1"))


# -- the lab page ------------------------------------------------------------------------------------------

def test_the_lab_page_builds_no_panel_before_the_experimenter_s_code(tmp_path):
    page, built = new_widgets(lambda: LabStudyPage("paper-sim", tmp_path / "logs", "", experimenter_code="s3cret"))
    assert page.app is None and not any(isinstance(w, ExperimenterPanel) for w in built)
    for _ in range(MAX_ATTEMPTS):
        assert not page.unlock("guess")
        assert "not the experimenter's code" in page.message.value
    assert not page.unlock("s3cret") and page.open_button.disabled  # too many tries: reload
    fresh = LabStudyPage("paper-sim", tmp_path / "logs", "", experimenter_code="s3cret")
    assert fresh.unlock("s3cret") and isinstance(fresh.app, StudyApp) and fresh.children == (fresh.app,)
    nobody = LabStudyPage("paper-sim", tmp_path / "logs", "", experimenter_code="")
    assert not nobody.unlock("") and "MT_WIDGETS_EXPERIMENTER_CODE" in nobody.message.value


def address_of(page) -> dict:
    query = page_addresses(page, "query")[-1]
    assert query.startswith("?"), query
    return {k: v[0] for k, v in parse_qs(query[1:]).items()}


def test_a_participant_s_reload_of_the_lab_page_resumes_them_without_the_panel(tmp_path):
    page = LabStudyPage(PILOT, tmp_path / "logs", "", experimenter_code="s3cret")
    page.unlock("s3cret")
    page.app.experimenter.participant.value = "L01"
    page.app.experimenter.start_button.click()
    while page.session.current_step().kind != "demonstration":
        act(page.app.participant_view)
    address = address_of(page)
    assert address["participant"] == "L01" and address["key"]
    page.session.close()
    again, built = new_widgets(lambda: LabStudyPage(PILOT, tmp_path / "logs", urlencode(address),
                                                    experimenter_code="s3cret"))
    assert again.app is None and again.view is not None and again.children == (again.view,)
    assert not any(isinstance(w, ExperimenterPanel) for w in built)
    assert again.session.current_step().kind == "demonstration"
    assert read_events(tmp_path / "logs" / "L01.jsonl")[0][-1]["type"] in ("session_resumed", "episode_started")
    # Another participant's ID with this key: the code prompt, nobody resumed.
    forged = LabStudyPage(PILOT, tmp_path / "logs", urlencode(dict(address, participant="L02")),
                          experimenter_code="s3cret")
    assert forged.view is None and forged.app is None and forged.session is None


# -- an answer outside an item's eligible band ---------------------------------------------------------------

ADULTS_ONLY = "You need to be 18 or older to take part, so the study ends here. Thank you for your interest."


def _adults_only_pilot(tmp_path) -> Path:
    """The pilot protocol with an age that screens under 18, and its own words for it."""
    text = Path(PILOT).read_text()
    text = re.sub(r'^ineligible = .*$', f'ineligible = "{ADULTS_ONLY}"', text, count=1, flags=re.M)
    demographics = 'id = "demographics"\nkind = "demographics"\ntitle = "About you"\n'
    assert demographics in text
    text = text.replace(demographics, demographics + """
[[before.items]]
id = "age"
kind = "number"
prompt = "Your age, in years"
minimum = 0
maximum = 120
integer = true
eligible_minimum = 18

[[before.items]]
id = "sex"
kind = "choice"
prompt = "Your sex"
options = ["female", "male"]
""")
    path = tmp_path / "adults_only.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("age, screened", [("17", True), ("18", False)])
def test_an_age_under_the_band_shows_the_protocols_words_and_no_further_step(tmp_path, age, screened):
    page = OnlineStudyPage(str(_adults_only_pilot(tmp_path)), tmp_path / "logs", prolific("A1"), redirect_delay_s=0)
    while page.session.current_step().kind != "demographics":
        act(page.view)
    page.view.form.fields["age"].value = age
    page.view.form.fields["sex"].value = "female"
    page.view.form.continue_button.click()
    page.view.form.continue_button.click()  # an impatient double click records nothing twice
    shown = " ".join(participant_texts(page))
    events = read_events(tmp_path / "logs" / "A1.jsonl")[0]
    done = [e for e in events if e["type"] == "step_done" and e["step"] == "demographics"]
    assert len(done) == 1 and done[0]["eligible"] is (not screened)
    if screened:
        assert page.session.current_step().kind == "ended" and ADULTS_ONLY in shown
        assert page.completion.code == "PILOTSCREEN"
        assert redirect_of(page) is None
        # No further step: no form, no button to go on, and the task's instructions never shown.
        assert not [b for b in buttons_in(page.view.body)]
        assert "please type" not in shown.lower()
        assert [e["type"] for e in events][-1] == "screened_out"
    else:
        assert page.session.current_step().kind == "instructions" and ADULTS_ONLY not in shown
        assert page.completion is None and redirect_of(page) is None
