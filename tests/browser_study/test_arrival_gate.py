"""Turned away before any kernel starts (the shipped configuration, deploy/voila/arrival_gate.py):
in Chromium on a phone, a new arrival at capacity gets the busy page with the protocol's return
URL, and links without a usable ID get their clear page; the server's kernels stay exactly the ones
it had (the preheated spares, untouched), nothing is recorded, and an enrolled participant still
gets their page."""

from __future__ import annotations

import shutil
import time
import urllib.error
import urllib.request
from urllib.parse import urlencode

import pytest

from browser.kiosk import kernel_processes
from browser_support import REPO, local_page, voila
from mt_widgets.study import Session, StudyFolder, load_protocol

from .conftest import PAGES
from .support import EXPERIMENTER_CODE, button

pytestmark = pytest.mark.browser

ONLINE = "/voila/render/study_online.ipynb"
TAKING_PART = "5f0a1b2c3d4e5f6a7b8c9d01"
RETURN_URL = "https://app.prolific.com/submissions"  # notebooks/study_online_pilot.toml's return_url


def _link(server, **parameters) -> str:
    return server.url(ONLINE) + ("?" + urlencode(parameters) if parameters else "")


def _files(folder) -> dict:
    return {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()} if folder.exists() else {}


@pytest.fixture(scope="module")
def full_server(tmp_path_factory):
    """The shipped configuration, for one participant at once, with one taking part already."""
    root = tmp_path_factory.mktemp("voila-gate")
    (root / "notebooks").mkdir()
    for name in PAGES:
        shutil.copy(REPO / "notebooks" / name, root / "notebooks" / name)
    logs = root / "logs"
    study = StudyFolder.create(logs, load_protocol(str(root / "notebooks" / "study_online_pilot.toml")))
    Session.start(study, TAKING_PART).close()
    server = voila(root, f"--Voila.config_file_paths={REPO / 'deploy' / 'voila'}",
                   env={"MT_WIDGETS_STUDY_LOGS": str(logs), "MT_WIDGETS_EXPERIMENTER_CODE": EXPERIMENTER_CODE,
                        "MT_WIDGETS_STUDY_MAX_PARTICIPANTS": "1"})
    server.logs = logs
    # The pools' spares (the lab page's and the online page's) start with the server.
    deadline = time.monotonic() + 120
    while len(kernel_processes(server)) < 2 and time.monotonic() < deadline:
        time.sleep(0.2)
    yield server
    server.stop()


def _get(url: str) -> tuple[int, dict, str]:
    try:
        with urllib.request.urlopen(url, timeout=30) as response:
            return response.status, dict(response.headers), response.read().decode()
    except urllib.error.HTTPError as error:
        return error.code, dict(error.headers), error.read().decode()


def test_at_capacity_and_for_bad_links_the_server_answers_without_a_kernel(browser, full_server, shot):
    kernels = {kernel_id: process.pid for kernel_id, process in kernel_processes(full_server).items()}
    assert len(kernels) == 2, kernels
    before = _files(full_server.logs)
    context, page = local_page(browser, 390, 844)  # a phone: how many Prolific participants arrive
    try:
        response = page.goto(_link(full_server, PROLIFIC_PID="5f0a1b2c3d4e5f6a7b8c9d02", STUDY_ID="ST1",
                                   SESSION_ID="SE2"), timeout=60_000)
        assert response.status == 503 and response.headers["retry-after"] == "600"
        text = page.inner_text("body")
        assert "The study is busy right now" in text and "come back in about 10 minutes" in text
        assert "open the same link again" in text and "Nothing was recorded" in text
        assert page.get_by_role("link", name="return it here").get_attribute("href") == RETURN_URL
        assert page.evaluate("document.documentElement.scrollWidth") <= 390  # no sideways scrolling
        page.screenshot(path=shot("busy-before-kernel"))
        response = page.goto(_link(full_server, STUDY_ID="ST1", SESSION_ID="SE3"), timeout=60_000)
        assert response.status == 400 and "This link does not say who you are" in page.inner_text("body")
        page.screenshot(path=shot("no-id-before-kernel"))
    finally:
        context.close()
    for parameters, words in [({"PROLIFIC_PID": "../../etc/passwd"}, "file path"),
                              ({"PROLIFIC_PID": "5f" * 60}, "120 characters long"),
                              ({"PROLIFIC_PID": "P\x0007"}, "control characters")]:
        status, headers, body = _get(_link(full_server, **parameters))
        assert status == 400 and words in body and "Nothing was recorded" in body, (parameters, status, body)
        assert RETURN_URL in body and "<script" not in body
    # No kernel started or taken: the same kernels, the same processes, no spare handed out.
    assert {k: p.pid for k, p in kernel_processes(full_server).items()} == kernels
    assert "Using pre-heated kernel" not in full_server.log.read_text()
    assert _files(full_server.logs) == before


def test_the_gate_lets_an_enrolled_participant_through_to_their_page(browser, full_server, shot):
    context, page = local_page(browser, 390, 844)
    try:
        response = page.goto(_link(full_server, PROLIFIC_PID=TAKING_PART, STUDY_ID="ST1", SESSION_ID="SE1"),
                             wait_until="commit", timeout=120_000)
        assert response.status == 200
        button(page, "Continue").wait_for(timeout=120_000)  # their session, where their log stops
        assert "busy" not in page.inner_text("body")
        page.screenshot(path=shot("enrolled-through-gate"))
    finally:
        context.close()
    assert "Using pre-heated kernel" in full_server.log.read_text()
