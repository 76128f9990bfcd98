"""What every real-browser test shares: Chromium's launch settings, local-only pages, and
Jupyter servers in their own process groups.

The one Playwright instance is the session fixture ``browser`` in ``tests/conftest.py``:
Playwright's sync API refuses a second instance while one runs, so no folder starts its own.
A missing Chromium or Playwright fails the tests, never skips them (docs/browser-testing.md).
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
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
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTERLAB_SETTINGS_DIR", "JUPYTERLAB_WORKSPACES_DIR", "JUPYTER_RUNTIME_DIR"):
        path = root / name.lower()
        path.mkdir(parents=True, exist_ok=True)
        env[name] = str(path)
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
        self.port, self.token, self.base_url = port, token, base_url
        self.log = root / f"{name}.log"
        self._log_file = open(self.log, "w")
        self.process = subprocess.Popen(command, cwd=root / "notebooks", env=jupyter_env(root, **(env or {})),
                                        stdout=self._log_file, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            wait_for_port(port, self.process, self.log)
        except BaseException:
            self.stop()
            raise

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


def voila(root: Path, *options: str, env: dict | None = None) -> Server:
    """Voila serving ``root/notebooks`` on a free port of 127.0.0.1."""
    port = free_port()
    return Server([str(BIN / "voila"), str(root / "notebooks"), "--no-browser", f"--port={port}",
                   "--Voila.ip=127.0.0.1", *options], port, root, "voila", f"http://127.0.0.1:{port}", env=env)


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


# -- helpers of the pages' tests: buttons, drags on a canvas, the marker, a participant's log --------

#: The end-effector marker's colour (Okabe-Ito yellow).
MARKER_RGB = (240, 228, 66)


def button(page, name: str):
    """The button named ``name``: icons add to a button's accessible name, so match the words only."""
    import re

    return page.get_by_role("button", name=re.compile(rf"^\W*{re.escape(name)}\s*$"))


def drag_from(page, pixel, offset, steps: int = 4) -> None:
    """A real drag on the first canvas from canvas ``pixel`` by ``offset`` (canvas pixels), through the
    element's CSS-scaled box, in ``steps`` moves."""
    import numpy as np

    element = page.locator("canvas").first
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")

    def to_page(x, y):
        return box["x"] + x * box["width"] / width, box["y"] + y * box["height"] / height

    start = to_page(*pixel)
    end = to_page(pixel[0] + offset[0], pixel[1] + offset[1])
    page.mouse.move(*start)
    page.mouse.down()
    for fraction in np.linspace(1.0 / steps, 1.0, steps):
        page.mouse.move(start[0] + fraction * (end[0] - start[0]), start[1] + fraction * (end[1] - start[1]))
    page.mouse.up()


def drag_and_confirm(page, pixel, offset, tries: int = 4, wait_ms: float = 4_000) -> None:
    """Drags the arrow (``drag_from``) and clicks Confirm once it is enabled; the canvas takes the drag
    once the state is drawn, so a drag that left Confirm disabled is made again (``tries`` in all)."""
    confirm = button(page, "Confirm")
    for _ in range(tries):
        drag_from(page, pixel, offset)
        try:
            page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(), timeout=wait_ms)
            break
        except Exception:
            continue
    confirm.click()


def wait_for_marker(page, pixel, canvases: int = 2, timeout: float = 15_000) -> None:
    """Waits until the page holds ``canvases`` canvases (one episode: teaching and reproduction) and
    the first shows the end-effector marker at ``pixel``: drawn, not just present."""
    page.wait_for_function(
        """([x, y, rgb, n]) => {
            const all = document.querySelectorAll('canvas');
            if (all.length !== n) return false;
            const d = all[0].getContext('2d').getImageData(Math.round(x) - 2, Math.round(y) - 2, 5, 5).data;
            for (let i = 0; i < d.length; i += 4) {
                if (Math.abs(d[i] - rgb[0]) < 40 && Math.abs(d[i + 1] - rgb[1]) < 40
                    && Math.abs(d[i + 2] - rgb[2]) < 40 && d[i + 3] > 200) return true;
            }
            return false;
        }""", arg=[float(pixel[0]), float(pixel[1]), list(MARKER_RGB), canvases], timeout=timeout)


def log_events(logs: Path, participant: str) -> list[dict]:
    """The events of ``participant``'s log in the study folder ``logs`` so far ([] before it exists)."""
    from mt_widgets.study import read_events

    path = Path(logs) / f"{participant}.jsonl"
    return read_events(path)[0] if path.exists() else []


def wait_for_log(logs: Path, participant: str, predicate, timeout: float = 15.0, poll: float = 0.05) -> list[dict]:
    """Waits until ``predicate(events)`` holds for ``participant``'s log; returns the events."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        events = log_events(logs, participant)
        if predicate(events):
            return events
        time.sleep(poll)
    last = log_events(logs, participant)[-1:]
    raise AssertionError(f"{participant}: the log never satisfied the condition; last event: {last}")


def current_episode(logs: Path, participant: str) -> dict:
    """The ``episode_started`` event of ``participant``'s current episode."""
    return [e for e in log_events(logs, participant) if e["type"] == "episode_started"][-1]


#: The study page as Voila serves it (tests/browser_study/conftest.py copies notebooks/study_sim.ipynb).
STUDY_PAGE = "/voila/render/study_sim.ipynb"


def open_and_fill(page, server, protocol_path, participant: str) -> None:
    """Opens the study page, chooses the protocol file (named "browser") and types the participant's ID."""
    page.goto(server.url(STUDY_PAGE), timeout=60_000)
    page.get_by_text("Experimenter", exact=True).wait_for(timeout=60_000)
    protocol = page.get_by_placeholder("paper-sim, paper-uarm or a .toml/.json file")
    protocol.fill(str(protocol_path))
    protocol.press("Enter")
    page.get_by_text("Protocol 'browser'").wait_for(timeout=10_000)
    page.get_by_placeholder("pseudonymous code, e.g. P07").fill(participant)
