"""Real-browser fixtures: Voila and JupyterLab servers, Debian Chromium driven by Playwright.

Each server runs in its own process group with its own JUPYTER_* directories in a
temporary folder and is ended (the whole group) at teardown. Pages may only talk to
127.0.0.1: everything else is aborted (Voila asks a CDN for a font). A missing Chromium or
Playwright fails the tests, never skips them (BROWSER_TESTING.md).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

PAGES = Path(__file__).parent / "pages"
DEMO = Path(__file__).resolve().parents[2] / "notebooks" / "demo.ipynb"      # the visitors' page, served as is
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
CHROMIUM = os.environ.get("MT_WIDGETS_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]
BIN = Path(sys.executable).parent


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _wait_for_port(port: int, process: subprocess.Popen, log: Path, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"server exited with {process.returncode}:\n{log.read_text()[-3000:]}")
        with socket.socket() as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise RuntimeError(f"server did not open port {port} within {timeout} s:\n{log.read_text()[-3000:]}")


def _jupyter_env(root: Path) -> dict:
    env = dict(os.environ)
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTERLAB_SETTINGS_DIR", "JUPYTERLAB_WORKSPACES_DIR", "JUPYTER_RUNTIME_DIR",
                 "JUPYTER_DATA_DIR_UNUSED"):
        path = root / name.lower()
        path.mkdir(parents=True, exist_ok=True)
        env[name] = str(path)
    env.pop("JUPYTER_DATA_DIR_UNUSED")
    # Keep off-screen outputs in the page and no news toast over the notebook.
    settings = root / "jupyterlab_settings_dir"
    (settings / "@jupyterlab" / "notebook-extension").mkdir(parents=True, exist_ok=True)
    (settings / "@jupyterlab" / "notebook-extension" / "tracker.jupyterlab-settings").write_text(
        json.dumps({"windowingMode": "none"}))
    (settings / "@jupyterlab" / "apputils-extension").mkdir(parents=True, exist_ok=True)
    (settings / "@jupyterlab" / "apputils-extension" / "notification.jupyterlab-settings").write_text(
        json.dumps({"fetchNews": "false"}))
    env["MT_WIDGETS_FAST"] = "1"
    return env


class Server:
    def __init__(self, command: list[str], port: int, root: Path, name: str, base_url: str, token: str = ""):
        self.port, self.token, self.base_url = port, token, base_url
        self.log = root / f"{name}.log"
        self._log_file = open(self.log, "w")
        self.process = subprocess.Popen(command, cwd=root / "notebooks", env=_jupyter_env(root),
                                        stdout=self._log_file, stderr=subprocess.STDOUT, start_new_session=True)
        _wait_for_port(port, self.process, self.log)

    def url(self, path: str) -> str:
        return f"{self.base_url}{path}"

    def stop(self) -> None:
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(5)
        self._log_file.close()


def _copy_pages(root: Path) -> None:
    notebooks = root / "notebooks"
    notebooks.mkdir(parents=True, exist_ok=True)
    for page in [*PAGES.glob("*.ipynb"), DEMO]:
        shutil.copy(page, notebooks / page.name)


@pytest.fixture(scope="session")
def browser():
    """Debian's Chromium through Playwright; fails when either is missing."""
    if not Path(CHROMIUM).exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: install it with `apt-get install -y chromium` "
                    f"(or set MT_WIDGETS_CHROMIUM)", pytrace=False)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as error:  # pragma: no cover - the message is the point
        pytest.fail(f"playwright is not installed ({error}): pip install 'mt-widgets[test]'", pytrace=False)
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


@pytest.fixture
def page(browser):
    """A fresh page that may only reach 127.0.0.1."""
    context = browser.new_context(viewport={"width": 1280, "height": 1100})
    page = context.new_page()

    def only_local(route):
        url = route.request.url
        if url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")):
            route.continue_()
        else:
            route.abort()

    page.route("**/*", only_local)
    yield page
    context.close()


@pytest.fixture(scope="session")
def voila_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("voila")
    _copy_pages(root)
    port = _free_port()
    # Preheated kernels: Voila runs each page's notebook before it is asked for, so opening a
    # page takes about 3 s instead of 5-6 s here. The widgets must then draw into views that
    # attach after the kernel ran, which is the ipycanvas #322 case these tests are about.
    server = Server([str(BIN / "voila"), str(root / "notebooks"), "--no-browser", f"--port={port}",
                     "--Voila.ip=127.0.0.1", "--preheat_kernel=True", "--pool_size=1"],
                    port, root, "voila", f"http://127.0.0.1:{port}")
    yield server
    server.stop()


@pytest.fixture(scope="session")
def lab_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    _copy_pages(root)
    port, token = _free_port(), "mt-widgets-test"
    server = Server([str(BIN / "jupyter"), "lab", "--no-browser", "--ip=127.0.0.1", f"--port={port}",
                     "--port-retries=0", "--allow-root", f"--IdentityProvider.token={token}",
                     f"--ServerApp.root_dir={root / 'notebooks'}", "--LabApp.extension_manager=readonly"],
                    port, root, "lab", f"http://127.0.0.1:{port}", token)
    yield server
    server.stop()


@pytest.fixture
def artifacts(request):
    """Where to keep screenshots: test-artifacts/<test name>-<step>.png."""
    ARTIFACTS.mkdir(exist_ok=True)
    name = request.node.name.replace("[", "-").replace("]", "")

    def path(step: str) -> str:
        return str(ARTIFACTS / f"{name}-{step}.png")

    return path
