"""At capacity, in Chromium: with one participant taking part on a server configured for one, a new
arrival's page says the study is busy and when to come back (never a page that hangs), and nothing
is recorded for them."""

from __future__ import annotations

import shutil
from urllib.parse import urlencode

import pytest

from browser_support import REPO, local_page, voila
from mt_widgets.study import Session, StudyFolder, load_protocol

from .conftest import PAGES
from .support import EXPERIMENTER_CODE

pytestmark = pytest.mark.browser

ONLINE = "/voila/render/study_online.ipynb"


@pytest.fixture(scope="module")
def voila_for_one(tmp_path_factory):
    root = tmp_path_factory.mktemp("voila-capacity")
    (root / "notebooks").mkdir()
    for name in PAGES:
        shutil.copy(REPO / "notebooks" / name, root / "notebooks" / name)
    server = voila(root, env={"MT_WIDGETS_STUDY_LOGS": str(root / "logs"),
                              "MT_WIDGETS_EXPERIMENTER_CODE": EXPERIMENTER_CODE,
                              "MT_WIDGETS_STUDY_MAX_PARTICIPANTS": "1"})
    server.logs = root / "logs"
    yield server
    server.stop()


def test_a_new_arrival_at_capacity_gets_a_busy_page_and_nothing_is_recorded(browser, voila_for_one, shot):
    logs = voila_for_one.logs
    # Someone is taking part right now (their log was just written).
    study = StudyFolder.create(logs, load_protocol(str(REPO / "notebooks" / "study_online_pilot.toml")))
    Session.start(study, "5f0a1b2c3d4e5f6a7b8c9d01").close()
    before = {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()}
    context, page = local_page(browser, 390, 844)
    try:
        query = urlencode({"PROLIFIC_PID": "5f0a1b2c3d4e5f6a7b8c9d02", "STUDY_ID": "ST1", "SESSION_ID": "SE2"})
        page.goto(voila_for_one.url(ONLINE) + "?" + query, wait_until="commit", timeout=120_000)
        page.get_by_text("The study is busy right now").wait_for(timeout=120_000)
        text = page.inner_text("body")
        assert "come back in about 10 minutes" in text and "open the same link again" in text
        assert "Nothing was recorded" in text and "Withdraw" not in text and "Welcome" not in text
        page.screenshot(path=shot("busy"))
    finally:
        context.close()
    assert {p: p.read_bytes() for p in logs.rglob("*") if p.is_file()} == before
