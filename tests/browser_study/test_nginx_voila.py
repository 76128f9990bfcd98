"""nginx (deploy/nginx/study-servers.conf.template) in front of two real Voila study servers with the
shipped configuration, in Chromium: a participant's page, its scripts and its kernel's websocket all
reach the one server their link was hashed to (the page works: a click is answered by the kernel and
recorded in the shared study folder), and the server's own busy page passes through nginx untouched
(not nginx's "server restarting" page). tests/study_shards/test_several_servers.py runs the same
template in front of stand-in page servers; this one proves it with Voila's websockets."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from pathlib import Path
from urllib.parse import urlencode

import pytest

from browser_support import REPO, free_port, local_page, voila
from mt_widgets.study import read_events

from .support import EXPERIMENTER_CODE, button

pytestmark = [pytest.mark.browser, pytest.mark.slow]

NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
ONLINE = "/voila/render/study_online.ipynb"
PAGES = ("study_online.ipynb", "study_online_pilot.toml")
sys.path.insert(0, str(REPO / "deploy" / "nginx"))
from render_config import render  # noqa: E402


def _wait_for(url: str, process, timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"{url}: nginx ended with {process.returncode} before answering")
        try:
            urllib.request.urlopen(url, timeout=2).read()
            return
        except urllib.error.HTTPError:
            return  # nginx answers (the upstream's status does not matter here)
        except (TimeoutError, urllib.error.URLError, ConnectionError):
            time.sleep(0.2)
    raise RuntimeError(f"{url}: no answer within {timeout_s} s")


@pytest.fixture(scope="module")
def behind_nginx(tmp_path_factory):
    if not os.path.exists(NGINX):
        pytest.fail("this test needs Debian's nginx (/usr/sbin/nginx): apt-get install nginx")
    logs = tmp_path_factory.mktemp("shared") / "logs"   # one study folder for both servers
    servers = []
    for name in ("v0", "v1"):
        root = tmp_path_factory.mktemp(f"voila-{name}")
        (root / "notebooks").mkdir()
        for page in PAGES:
            shutil.copy(REPO / "notebooks" / page, root / "notebooks" / page)
        servers.append(voila(root, f"--Voila.config_file_paths={REPO / 'deploy' / 'voila'}",
                             env={"MT_WIDGETS_STUDY_LOGS": str(logs), "MT_WIDGETS_EXPERIMENTER_CODE": EXPERIMENTER_CODE,
                                  "MT_WIDGETS_STUDY_MAX_PARTICIPANTS": "1"}))
    # nginx's worker runs as nobody when the test runs as root: its prefix must be reachable by it.
    prefix = Path(tempfile.mkdtemp(prefix="mt-nginx-voila-"))
    prefix.chmod(0o755)
    listen = free_port()
    (prefix / "nginx.conf").write_text(render([f"127.0.0.1:{s.port}" for s in servers], f"127.0.0.1:{listen}",
                                              prefix, secure_cookie=False))
    nginx = subprocess.Popen([NGINX, "-p", str(prefix), "-e", str(prefix / "error.log"), "-c",
                              str(prefix / "nginx.conf"), "-g",
                              "daemon off;" + (" user nobody nogroup;" if os.geteuid() == 0 else "")],
                             stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    try:
        base = f"http://127.0.0.1:{listen}"
        _wait_for(base + "/voila/static/", nginx)
        yield servers, base, logs, prefix
    finally:
        nginx.terminate()
        nginx.wait(10)
        for server in servers:
            server.stop()
        shutil.rmtree(prefix, ignore_errors=True)


def test_a_participant_takes_part_through_nginx_and_a_busy_arrival_gets_the_servers_page(browser, behind_nginx,
                                                                                       artifacts):
    servers, base, logs, prefix = behind_nginx
    pid = "5f0a1b2c3d4e5f6a7b8c9e01"
    context, page = local_page(browser, 390, 844)
    try:
        page.goto(f"{base}{ONLINE}?" + urlencode({"PROLIFIC_PID": pid, "STUDY_ID": "NGX", "SESSION_ID": "S1"}),
                  wait_until="commit", timeout=120_000)
        # The welcome screen comes from the kernel over the websocket, and the click goes back over it.
        button(page, "Continue").click(timeout=120_000)
        button(page, "I agree").wait_for(timeout=60_000)
        page.screenshot(path=artifacts("through-nginx"))
    finally:
        context.close()
    events = read_events(logs / f"{pid}.jsonl")[0]
    assert [event["type"] for event in events] == ["session_started", "screen_done"], events  # the click, logged
    # Every request of that page, the websocket's upgrade (101) included, went to one server. (nginx
    # logs a websocket when it ends: the page has just closed.)
    deadline = time.monotonic() + 30
    while True:
        log = (prefix / "access.log").read_text()
        channels = [line for line in log.splitlines() if re.search(r"/api/kernels/[0-9a-f-]+/channels\" 101 ", line)]
        if channels or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    assert channels, log[-2000:]
    lines = log.splitlines()
    page_requests = lines[next(i for i, line in enumerate(lines) if f'"GET {ONLINE}"' in line):]  # not the warm-up's
    upstreams = {line.rsplit(" ", 1)[-1] for line in page_requests}
    assert len(upstreams) == 1, upstreams
    assert pid not in log  # the access log names no one

    # A new participant while the one above takes part (capacity 1, counted from the shared folder):
    # the server's busy page, through nginx, with its status; no kernel was needed for it.
    other = "5f0a1b2c3d4e5f6a7b8c9e02"
    context, page = local_page(browser, 390, 844)
    try:
        response = page.goto(f"{base}{ONLINE}?" + urlencode({"PROLIFIC_PID": other, "STUDY_ID": "NGX"}),
                             timeout=60_000)
        text = page.inner_text("body")
        assert response.status == 503 and "The study is busy right now" in text and "restarting" not in text, text
        page.screenshot(path=artifacts("busy-through-nginx"))
    finally:
        context.close()
    assert not (logs / f"{other}.jsonl").exists()
