"""Who may not start now (mt_widgets/apps/study/arrival.py): the decision the server's gate and the
page share, its words with the protocol's return URL, and a page that holds nothing but them."""

from __future__ import annotations

import pytest

from mt_widgets.apps.study import OnlineStudyPage
from mt_widgets.apps.study.arrival import (
    DEFAULT_PROTOCOL,
    PROTOCOL_VARIABLE,
    TurnedAway,
    arrival_or_refusal,
    served_protocol,
    turned_away_page,
)
from mt_widgets.apps.study.capacity import Capacity
from mt_widgets.apps.study.online import parse_query
from mt_widgets.study import Session, StudyFolder, load_protocol

from .support import PILOT, prolific

RETURN_URL = "https://app.prolific.com/submissions"


def test_a_usable_link_with_room_is_let_through_and_nothing_is_read_into_being(tmp_path):
    online = load_protocol(PILOT).online
    arrival, turned = arrival_or_refusal(online, tmp_path / "logs", parse_query(prolific("5f0a1b2c3d4e5f6a7b8c9d03")),
                                         Capacity(max_participants=1))
    assert turned is None and arrival.participant_id == "5f0a1b2c3d4e5f6a7b8c9d03"
    assert not (tmp_path / "logs").exists()


def test_bad_links_and_a_full_server_are_turned_away_with_the_return_url(tmp_path):
    protocol = load_protocol(PILOT)
    assert protocol.online.return_url == RETURN_URL
    logs = tmp_path / "logs"
    Session.start(StudyFolder.create(logs, protocol), "5f0a1b2c3d4e5f6a7b8c9d01").close()
    one = Capacity(max_participants=1)
    _, busy = arrival_or_refusal(protocol.online, logs, parse_query(prolific("5f0a1b2c3d4e5f6a7b8c9d02")), one)
    assert busy.busy and busy.retry_after_s == 600 and busy.return_url == RETURN_URL
    assert "The study is busy right now" in busy.words
    # The one taking part comes back: their page, whatever the count.
    assert arrival_or_refusal(protocol.online, logs, parse_query(prolific("5f0a1b2c3d4e5f6a7b8c9d01")), one)[1] is None
    _, bad = arrival_or_refusal(protocol.online, logs, parse_query("STUDY_ID=S1"), one)
    assert not bad.busy and bad.retry_after_s is None and bad.words.startswith("This link does not say who you are")
    page = turned_away_page(bad)
    assert f"href='{RETURN_URL}'" in page and "<script" not in page and "width=device-width" in page
    with pytest.raises(TypeError, match="capacity: expected a Capacity"):
        arrival_or_refusal(protocol.online, logs, {}, 1)


def test_the_words_and_the_url_are_escaped_on_the_servers_page():
    page = turned_away_page(TurnedAway("<img src=x onerror=alert(1)>", True, "https://a.org/?a=1&b='2'"))
    assert "<img" not in page and "&lt;img" in page and "href='https://a.org/?a=1&amp;b=&#x27;2&#x27;'" in page


def test_the_page_shows_the_return_url_when_it_turns_someone_away(tmp_path):
    page = OnlineStudyPage(PILOT, tmp_path / "logs", "STUDY_ID=S1", capacity=Capacity())
    assert page.session is None and RETURN_URL in page.children[0].value
    assert not (tmp_path / "logs").exists()


def test_the_served_protocol_is_read_beside_the_page_as_its_kernel_reads_it(tmp_path, monkeypatch):
    monkeypatch.delenv(PROTOCOL_VARIABLE, raising=False)
    assert served_protocol(tmp_path) == DEFAULT_PROTOCOL  # not beside it: a name load_protocol resolves
    (tmp_path / DEFAULT_PROTOCOL).write_text("")
    assert served_protocol(tmp_path) == str(tmp_path / DEFAULT_PROTOCOL)
    monkeypatch.setenv(PROTOCOL_VARIABLE, "paper-sim")
    assert served_protocol(tmp_path) == "paper-sim"
