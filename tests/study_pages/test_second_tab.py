"""The same participant twice (a second tab, another device) and an erased participant's link: each
page says in words what happens, and nothing is lost or recorded twice."""

from __future__ import annotations

from blinding_support import participant_texts
from mt_widgets.apps.study import OnlineStudyPage
from mt_widgets.study import StudyFolder, erase_participant, read_events

from .support import PILOT, act, buttons_in, prolific


def _text(page) -> str:
    return " ".join(participant_texts(page))


def test_a_second_tab_continues_and_the_first_says_so_with_nothing_recorded_twice(tmp_path):
    pid = "5f0a1b2c3d4e5f6a7b8c9d77"
    first = OnlineStudyPage(PILOT, tmp_path / "logs", prolific(pid))
    act(first.view)  # welcome
    assert first.session.current_step().kind == "consent"
    second = OnlineStudyPage(PILOT, tmp_path / "logs", prolific(pid))  # the same link, another tab
    assert second.session.current_step().kind == "consent"   # resumed where the first tab is
    # The first tab's click reaches a session that is no longer the participant's: refused in words.
    [b for b in buttons_in(first.view.body) if b.description == "I agree"][0].click()
    text = _text(first)
    assert "open in another tab or window" in text and "Everything you did so far is saved" in text
    assert "call the experimenter" not in text.lower() and not buttons_in(first.view)
    # The second tab goes on; the log holds each step once, and the participant is enrolled once.
    act(second.view)
    assert second.session.current_step().kind != "consent" and second.view.stopped_by is None
    events, _ = read_events(tmp_path / "logs" / f"{pid}.jsonl")
    assert [e["type"] for e in events].count("consent_given") == 1
    assert [e["type"] for e in events].count("screen_done") == 1
    assert StudyFolder(tmp_path / "logs").participant_ids() == [pid]


def test_an_erased_participant_s_link_records_nothing(tmp_path):
    pid = "5f0a1b2c3d4e5f6a7b8c9d78"
    page = OnlineStudyPage(PILOT, tmp_path / "logs", prolific(pid))
    page.session.close()
    erase_participant(tmp_path / "logs", pid)
    before = sorted(p.name for p in (tmp_path / "logs").iterdir())
    again = OnlineStudyPage(PILOT, tmp_path / "logs", prolific(pid))
    assert again.session is None and "erased from this study" in _text(again)
    assert sorted(p.name for p in (tmp_path / "logs").iterdir()) == before
    assert pid not in StudyFolder(tmp_path / "logs").participant_ids()
