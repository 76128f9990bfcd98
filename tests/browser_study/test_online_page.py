"""Online participants in Chromium: several arrive by URL at once on notebooks/study_online.ipynb.

One reloads in the middle of an episode and resumes at the same demonstration; one withdraws
and lands on the protocol's withdrawal URL with its code; one declines consent and lands on the
declined URL; one with an unusable ID is refused with nothing written. No page shows an
experimenter control or anything about another participant. The pages are served with the
shipped configuration (deploy/voila/voila.py), so the first arrival takes the preheated kernel,
which waits for the page's query string (voila.utils.get_query_string).
"""

from __future__ import annotations

import re
from urllib.parse import urlencode

import numpy as np
import pytest

from browser_support import local_page
from mt_widgets import SKILLS
from mt_widgets.study import StudyFolder
from mt_widgets.widgets import ArmView

from .support import button, current_episode, demonstrate, wait_for_log, wait_for_marker

pytestmark = pytest.mark.browser

ONLINE = "/voila/render/study_online.ipynb"
# The pilot's old completion address (nothing serves it): the page must never go there.
COMPLETE = "http://localhost/prolific/complete"
PEOPLE = {"reloads": "5f0a1b2c3d4e5f6a7b8c9d01", "withdraws": "5f0a1b2c3d4e5f6a7b8c9d02",
          "declines": "5f0a1b2c3d4e5f6a7b8c9d03"}
GROUP_WORDS = re.compile(r"\b(target|control|group|groups|condition)\b", re.IGNORECASE)


def arrive(browser, server, pid):
    context, page = local_page(browser, 1280, 1100)
    landed = []

    def completion(route):
        landed.append(route.request.url)
        route.fulfill(status=200, content_type="text/html", body="<html><body>Back at the pool</body></html>")
    # Registered after local_page's catch-all, so it runs first for the completion URLs.
    page.route(f"{COMPLETE}**", completion)
    page.landed = landed
    query = urlencode({"PROLIFIC_PID": pid, "STUDY_ID": "ST1", "SESSION_ID": f"SE-{pid[-2:]}"})
    page.goto(f"{server.url(ONLINE)}?{query}", wait_until="commit", timeout=120_000)
    return context, page


def nothing_of_others(page, own):
    text = page.inner_text("body")
    source = page.content()
    assert "Experimenter" not in text and "List participants" not in text and "Resume participant" not in text
    assert not GROUP_WORDS.search(text), GROUP_WORDS.search(text).group(0)
    for other in PEOPLE.values():
        if other != own:
            assert other not in source


def test_participants_arrive_by_url_at_once_one_reloads_one_withdraws_one_declines(browser, voila_shipped, shot):
    server = voila_shipped
    pages = {role: arrive(browser, server, pid) for role, pid in PEOPLE.items()}  # all at once
    try:
        for role, (_, page) in pages.items():
            page.get_by_text("Welcome, and thank you for taking part.").wait_for(timeout=120_000)
            nothing_of_others(page, PEOPLE[role])
        pages["reloads"][1].screenshot(path=shot("welcome"))

        # Withdraws at once: the withdrawal code, on the page. The pilot gives no completion URL, so
        # the page stays (it used to go to http://localhost/prolific/complete, which nothing serves).
        page = pages["withdraws"][1]
        address = page.url
        button(page, "Withdraw from the study").click()
        button(page, "Yes, withdraw").dblclick()
        page.get_by_text("PILOTWITHDRAW").wait_for(timeout=15_000)
        page.get_by_text("This is the end of the study").wait_for(timeout=15_000)

        # Declines consent: the declined code.
        declines = pages["declines"][1]
        button(declines, "Continue").click()
        button(declines, "I do not agree").click()
        declines.get_by_text("PILOTDECLINE").wait_for(timeout=15_000)
        declines.screenshot(path=shot("declined"))
        page.wait_for_timeout(5000)   # longer than a redirect's delay (4 s): still on the page, nowhere else asked
        page.screenshot(path=shot("withdrawn"))
        assert page.url == address and page.landed == [] and declines.landed == []

        # Goes on to the first episode, reloads mid-episode, and resumes at the same demonstration.
        pid, page = PEOPLE["reloads"], pages["reloads"][1]
        button(page, "Continue").click()
        button(page, "I agree").click()
        page.get_by_role("radio", name="no").check()
        button(page, "Continue").click()
        page.get_by_placeholder("a number (years)").fill("17")
        page.get_by_role("radio", name="male", exact=True).check()
        button(page, "Continue").click()
        page.get_by_text("please type a whole number from 18 to 120").wait_for()
        page.get_by_placeholder("a number (years)").fill("34")
        button(page, "Continue").click()
        button(page, "Start the practice").click()
        page.get_by_text("Practice time is over.").wait_for(timeout=90_000)
        button(page, "Continue to the study").click()
        button(page, "Start").click()
        demonstrate(page, server, pid, "P1", 0, (50, -40))
        demonstrate(page, server, pid, "P1", 1, (-40, 30))
        page.reload(wait_until="commit")
        page.get_by_text("Part 1 of 3, round 1 of 1").wait_for(timeout=120_000)
        episode = current_episode(server, pid)
        wait_for_marker(page, ArmView(SKILLS["sim-point"]).end_effector_pixel(np.asarray(episode["query_states"][2])))
        nothing_of_others(page, pid)
        page.screenshot(path=shot("resumed"))
        demonstrate(page, server, pid, "P1", 2, (30, 50))
        events = wait_for_log(server, pid, lambda ev: sum(e["type"] == "demonstration" for e in ev) == 3)
        assert [e["index"] for e in events if e["type"] == "demonstration"] == [0, 1, 2]
        assert any(e["type"] == "session_resumed" for e in events)
    finally:
        for context, _ in pages.values():
            context.close()

    study = StudyFolder(server.logs)
    outcomes = study.outcomes()
    assert outcomes[PEOPLE["withdraws"]]["outcome"] == "withdrawn"
    assert outcomes[PEOPLE["declines"]]["outcome"] == "declined"
    enrolment = study.enrolment(PEOPLE["reloads"])
    assert enrolment["method"] == "block" and enrolment["url_parameters"]["STUDY_ID"] == "ST1"


def test_an_unusable_id_in_the_link_is_refused_and_nothing_is_written(browser, voila_study, shot):
    context, page = local_page(browser, 390, 844)
    try:
        page.goto(voila_study.url(ONLINE) + "?PROLIFIC_PID=..%2F..%2Fetc", timeout=120_000)
        page.get_by_text("looks like a file path").wait_for(timeout=120_000)
        page.screenshot(path=shot("refused"))
        assert "Withdraw" not in page.inner_text("body")
    finally:
        context.close()
    written = [p.name for p in voila_study.logs.rglob("*")] if voila_study.logs.exists() else []
    assert not any("etc" in name for name in written)
    enrolments = (voila_study.logs / "_enrolment.jsonl")
    assert not enrolments.exists() or "etc" not in enrolments.read_text()
