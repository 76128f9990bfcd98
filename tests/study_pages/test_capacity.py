"""At capacity, a clear page: a new arrival is told the study is busy and when to come back, nothing
is written for them, and a participant already taking part always gets their page."""

from __future__ import annotations

import os
import time

import pytest

from blinding_support import participant_texts
from mt_widgets.apps.study import OnlineStudyPage
from mt_widgets.apps.study.capacity import Capacity, available_mib

from .support import PILOT, act, prolific


def _text(page) -> str:
    return " ".join(participant_texts(page))


def test_a_full_study_turns_a_new_arrival_away_in_words_and_writes_nothing(tmp_path):
    logs = tmp_path / "logs"
    one = Capacity(max_participants=1)
    first = OnlineStudyPage(PILOT, logs, prolific("A0000000000000000000000a"), capacity=one)
    act(first.view)
    before = {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()}
    turned = OnlineStudyPage(PILOT, logs, prolific("B0000000000000000000000b"), capacity=one)
    text = _text(turned)
    assert turned.session is None and "The study is busy right now" in text and "about 10 minutes" in text
    assert "Nothing was recorded" in text and "mt-study-busy" in turned._dom_classes
    assert {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()} == before
    # The one taking part reloads: their page, whatever the count.
    first.session.close()
    again = OnlineStudyPage(PILOT, logs, prolific("A0000000000000000000000a"), capacity=one)
    assert again.session is not None and again.session.current_step().kind == "consent"
    # Once their log has been quiet for the active window, they no longer count: room again.
    old = time.time() - 601
    os.utime(logs / "A0000000000000000000000a.jsonl", (old, old))
    again.session.close()
    later = OnlineStudyPage(PILOT, logs, prolific("B0000000000000000000000b"), capacity=one)
    assert later.session is not None


def test_too_little_free_memory_turns_new_arrivals_away_and_nothing_is_created(tmp_path):
    assert available_mib() > 0
    page = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("C0000000000000000000000c"),
                           capacity=Capacity(min_free_mib=10 ** 9))  # more than any machine has
    assert page.session is None and "busy" in _text(page) and not (tmp_path / "logs").exists()
    roomy = OnlineStudyPage(PILOT, tmp_path / "logs", prolific("C0000000000000000000000c"), capacity=Capacity())
    assert roomy.session is not None


def test_the_capacity_comes_from_the_environment_and_bad_values_are_refused():
    assert Capacity.from_environment({}) == Capacity()
    assert Capacity.from_environment({"MT_WIDGETS_STUDY_MAX_PARTICIPANTS": "100",
                                      "MT_WIDGETS_STUDY_MIN_FREE_MIB": "512"}) == Capacity(100, 512.0)
    with pytest.raises(ValueError, match="MT_WIDGETS_STUDY_MAX_PARTICIPANTS: expected a number"):
        Capacity.from_environment({"MT_WIDGETS_STUDY_MAX_PARTICIPANTS": "many"})
    with pytest.raises(ValueError, match="max_participants: expected a number >= 0"):
        Capacity(max_participants=-1)
    with pytest.raises(ValueError, match="active_s"):
        Capacity(active_s=0)
