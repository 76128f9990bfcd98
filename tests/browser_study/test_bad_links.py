"""Bad links in Chromium: a link without an ID, an over-long one, and the same participant in a
second tab each get a page that says in words what to do; nothing is recorded for a bad link, and
the second tab neither loses nor duplicates a step."""

from __future__ import annotations

from urllib.parse import urlencode

import pytest

from browser_support import LOCAL_PREFIXES, local_page
from mt_widgets.study import StudyFolder, read_events

from .support import button

pytestmark = pytest.mark.browser

ONLINE = "/voila/render/study_online.ipynb"


@pytest.mark.parametrize("name, query, words", [
    ("no-id", "?STUDY_ID=ST1&SESSION_ID=SE1", "this link does not say who you are"),
    ("over-long", "?" + urlencode({"PROLIFIC_PID": "5f" * 60, "STUDY_ID": "ST1"}), "120 characters long"),
], ids=["no-id", "over-long"])
def test_a_link_without_a_usable_id_gets_a_clear_page_and_nothing_is_written(browser, voila_study, shot, name,
                                                                              query, words):
    logs = voila_study.logs
    before = {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()} if logs.exists() else {}
    context, page = local_page(browser, 390, 844)  # a phone: how many Prolific participants arrive
    try:
        page.goto(voila_study.url(ONLINE) + query, wait_until="commit", timeout=120_000)
        page.get_by_text(words).wait_for(timeout=120_000)
        text = page.inner_text("body")
        assert "Nothing was recorded" in text and "with the link exactly as you were given it" in text
        assert "Withdraw" not in text and "Traceback" not in text
        page.screenshot(path=shot(f"bad-link-{name}"))
    finally:
        context.close()
    after = {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()} if logs.exists() else {}
    assert after == before  # nothing written, not even the study folder's first files


def test_a_second_tab_of_the_same_participant_takes_over_and_the_first_says_so(browser, voila_study, shot):
    pid = "5f0a1b2c3d4e5f6a7b8c9d55"
    link = voila_study.url(ONLINE) + "?" + urlencode({"PROLIFIC_PID": pid, "STUDY_ID": "ST1", "SESSION_ID": "SE5"})
    context, first = local_page(browser, 1280, 1000)
    try:
        first.goto(link, wait_until="commit", timeout=120_000)
        button(first, "Continue").click(timeout=120_000)  # the page's kernel starts first
        button(first, "I agree").wait_for(timeout=120_000)
        second = context.new_page()  # the same browser, a second tab with the same link
        second.route("**/*", lambda route: route.continue_() if route.request.url.startswith(LOCAL_PREFIXES)
                     else route.abort())
        second.goto(link, wait_until="commit", timeout=120_000)
        button(second, "I agree").wait_for(timeout=120_000)   # resumed where the first tab was
        button(first, "I agree").click()
        first.get_by_text("This study is open in another tab or window.").wait_for(timeout=30_000)
        assert "call the experimenter" not in first.inner_text("body").lower()
        first.screenshot(path=shot("second-tab-first"))
        button(second, "I agree").click()
        button(second, "I agree").wait_for(state="detached", timeout=30_000)
        second.screenshot(path=shot("second-tab-second"))
    finally:
        context.close()
    events, _ = read_events(voila_study.logs / f"{pid}.jsonl")
    kinds = [e["type"] for e in events]
    assert kinds.count("consent_given") == 1 and kinds.count("screen_done") == 1 and "session_resumed" in kinds
    assert StudyFolder(voila_study.logs).participant_ids().count(pid) == 1
