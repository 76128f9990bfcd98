"""What every real-browser test shares: Chromium's launch settings, local-only pages, and
Jupyter servers in their own process groups.

The one Playwright instance is the session fixture ``browser`` in ``tests/conftest.py``:
Playwright's sync API refuses a second instance while one runs, so no folder starts its own.
A missing Chromium or Playwright fails the tests, never skips them (docs/browser-testing.md).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = os.environ.get("MT_WIDGETS_CHROMIUM", "/usr/bin/chromium")
# Without the networking switches Chromium keeps trying to reach the internet (docs/browser-testing.md).
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]
BIN = Path(sys.executable).parent
LOCAL_PREFIXES = ("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")
# Every test server's kernels talk over IPC sockets, not TCP ports: jupyter_client picks a kernel's
# ports by binding port 0 and closing it again, so another process can take one before the kernel
# binds it; the kernel then dies at start, and Voila 0.5 keeps such a page loading for ever (its
# renderer's task fails and never ends the stream: seen in CI as a 240 s Page.goto timeout).
# deploy/voila/voila.py ships the same choice; the hub's servers have it too.
IPC_KERNELS = "--KernelManager.transport=ipc"


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_for_port(port: int, process: subprocess.Popen, log: Path, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"server exited with {process.returncode}:\n{log.read_text()[-3000:]}")
        with socket.socket() as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    raise RuntimeError(f"server did not open port {port} within {timeout} s:\n{log.read_text()[-3000:]}")


def jupyter_env(root: Path, **extra: str) -> dict:
    """The environment of a test server: its own JUPYTER_* folders under ``root``."""
    env = dict(os.environ)
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTERLAB_SETTINGS_DIR", "JUPYTERLAB_WORKSPACES_DIR"):
        path = root / name.lower()
        path.mkdir(parents=True, exist_ok=True)
        env[name] = str(path)
    # The runtime folder holds Jupyter Lab's kernels' IPC sockets, whose paths may not exceed 107
    # bytes: a short folder of its own rather than one under pytest's deep temporary folders.
    runtime = root / "runtime-link"
    if not runtime.exists():
        runtime.symlink_to(tempfile.mkdtemp(prefix="mtw-rt-"))
    env["JUPYTER_RUNTIME_DIR"] = str(runtime.resolve())
    # Keep off-screen outputs in the page and no news toast over the notebook.
    settings = root / "jupyterlab_settings_dir"
    (settings / "@jupyterlab" / "notebook-extension").mkdir(parents=True, exist_ok=True)
    (settings / "@jupyterlab" / "notebook-extension" / "tracker.jupyterlab-settings").write_text(
        json.dumps({"windowingMode": "none"}))
    (settings / "@jupyterlab" / "apputils-extension").mkdir(parents=True, exist_ok=True)
    (settings / "@jupyterlab" / "apputils-extension" / "notification.jupyterlab-settings").write_text(
        json.dumps({"fetchNews": "false"}))
    env.update(extra)
    return env


# The servers running now: a failing test's report carries the end of each one's log (tests/conftest.py).
RUNNING: list[Server] = []


class Server:
    """A Jupyter server (Voila or Lab) in its own process group, serving ``root/notebooks``.

    Args:
        command: the command line; ``port`` must be the one it listens on.
        root: a temporary folder for its JUPYTER_* folders, its log and ``notebooks/``.
        name: names the log file.
        base_url: what ``url(path)`` prefixes.
        token: the Lab token, if any.
        env: extra environment variables.
    """

    def __init__(self, command: list[str], port: int, root: Path, name: str, base_url: str, token: str = "",
                 env: dict | None = None):
        self.port, self.token, self.base_url, self.root = port, token, base_url, root
        self.log = root / f"{name}.log"
        self._log_file = open(self.log, "w")
        self.process = subprocess.Popen(command, cwd=root / "notebooks", env=jupyter_env(root, **(env or {})),
                                        stdout=self._log_file, stderr=subprocess.STDOUT, start_new_session=True)
        RUNNING.append(self)
        try:
            wait_for_port(port, self.process, self.log)
        except BaseException:
            self.stop()
            raise

    def url(self, path: str) -> str:
        return f"{self.base_url}{path}"

    def stop(self) -> None:
        if self in RUNNING:
            RUNNING.remove(self)
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(5)
        self._log_file.close()
        runtime = self.root / "runtime-link"
        if runtime.is_symlink():
            shutil.rmtree(runtime.resolve(), ignore_errors=True)
            runtime.unlink()


def voila(root: Path, *options: str, env: dict | None = None) -> Server:
    """Voila serving ``root/notebooks`` on a free port of 127.0.0.1."""
    port = free_port()
    return Server([str(BIN / "voila"), str(root / "notebooks"), "--no-browser", f"--port={port}",
                   "--Voila.ip=127.0.0.1", IPC_KERNELS, *options],
                  port, root, "voila", f"http://127.0.0.1:{port}", env=env)


def local_page(browser, width: int = 1280, height: int = 1100):
    """(context, page) of a fresh page that may only reach 127.0.0.1 (Voila asks a CDN for a font)."""
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    page.route("**/*", lambda route: route.continue_() if route.request.url.startswith(LOCAL_PREFIXES)
               else route.abort())
    return context, page


def artifact_path(test_name: str, step: str) -> str:
    """Where a screenshot is kept: test-artifacts/<test name>-<step>.png."""
    ARTIFACTS.mkdir(exist_ok=True)
    return str(ARTIFACTS / f"{test_name.replace('[', '-').replace(']', '')}-{step}.png")
