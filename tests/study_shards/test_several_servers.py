"""Several study servers behind nginx (deploy/nginx/study-servers.conf.template): sticky by participant,
one allocation sequence over all servers, one dataset; a server killed mid-study and restarted loses
nobody; a participant arriving on another server than their own is told so, and nothing is duplicated.

Three study servers (tests/study_shards/page_server.py: the online page's objects behind HTTP, as
Voila's kernels hold them) share one study folder; nginx (Debian's, as a non-root worker, every
file under its own prefix) routes by the shipped template. Thirty scripted participants go through
the pilot protocol, one action each in turn.
"""

from __future__ import annotations

import http.cookiejar
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections import Counter
from pathlib import Path
from urllib.parse import urlencode

import pytest

from mt_widgets.study import StudyFolder, read_events
from mt_widgets.study.participants import block_assignment

ROOT = Path(__file__).resolve().parents[2]
PILOT = str(ROOT / "notebooks" / "study_online_pilot.toml")
NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
RENDER = "/voila/render/study_online.ipynb"
sys.path.insert(0, str(ROOT / "deploy" / "nginx"))
from render_config import render  # noqa: E402

pytestmark = pytest.mark.slow

N_PARTICIPANTS = 30
KILL_AFTER = 9      # rounds (one action of each participant) before one server is killed: in their first phase
MAX_ROUNDS = 60     # the pilot takes 33 actions from the welcome to the completion code


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(url: str, process, timeout_s: float = 90.0) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"{url}: the process ended with {process.returncode} before answering")
        try:
            urllib.request.urlopen(url, timeout=2).read()
            return
        except (TimeoutError, urllib.error.URLError, ConnectionError):
            time.sleep(0.2)
    raise RuntimeError(f"{url}: no answer within {timeout_s} s")


class StudyServer:
    def __init__(self, name: str, port: int, folder: Path, out: Path):
        self.name, self.port, self.folder, self.out = name, port, folder, out
        self.process = None

    def start(self) -> subprocess.Popen:
        log = open(self.out, "ab")
        self.process = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("page_server.py")), "--port", str(self.port),
             "--name", self.name, "--protocol", PILOT, "--folder", str(self.folder)],
            stdout=log, stderr=subprocess.STDOUT, env={**os.environ, "PYTHONPATH": f"{ROOT}:{ROOT / 'tests'}"})
        log.close()
        return self.process

    def wait(self) -> None:
        wait_for(f"http://127.0.0.1:{self.port}/health", self.process)

    def kill(self) -> None:
        self.process.send_signal(signal.SIGKILL)
        self.process.wait(10)


class Participant:
    """A participant's browser: their link, their cookies, the kernel id of their open page."""

    def __init__(self, pid: str, base: str):
        self.pid, self.base = pid, base
        self.opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(http.cookiejar.CookieJar()))
        self.kernel, self.server, self.state = None, None, None

    def request(self, method: str, url: str) -> tuple[int, str, str | None]:
        try:
            with self.opener.open(urllib.request.Request(url, method=method, data=b"" if method == "POST" else None),
                                  timeout=60) as reply:
                return reply.status, reply.read().decode(), reply.headers.get("X-Study-Server")
        except urllib.error.HTTPError as error:
            return error.code, error.read().decode(), error.headers.get("X-Study-Server")

    def open_link(self, base: str | None = None) -> tuple[int, dict | str]:
        query = urlencode({"PROLIFIC_PID": self.pid, "STUDY_ID": "SHARDS", "SESSION_ID": f"S-{self.pid}"})
        status, body, server = self.request("GET", f"{base or self.base}{RENDER}?{query}")
        if status != 200:
            return status, body
        reply = json.loads(body)
        if base is None:
            self.kernel, self.server, self.state = reply["kernel"], server, reply
        return status, reply

    def act(self) -> tuple[int, dict | str]:
        """One action on the open page (its kernel's URL carries no ID: the cookie routes it)."""
        status, body, server = self.request("POST", f"{self.base}/api/kernels/{self.kernel}/act")
        if status != 200:
            return status, body
        reply = json.loads(body)
        assert server == self.server, f"{self.pid}: opened on {self.server}, an action went to {server}"
        self.state = reply
        return status, reply


@pytest.fixture
def cluster(tmp_path):
    if not os.path.exists(NGINX):
        pytest.fail("this test needs Debian's nginx (/usr/sbin/nginx): scripts/run-tests.sh installs it, or "
                    "apt-get install nginx")
    folder = tmp_path / "study"
    servers = [StudyServer(f"s{i}", free_port(), folder, tmp_path / f"s{i}.out") for i in range(3)]
    # nginx's worker runs as nobody when the test runs as root: its prefix must be reachable by it,
    # which pytest's 0700 tmp_path is not.
    prefix = Path(tempfile.mkdtemp(prefix="mt-nginx-"))
    prefix.chmod(0o755)
    listen = free_port()
    config = render([f"127.0.0.1:{s.port}" for s in servers], f"127.0.0.1:{listen}", prefix, secure_cookie=False)
    (prefix / "nginx.conf").write_text(config)
    command = [NGINX, "-p", str(prefix), "-e", str(prefix / "error.log"), "-c", str(prefix / "nginx.conf"),
               "-g", "daemon off;" + (" user nobody nogroup;" if os.geteuid() == 0 else "")]
    nginx = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    try:
        for server in servers:
            server.start()
        for server in servers:
            server.wait()
        wait_for(f"http://127.0.0.1:{listen}/health", nginx)
        yield servers, f"http://127.0.0.1:{listen}", folder, prefix
    finally:
        for server in servers:
            if server.process is not None and server.process.poll() is None:
                server.process.terminate()
                server.process.wait(10)
        nginx.terminate()
        nginx.wait(10)
        shutil.rmtree(prefix, ignore_errors=True)


def test_thirty_participants_on_three_servers_one_sequence_one_dataset_a_server_killed_and_back(cluster):
    servers, base, folder, nginx_prefix = cluster
    by_name = {s.name: s for s in servers}
    people = [Participant(f"5f0a1b2c3d4e5f6a7b8c{i:04d}", base) for i in range(N_PARTICIPANTS)]
    for person in people:
        status, reply = person.open_link()
        assert status == 200 and reply["step"] is not None, reply
    homes = Counter(p.server for p in people)
    assert set(homes) == set(by_name), f"every server serves someone: {homes}"

    # One allocation sequence over all servers: enrolments 0..29, block slots 0..29, each the group
    # the protocol's block sequence gives that slot, whichever server drew it.
    study = StudyFolder(folder)
    protocol = study.protocol
    records = study.enrolments()
    assert sorted(r["participant"] for r in records) == sorted(p.pid for p in people)
    assert [r["index"] for r in records] == list(range(N_PARTICIPANTS))
    assert [r["block_slot"] for r in records] == list(range(N_PARTICIPANTS))
    assert [r["group"] for r in records] == [
        block_assignment(k, protocol.groups, protocol.block_size, protocol.assignment_seed)
        for k in range(N_PARTICIPANTS)]
    complete = N_PARTICIPANTS // protocol.block_size * protocol.block_size
    assert set(Counter(r["group"] for r in records[:complete]).values()) == {complete // len(protocol.groups)}

    victim = by_name[homes.most_common(1)[0][0]]
    for round_ in range(MAX_ROUNDS):
        if all(p.state["finished"] for p in people):
            break
        if round_ == KILL_AFTER:
            victim.kill()
            stranded = [p for p in people if p.server == victim.name]
            enrolled, sizes = len(study.enrolments()), {p.pid: log_size(folder, p.pid) for p in people}
            for person in stranded:  # their next action, and a reload, while their server is down
                for status, reply in (person.act(), person.open_link()):
                    assert status == 503 and "restarting" in reply and "saved" in reply, (status, reply)
            assert len(study.enrolments()) == enrolled
            assert {p.pid: log_size(folder, p.pid) for p in people} == sizes
            # Bad input: one of them, sent to another server (an operator's failover, a stale route),
            # while none of their pages is open anywhere: resumed from the shared folder, not enrolled again.
            other = next(s for s in servers if s is not victim)
            status, moved = stranded[0].open_link(f"http://127.0.0.1:{other.port}")
            assert status == 200 and moved["step"] == stranded[0].state["step"], moved
            # ... and that page still open there when their own server is back and they reload on it: the
            # reload continues them (the newest page wins, as with a second tab); the page on the other
            # server, at its next action, says so in words and writes nothing.
            victim.start()
            victim.wait()
            status, back = stranded[0].open_link()
            assert status == 200 and stranded[0].server == victim.name and back["step"] == moved["step"], back
            size = log_size(folder, stranded[0].pid)
            stale = urllib.request.Request(f"http://127.0.0.1:{other.port}/api/kernels/{moved['kernel']}/act",
                                           data=b"", method="POST")
            told = json.loads(urllib.request.urlopen(stale, timeout=30).read())
            assert "other tab" in told["text"] or "another" in told["text"], told
            assert log_size(folder, stranded[0].pid) == size and len(study.enrolments()) == enrolled
            # Their reload on their restarted server: each resumes where their log stops.
            for person in stranded[1:]:
                before = person.state["step"]
                status, body = person.act()  # the old page's kernel died with the server
                assert status == 404 and "no such kernel" in body
                status, reply = person.open_link()
                assert status == 200 and person.server == victim.name and reply["step"] == before, (before, reply)
        for person in people:
            if not person.state["finished"]:
                status, reply = person.act()
                assert status == 200, (person.pid, status, reply)
    assert all(p.state["finished"] for p in people), "everyone reaches the end within MAX_ROUNDS"

    # One dataset: everyone enrolled once, no one else, each log whole and resumed where it stopped,
    # everyone completed, and the groups as balanced as the blocks make them.
    study = StudyFolder(folder)
    records = study.enrolments()
    assert [row["state"] for row in study.status()] == ["completed"] * N_PARTICIPANTS
    completed = {group: row["completed"] for group, row in study.group_status().items()}
    assert completed == dict(Counter(r["group"] for r in records))
    assert max(completed.values()) - min(completed.values()) <= protocol.block_size // len(protocol.groups)
    assert len(records) == N_PARTICIPANTS == len({r["participant"] for r in records})
    logs = sorted(p.stem for p in folder.glob("*.jsonl") if not p.name.startswith("_"))
    assert logs == sorted(p.pid for p in people)
    for person in people:
        events, _ = read_events(folder / f"{person.pid}.jsonl")
        assert sum(e["type"] == "session_started" for e in events) == 1
        resumes = sum(e["type"] == "session_resumed" for e in events)
        assert resumes >= (person.server == victim.name), (person.pid, resumes)
    # nginx's access log names no one (the IDs ride in the query string, which it does not log).
    logged = (nginx_prefix / "access.log").read_text()
    assert logged.count(RENDER) >= N_PARTICIPANTS and not any(p.pid in logged for p in people)
    # Coming back with their link, on their own server, each is sent on with their completion code again.
    for person in people:
        status, body, _ = person.request("DELETE", f"{base}/api/kernels/{person.kernel}")
        assert status == 200, body
        status, reply = person.open_link()
        assert status == 200 and reply["step"] is None and "PILOTDONE" in reply["text"], (person.pid, reply)


def log_size(folder: Path, pid: str) -> int:
    path = folder / f"{pid}.jsonl"
    return path.stat().st_size if path.exists() else -1
