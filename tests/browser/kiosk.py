"""The kiosk's measurements, shared by tests/browser/test_kiosk.py and benchmarks/bench_kiosk.py.

A Voila server for one page (the way scripts/serve-demo.sh serves it), with or without the
shipped configuration deploy/voila/voila.py; the memory of the server and its kernels (resident
set sizes, read with psutil, which ipykernel itself depends on); and one visit as a visitor makes
it: open the page, wait for the drawn arm, click a skill button, wait for its answer, close the
page. Times are the page's own ``performance.now()``, milliseconds since navigation started.
"""

from __future__ import annotations

import functools
import re
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import psutil

from browser_support import BIN, IPC_KERNELS, LOCAL_PREFIXES, REPO, Server, free_port
from mt_widgets.widgets import DemoPage

from .helpers import OKABE, ee_pixel, wait_for_color

DEPLOY = REPO / "deploy" / "voila"
DEMO = REPO / "notebooks" / "demo.ipynb"
DEMO_URL_PATH = "/"                     # Voila serving one notebook renders it at the root
#: The button a visit clicks once the arm is drawn, and the skill whose canvas answers it.
ANSWER_BUTTON, ANSWER_SKILL = "uArm: reach a point", "uarm-point"


def start_page_server(root: Path, notebook: Path = DEMO, *, shipped_config: bool = True,
                      overrides: tuple[str, ...] = ()) -> Server:
    """Voila serving a copy of ``notebook`` alone on 127.0.0.1, as scripts/serve-demo.sh does.

    Args:
        root: an empty temporary folder (the server's JUPYTER_* folders, log and ``notebooks/``).
        shipped_config: read deploy/voila/voila.py (True) or run stock Voila (False).
        overrides: further ``--Class.trait=value`` options; they win over the config file.
    """
    (root / "notebooks").mkdir(parents=True, exist_ok=True)
    page = root / "notebooks" / notebook.name
    shutil.copy(notebook, page)
    port = free_port()
    # The shipped config sets IPC kernels itself; stock Voila gets them from the command line, as
    # every test server does (tests/browser_support.py says why).
    config = [f"--Voila.config_file_paths={DEPLOY}"] if shipped_config else [f"--Voila.config_file_paths={root}",
                                                                            IPC_KERNELS]
    return Server([str(BIN / "voila"), str(page), "--no-browser", f"--port={port}", "--Voila.ip=127.0.0.1",
                   *config, *overrides], port, root, "voila", f"http://127.0.0.1:{port}")


def kernel_processes(server: Server) -> dict[str, psutil.Process]:
    """The server's kernels by kernel id (read from each kernel's ``-f .../kernel-<id>.json``).

    A kernel that runs a subprocess has, between fork and exec, a child with its own command
    line; that child is not the kernel, so the process kept for an id is the one whose parent
    is not the same kernel (CI once saw the transient child's pid here and then the kernel's)."""
    matches: dict[str, list[psutil.Process]] = {}
    for child in psutil.Process(server.process.pid).children(recursive=True):
        try:
            match = re.search(r"kernel-([0-9a-f-]{36})\.json", " ".join(child.cmdline()))
        except psutil.NoSuchProcess:
            continue
        if match:
            matches.setdefault(match.group(1), []).append(child)
    def parent(process: psutil.Process) -> int | None:
        try:
            return process.ppid()
        except psutil.NoSuchProcess:
            return None

    kernels = {}
    for kernel_id, processes in matches.items():
        pids = {process.pid for process in processes}
        kernels[kernel_id] = next((p for p in processes if parent(p) not in pids), processes[0])
    return kernels


def memory_mb(server: Server) -> tuple[float, float, int]:
    """(server RSS, RSS of all its descendants, number of kernels), in MiB."""
    root = psutil.Process(server.process.pid)
    own = root.memory_info().rss
    children = 0
    for child in root.children(recursive=True):
        try:
            children += child.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return own / 2**20, children / 2**20, len(kernel_processes(server))


def spares_pending(server: Server) -> int:
    """How many preheated kernels the server still owes its pools (0 without preheating).

    Voila logs "Using pre-heated kernel: <id> for <notebook>" when a visitor takes a spare and
    "Kernel pool of <notebook> is filled" once the refill's kernel has started (after the
    configured ``fill_delay``); the first fill logs the latter once.
    """
    log = server.log.read_text()
    taken = re.findall(r"Using pre-heated kernel: \S+ for (.+)", log)
    filled = re.findall(r"Kernel pool of (.+) is filled", log)
    return sum(max(0, taken.count(name) + 1 - filled.count(name)) for name in set(taken) | set(filled))


def wait_until_quiet(server: Server, window: float = 0.6, timeout: float = 60.0) -> None:
    """Wait until the server's pools are refilled and it and its kernels use no CPU for ``window`` seconds.

    A preheated kernel is ready for the next visitor only once it has run the page's notebook;
    Voila logs "pool filled" as soon as the kernel starts (``spares_pending``), so the idle CPU
    after that is the signal.
    """
    deadline = time.monotonic() + timeout
    while spares_pending(server) and time.monotonic() < deadline:
        time.sleep(0.1)
    root = psutil.Process(server.process.pid)

    def cpu() -> float:
        total = sum(root.cpu_times()[:2])
        for child in root.children(recursive=True):
            try:
                total += sum(child.cpu_times()[:2])
            except psutil.NoSuchProcess:
                pass
        return total

    before = cpu()
    while time.monotonic() < deadline:
        time.sleep(window)
        now = cpu()
        if now - before < 0.02:                     # 20 ms of CPU in a window: timer ticks only
            return
        before = now
    raise AssertionError(f"the server did not settle within {timeout} s")


#: Chromium arguments that keep every host but 127.0.0.1 unresolvable: pages reach nothing else
#: without Playwright's request interception, which turns the HTTP cache off (a kiosk's browser
#: keeps its cache between visitors; a benchmark must too).
LOCAL_ONLY_ARGS = ["--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1"]


def kiosk_context(browser, width: int = 1280, height: int = 1100, cache: bool = False):
    """The kiosk's one browser context (its HTTP cache is shared by every visit); 127.0.0.1 only.

    ``cache``: keep the HTTP cache on, as a kiosk's browser has it; the browser must then have been
    launched with ``LOCAL_ONLY_ARGS`` (nothing is intercepted). Without it every request goes
    through Playwright's router, which aborts the non-local ones and disables the cache, and
    loses some of the shutdown beacons a closing page sends (2 of 10 visits, against 0 of 10 with
    ``cache``): a test that counts beacons needs ``cache``.
    """
    context = browser.new_context(viewport={"width": width, "height": height})
    if not cache:
        context.route("**/*", lambda route: route.continue_() if route.request.url.startswith(LOCAL_PREFIXES)
                      else route.abort())
    return context


@dataclass
class Visit:
    kernel_id: str
    drawn_ms: float          # navigation -> the arm drawn on the teaching canvas
    answered_ms: float       # navigation -> a skill button's click answered by the new skill's canvas
    #: Where the time went, each from navigation (ms): the page's HTML received, DOMContentLoaded
    #: done, the load event done (the page's own scripts and styles loaded), the kernel asked for
    #: (Voila's app has loaded its extensions and starts the widget manager's connection), the
    #: first canvas element on the page (the widgets rendered); and what was fetched: requests,
    #: MB over the wire, MB of bodies, and how many of the requests the server answered (not
    #: the browser's cache: ``transferSize`` > 0).
    phases: dict | None = None


#: Notes, in the page, when the first canvas element is inserted into the document (ms since
#: navigation; the arm is drawn on it within a frame or two). Every time a visit reports is taken in
#: the page like this, or by a check the page runs on every animation frame (``wait_for_color``):
#: Playwright's own waits for a selector poll from the test's process at 0, 20, 50, 100, 100 and then
#: every 500 ms, so a time read after them is late by up to half a second (seen in 7 warm visits:
#: the canvas inserted at 0.53-0.91 s, found 0.08-0.51 s later).
NOTE_FIRST_CANVAS = """
new MutationObserver((_, observer) => {
  if (document.querySelector('canvas')) { window.__firstCanvas = performance.now(); observer.disconnect(); }
}).observe(document, {subtree: true, childList: true});
"""


@functools.lru_cache(maxsize=1)
def reference_episodes():
    """The page's first episode and the one its button opens, built without a kernel (for expected pixels)."""
    return DemoPage().episode, DemoPage(skill=ANSWER_SKILL).episode


def visit(context, server: Server, *, unload: bool = True, keep_open: bool = False, screenshot: str = ""):
    """One visitor: open the demo page, wait for the arm, click a skill, wait for its canvas, close.

    Args:
        unload: close as a tab is closed (``beforeunload`` runs, so Voila's page asks for its
            kernel's shutdown) or vanish without it (a killed browser, a discarded phone tab).
        keep_open: leave the page open and return it too.
    Returns:
        the ``Visit`` (and the page when ``keep_open``).
    """
    first, answer = reference_episodes()
    page = context.new_page()
    page.add_init_script(NOTE_FIRST_CANVAS)
    page.goto(server.url(DEMO_URL_PATH), wait_until="commit", timeout=60_000)
    drawn = wait_for_color(page, 0, *ee_pixel(first), OKABE["yellow"], timeout=60_000)
    canvas_ms = page.evaluate("window.__firstCanvas")
    assert canvas_ms is not None, "the arm was drawn, yet the page's observer saw no canvas inserted"
    phases = page.evaluate("""() => { const n = performance.getEntriesByType('navigation')[0];
        const r = performance.getEntriesByType('resource');
        const kernel = r.find(e => /\\/api\\/kernels\\/[0-9a-f-]{36}/.test(e.name));
        return {html_ms: n.responseEnd, dom_ms: n.domContentLoadedEventEnd, load_ms: n.loadEventEnd,
                kernel_ms: kernel ? kernel.startTime : NaN, requests: r.length + 1,
                served: 1 + r.filter(e => e.transferSize > 0).length,
                transfer_mb: (n.transferSize + r.reduce((a, e) => a + e.transferSize, 0)) / 1e6,
                body_mb: (n.encodedBodySize + r.reduce((a, e) => a + e.encodedBodySize, 0)) / 1e6}; }""")
    phases["canvas_ms"] = canvas_ms
    page.get_by_role("button", name=ANSWER_BUTTON, exact=True).click()
    answered = wait_for_color(page, 0, *ee_pixel(answer), OKABE["black"], tolerance=20, timeout=60_000)
    if screenshot:
        page.screenshot(path=screenshot)
    kernel_id = page.evaluate("() => JSON.parse(document.getElementById('jupyter-config-data').textContent).kernelId")
    result = Visit(kernel_id, drawn, answered, phases)
    if keep_open:
        return result, page
    page.close(run_before_unload=unload)
    return result


def wait_for_exit(server: Server, kernel_id: str, timeout: float) -> float:
    """Seconds until kernel ``kernel_id``'s process is gone; fails after ``timeout``."""
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        if kernel_id not in kernel_processes(server):
            return time.monotonic() - started
        time.sleep(0.2)
    raise AssertionError(f"kernel {kernel_id} still runs {timeout} s later")
