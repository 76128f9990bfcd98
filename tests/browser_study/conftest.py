"""A Voila server for the study page, and Debian Chromium through Playwright.

The server runs notebooks/study_sim.ipynb as a participant would get it, in its own process
group with its own JUPYTER_* folders and log folder in a temporary directory; the whole group
is ended at teardown. A missing Chromium or Playwright fails the tests, never skips them.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = os.environ.get("MT_WIDGETS_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class VoilaServer:
    """``voila notebooks/ --no-browser`` on a free port, with a log folder of its own."""

    def __init__(self, root: Path):
        self.root = root
        self.notebooks = root / "notebooks"
        self.notebooks.mkdir(parents=True)
        shutil.copy(REPO / "notebooks" / "study_sim.ipynb", self.notebooks / "study_sim.ipynb")
        self.logs = root / "logs"
        env = dict(os.environ)
        for name in ("JUPYTER_CONFIG_DIR", "JUPYTER_RUNTIME_DIR", "JUPYTERLAB_SETTINGS_DIR",
                     "JUPYTERLAB_WORKSPACES_DIR"):
            (root / name.lower()).mkdir()
            env[name] = str(root / name.lower())
        # The page as a participant gets it: the real log folder, not the notebook's test folder.
        env["MT_WIDGETS_FAST"] = "0"
        env["MT_WIDGETS_STUDY_LOGS"] = str(self.logs)
        self.port = _free_port()
        self.log_path = root / "voila.log"
        self._log = open(self.log_path, "w")
        self.process = subprocess.Popen(
            [str(Path(sys.executable).parent / "voila"), str(self.notebooks), "--no-browser", f"--port={self.port}",
             "--Voila.ip=127.0.0.1"], cwd=self.notebooks, env=env, stdout=self._log, stderr=subprocess.STDOUT,
            start_new_session=True)
        deadline = time.monotonic() + 60
        while True:
            if self.process.poll() is not None:
                raise RuntimeError(f"voila exited with {self.process.returncode}:\n{self.log_path.read_text()[-3000:]}")
            with socket.socket() as sock:
                if sock.connect_ex(("127.0.0.1", self.port)) == 0:
                    break
            if time.monotonic() > deadline:
                raise RuntimeError(f"voila did not open its port:\n{self.log_path.read_text()[-3000:]}")
            time.sleep(0.1)

    def url(self, path: str) -> str:
        return f"http://127.0.0.1:{self.port}{path}"

    def stop(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(5)
        self._log.close()


@pytest.fixture(scope="module")
def voila_study(tmp_path_factory):
    server = VoilaServer(tmp_path_factory.mktemp("voila-study"))
    yield server
    server.stop()


@pytest.fixture(scope="module")
def chromium():
    if not Path(CHROMIUM).exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: install it with `apt-get install -y chromium` "
                    f"(or set MT_WIDGETS_CHROMIUM)", pytrace=False)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as error:
        pytest.fail(f"playwright is not installed ({error}): pip install 'mt-widgets[test]'", pytrace=False)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def page(chromium):
    context = chromium.new_context(viewport={"width": 1280, "height": 1200})
    page = context.new_page()

    def only_local(route):
        if route.request.url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")):
            route.continue_()
        else:
            route.abort()  # Voila asks a CDN for a font

    page.route("**/*", only_local)
    yield page
    context.close()


@pytest.fixture
def shot(request):
    ARTIFACTS.mkdir(exist_ok=True)
    name = request.node.name

    def path(step: str) -> str:
        return str(ARTIFACTS / f"{name}-{step}.png")

    return path
