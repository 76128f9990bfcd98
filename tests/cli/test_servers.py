"""``mt-widgets lab``, ``demo`` and ``study serve`` start their real server on 127.0.0.1 with a free
port, answer an HTTP GET, and stop cleanly on SIGTERM (a service manager's stop)."""

import http.client
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from mt_widgets.cli.servers import free_port, online_study, participant_link
from mt_widgets.study import load_protocol

REPO = Path(__file__).resolve().parents[2]
START_S = 120.0  # two cores shared with the rest of the suite: JupyterLab alone took 20 s here


def _start(argv, cwd, env=None):
    return subprocess.Popen([sys.executable, "-m", "mt_widgets.cli", *argv], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True,
                            env={**os.environ, "PYTHONPATH": str(REPO), **(env or {})})


def _get(port: int, path: str, server: subprocess.Popen) -> tuple[int, str]:
    """The status and the first 64 kB of GET ``path``, once the server listens (waiting at most START_S)."""
    deadline = time.monotonic() + START_S
    while True:
        assert server.poll() is None, f"the server ended early:\n{server.stdout.read()}"
        connection = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        try:
            connection.request("GET", path)
            response = connection.getresponse()
            return response.status, response.read(65536).decode("utf-8", "replace")
        except ConnectionRefusedError:
            assert time.monotonic() < deadline, f"nothing listens on {port} after {START_S} s"
            time.sleep(0.5)
        finally:
            connection.close()


def _ended_cleanly(server: subprocess.Popen, out: str) -> bool:
    """Exit 0 or by the signal; or Voila 0.5's own shutdown race, met when SIGTERM comes while its
    preheated kernel is still starting (shutdown_all asks for a kernel the pool has not registered
    yet: "HTTP 404: Kernel does not exist", exit 1; the kernel then ends by itself)."""
    return server.returncode in (0, -signal.SIGTERM) or (
        server.returncode == 1 and "Kernel does not exist" in out and "mt_widgets/cli" not in out)


def _stop(server: subprocess.Popen) -> str:
    """SIGTERM, as a service manager stops the command; the server must end by itself within 30 s."""
    server.send_signal(signal.SIGTERM)
    try:
        out, _ = server.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(server.pid, signal.SIGKILL)
        server.communicate()
        raise AssertionError("the server did not stop within 30 s of SIGTERM") from None
    return out


@pytest.mark.slow
def test_lab_opens_jupyterlab_on_the_copied_tutorials(tmp_path):
    port = free_port()
    server = _start(["lab", str(tmp_path / "class"), "--no-browser", "--port", str(port), "--",
                     "--ServerApp.ip=127.0.0.1"], cwd=tmp_path)
    try:
        # The page is behind the token the command printed, in the start-here URL.
        first = server.stdout.readline() + server.stdout.readline()
        token = re.search(r"open http://localhost:\d+/lab/tree/tutorials/00_start_here.ipynb\?token=(\w+)", first)
        assert token, first
        status, body = _get(port, f"/api/contents/tutorials?token={token[1]}", server)
        assert status == 200 and '"name": "00_start_here.ipynb"' in body.replace('":"', '": "')
        assert _get(port, "/api/contents/tutorials", server)[0] == 403  # no token, no notebooks
    finally:
        out = first + _stop(server)
    assert server.returncode in (0, -signal.SIGTERM)
    assert (tmp_path / "class" / "notebooks" / "demo.ipynb").exists()
    assert "files copied" in first and "DeprecationWarning" not in out and "ServerApp.token" not in out, out


@pytest.mark.slow
def test_demo_serves_the_demo_page(tmp_path):
    port = free_port()
    server = _start(["demo", "--port", str(port), "--", "--Voila.ip=127.0.0.1"], cwd=tmp_path)
    try:
        status, body = _get(port, "/", server)
        assert status == 200 and "<title>demo</title>" in body
    finally:
        out = _stop(server)
    assert _ended_cleanly(server, out), out
    assert "is not trusted" not in out and "Voila" in out, out   # deploy/voila/log_filters.py
    # A clean stop: each forked kernel's end is read without the stopped event loop (ForkedProcess).
    assert "Wait for final termination of kernel timed out" not in out and "Task was destroyed" not in out, out


@pytest.mark.slow
def test_study_serve_online_serves_only_the_study_pages_and_cleans_up(tmp_path):
    port = free_port()
    # A temporary folder of its own (short: Voila's kernel sockets live there too, at most 107 bytes a path).
    own_tmp = Path(tempfile.mkdtemp(prefix="mtw-"))
    server = _start(["study", "serve", "--online", "--port", str(port), "--", "--Voila.ip=127.0.0.1"], cwd=tmp_path,
                    env={"MT_WIDGETS_EXPERIMENTER_CODE": "", "TMPDIR": str(own_tmp),
                         "MT_WIDGETS_STUDY_PROTOCOL": "", "MT_WIDGETS_STUDY_LOGS": str(tmp_path / "logs")})
    try:
        assert server.stdout.readline().startswith("Experimenter code for this server: ")
        said = dict(server.stdout.readline().rstrip("\n").split(": ", 1) for _ in range(5))
        assert said["Protocol"] == str(REPO / "notebooks" / "study_online_pilot.toml")
        assert said["Logs"] == str(tmp_path / "logs")
        link = said["Participant link to try (a made-up test ID)"]
        assert link.startswith(f"http://localhost:{port}/voila/render/study_online.ipynb?PROLIFIC_PID=")
        assert said["Experimenter's page"] == f"http://localhost:{port}/voila/render/study_sim.ipynb"
        # The pilot sends no one to a dead address: its last page shows the code and stays.
        assert said["At the end"].startswith("the page shows the completion code (PILOTDONE) and stays")
        assert "give each ending its url" in said["At the end"] and "http" not in said["At the end"]
        status, body = _get(port, "/voila/api/contents", server)  # what the served folder holds
        assert status == 200
        # Voila lists notebooks only (the pilot protocol beside them is read by the online page).
        assert {item["name"] for item in json.loads(body)["content"]} == {"study_online.ipynb", "study_sim.ipynb"}
    finally:
        out = _stop(server)
    assert _ended_cleanly(server, out), out
    assert list(own_tmp.glob("mt-widgets-study-pages.*")) == []
    shutil.rmtree(own_tmp, ignore_errors=True)


def test_the_online_study_served_is_the_pilot_unless_set_and_its_printed_link_enrols_a_test_participant(tmp_path):
    protocol, logs = online_study({"HOME": str(tmp_path)})
    assert protocol == str(REPO / "notebooks" / "study_online_pilot.toml")
    assert logs == Path.home() / "mt-widgets-studies" / "online"
    mine = tmp_path / "mine.toml"
    assert online_study({"MT_WIDGETS_STUDY_PROTOCOL": str(mine), "MT_WIDGETS_STUDY_LOGS": "~/x"}) == (
        str(mine), Path.home() / "x")
    link = participant_link("http://localhost:8866", protocol)
    assert link.startswith("http://localhost:8866/voila/render/study_online.ipynb?PROLIFIC_PID=")
    query = dict(pair.split("=") for pair in link.split("?", 1)[1].split("&"))
    arrival = load_protocol(protocol).online.participant_from_url(query)
    assert len(arrival.participant_id) == 24 and set(arrival.parameters) == {"STUDY_ID", "SESSION_ID"}
    assert participant_link("http://localhost:8866", protocol) != link   # each try a new participant
