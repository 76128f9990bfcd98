"""The online study page on one machine: concurrent participants at human pace, memory and response time.

Run: ``python benchmarks/bench_online.py`` (``--participants 4,8`` the group sizes, ``--think S``
seconds between a participant's actions, default 3). One Voila server with the shipped
configuration (deploy/voila/voila.py) serves notebooks/study_online.ipynb with the shipped pilot
protocol; N participants arrive by their own Prolific URL at once (N tabs of one Chromium) and
each goes through the welcome, consent, the eligibility question, age and sex, and into the
practice, one action every ``--think`` seconds, as a person would. Measured:

- arrival: navigation -> the welcome text shown (p50, p95, worst);
- response: a button's click -> the next screen's text shown (p50, p95, worst), every action of
  every participant, while the others' pages run (practice clocks tick every second);
- memory: resident set sizes of the server and all its kernels once everyone is in the
  practice, and per kernel.

Target: every response within 1 s at p95 (what feels immediate for a page that changes screen),
and memory bounded by the kernels of the open pages (about 200 MB each). The browser runs on the
same 2 cores, so the figures are an upper bound of what a dedicated server gives.

Burst mode (``--burst N --window W``, issue 29): N participants open their Prolific links at
random moments (uniform, seeded) within W seconds. By default at the widget-state level, as a
page's widget manager sees it without a browser: the page's HTML read to its end (its cells run
in its kernel), then its kernel's widget states asked for over the websocket, as the page's
widget manager does, until they hold the welcome text; printed with where the time went (first
bytes, kernel id in the page, cells run, welcome) and the CPU seconds of the server, the kernel
template and the kernels during the burst. With ``--browser`` each arrival is a tab of one
Chromium: time from the navigation to the welcome screen's text shown (the page notes it
itself, so a page read late is timed right). Both give p50 / p95 / worst, and PSS per
participant (server, kernel template and kernels together, once all have arrived). ``--compare``
runs the same burst with kernels started the usual way (``MT_KERNEL_TEMPLATE=off``) for the
ratio. Targets: p95 <= 5 s, worst <= 10 s, <= 100 MiB PSS per participant (issue 29, idle
machine). The load average is printed beside the figures.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path
from urllib.parse import urlencode

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]

import psutil  # noqa: E402
from playwright.sync_api import sync_playwright  # noqa: E402

from browser_support import CHROMIUM, CHROMIUM_ARGS, local_page, voila  # noqa: E402

#: (button to press, text of the screen it leads to), with the form input each screen needs.
PATH = [("Continue", "By pressing \"I agree\""), ("I agree", "Have you studied robotics"),
        ("Continue", "Your age, in years"), ("Continue", "The robot is a two-link arm"),
        ("Start the practice", "Practice time left")]


def button(page, name):
    return page.get_by_role("button", name=re.compile(rf"^\W*{re.escape(name)}\s*$"))


def memory_mb(server) -> tuple[float, float, int]:
    """(server RSS, RSS of everything under it, number of kernels), in MiB."""
    root = psutil.Process(server.process.pid)
    children, kernels = 0, 0
    for child in root.children(recursive=True):
        try:
            children += child.memory_info().rss
            kernels += "ipykernel" in " ".join(child.cmdline())
        except psutil.NoSuchProcess:
            pass
    return root.memory_info().rss / 2**20, children / 2**20, kernels


def percentile(values, q):
    ordered = sorted(values)
    return ordered[round(q * (len(ordered) - 1))]


def run(browser, n: int, think_s: float) -> dict:
    root = Path(tempfile.mkdtemp(prefix="bench-online-"))
    (root / "notebooks").mkdir()
    for name in ("study_online.ipynb", "study_online_pilot.toml"):
        shutil.copy(ROOT / "notebooks" / name, root / "notebooks" / name)
    server = voila(root, f"--Voila.config_file_paths={ROOT / 'deploy' / 'voila'}",
                   env={"MT_WIDGETS_STUDY_LOGS": str(root / "logs")})
    pages, arrivals, responses = [], [], []
    try:
        time.sleep(5.0)  # the preheated spare runs the notebook up to its wait for a request
        for i in range(n):
            context, page = local_page(browser, 1280, 1000)
            query = urlencode({"PROLIFIC_PID": f"5f0a1b2c3d4e5f6a7b8c{i:04d}", "STUDY_ID": "BENCH",
                               "SESSION_ID": f"S{i}"})
            started = time.monotonic()
            page.goto(f"{server.url('/voila/render/study_online.ipynb')}?{query}", wait_until="commit",
                      timeout=300_000)
            pages.append((context, page, started))
        for _, page, started in pages:
            page.get_by_text("Welcome, and thank you for taking part.").wait_for(timeout=300_000)
            arrivals.append(time.monotonic() - started)
        for name, next_text in PATH:
            round_start = time.monotonic()
            for _, page, _ in pages:
                if next_text == "The robot is a two-link arm":
                    page.get_by_placeholder("a number (years)").fill("30")
                    page.get_by_role("radio", name="female").check()
                elif next_text == "Your age, in years":
                    page.get_by_role("radio", name="no").check()
                clicked = time.monotonic()
                button(page, name).click()
                page.get_by_text(next_text).first.wait_for(timeout=120_000)
                responses.append(time.monotonic() - clicked)
            time.sleep(max(0.0, think_s - (time.monotonic() - round_start)))
        own, children, kernels = memory_mb(server)
    finally:
        for context, _, _ in pages:
            context.close()
        server.stop()
        shutil.rmtree(root, ignore_errors=True)
    return {"arrivals": arrivals, "responses": responses, "server_mb": own, "kernels_mb": children,
            "kernels": kernels}


WELCOME = "Welcome, and thank you for taking part."


def pss_mib(server) -> tuple[float, int]:
    """(PSS of the server and everything under it in MiB, number of processes)."""
    root = psutil.Process(server.process.pid)
    total, count = 0, 0
    for process in [root, *root.children(recursive=True)]:
        try:
            total += process.memory_full_info().pss
            count += 1
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            pass
    return total / 2**20, count


#: Notes, in the page, the moment its welcome screen appears (ms since the navigation started).
WATCH_WELCOME = """
new MutationObserver((_, observer) => {
  if (document.body && document.body.innerText.includes(WELCOME)) {
    window.__welcome = performance.now();
    observer.disconnect();
  }
}).observe(document, {subtree: true, childList: true, characterData: true});
""".replace("WELCOME", repr(WELCOME))


def burst(browser, n: int, window_s: float, template: bool, seed: int = 29) -> dict:
    """N arrivals within ``window_s``: seconds from each one's navigation to its welcome screen, and PSS."""
    import random

    root = Path(tempfile.mkdtemp(prefix="bench-online-burst-"))
    (root / "notebooks").mkdir()
    for name in ("study_online.ipynb", "study_online_pilot.toml"):
        shutil.copy(ROOT / "notebooks" / name, root / "notebooks" / name)
    env = {"MT_WIDGETS_STUDY_LOGS": str(root / "logs"), "MT_KERNEL_TEMPLATE": "on" if template else "off"}
    server = voila(root, f"--Voila.config_file_paths={ROOT / 'deploy' / 'voila'}", env=env)
    rng = random.Random(seed)  # one generator: a new one per draw gave every arrival the same moment
    offsets = sorted(rng.uniform(0, window_s) for _ in range(n))
    pages, times, errors = [], [], []
    try:
        time.sleep(8.0)  # the server's start and its preheated spare, before the study opens
        start = time.monotonic()
        for i, offset in enumerate(offsets):
            time.sleep(max(0.0, start + offset - time.monotonic()))
            context, page = local_page(browser, 1280, 1000)
            page.add_init_script(WATCH_WELCOME)
            query = urlencode({"PROLIFIC_PID": f"5f0a1b2c3d4e5f6a7b8c{i:04d}", "STUDY_ID": "BENCH",
                               "SESSION_ID": f"S{i}"})
            page.goto(f"{server.url('/voila/render/study_online.ipynb')}?{query}", wait_until="commit",
                      timeout=300_000)
            pages.append((context, page))
        for i, (_, page) in enumerate(pages):
            try:
                page.wait_for_function("window.__welcome !== undefined", timeout=600_000)
                times.append(page.evaluate("window.__welcome") / 1000)
            except Exception as error:  # a lost arrival is reported, not retried
                errors.append(f"arrival {i}: {error!r}"[:300])
        pss, processes = pss_mib(server)
    finally:
        for context, _ in pages:
            context.close()
        server.stop()
        shutil.rmtree(root, ignore_errors=True)
    return {"times": times, "errors": errors, "pss_mib": pss, "processes": processes}


def _cpu_by_kind(server) -> dict:
    """CPU seconds (user + system) of the server, its kernel template and its kernels, so far."""
    root = psutil.Process(server.process.pid)
    kinds = {"server": 0.0, "template": 0.0, "kernels": 0.0}
    for process in [root, *root.children(recursive=True)]:
        try:
            times, command = process.cpu_times(), " ".join(process.cmdline())
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
        kind = ("server" if process.pid == root.pid else "template" if "mt_widgets.kernels.template" in command
                else "kernels")
        kinds[kind] += times.user + times.system
    return kinds


async def _arrive(session, server, i: int, offset: float, start: float) -> dict:
    """One participant at the widget-state level: the page's HTML, then its kernel's widget states over the websocket.

    Stages (seconds from the request): ``head`` the first bytes of the page, ``kernel`` its kernel id
    in the page (the kernel started), ``cells`` the page's cells executed (the HTML's end),
    ``welcome`` the welcome text in the widgets' state, as the page's widget manager asks for it.
    """
    import asyncio
    import json as _json
    import uuid

    await asyncio.sleep(max(0.0, start + offset - time.monotonic()))
    query = urlencode({"PROLIFIC_PID": f"5f0a1b2c3d4e5f6a7b8c{i:04d}", "STUDY_ID": "BENCH", "SESSION_ID": f"S{i}"})
    t0 = time.monotonic()
    stages, kernel_id, html = {"at": t0 - start}, None, ""
    async with session.get(f"{server.url('/voila/render/study_online.ipynb')}?{query}") as response:
        async for chunk in response.content.iter_any():
            stages.setdefault("head", time.monotonic() - t0)
            html += chunk.decode(errors="replace")
            if kernel_id is None:
                found = re.search(r'"kernelId": "([0-9a-f-]{36})"', html)
                if found:
                    kernel_id = found.group(1)
                    stages["kernel"] = time.monotonic() - t0
    stages["cells"] = time.monotonic() - t0
    if kernel_id is None:
        raise RuntimeError(f"arrival {i}: no kernel id in the page ({len(html)} characters)")
    ws = await session.ws_connect(server.url(f"/api/kernels/{kernel_id}/channels").replace("http", "ws", 1))
    comm_id, session_id = uuid.uuid4().hex, uuid.uuid4().hex

    def message(msg_type, content, metadata=None):
        return {"header": {"msg_id": uuid.uuid4().hex, "msg_type": msg_type, "username": "", "session": session_id,
                           "date": "", "version": "5.3"}, "parent_header": {}, "metadata": metadata or {},
                "content": content, "channel": "shell", "buffers": []}

    await ws.send_json(message("comm_open", {"comm_id": comm_id, "target_name": "jupyter.widget.control",
                                             "data": {}}, {"version": "1.0.0"}))
    await ws.send_json(message("comm_msg", {"comm_id": comm_id, "data": {"method": "request_states"}}))
    async for received in ws:
        if received.type != 1:  # aiohttp.WSMsgType.TEXT
            continue
        msg = _json.loads(received.data)
        content = msg.get("content", {})
        if msg.get("msg_type") == "comm_msg" and content.get("comm_id") == comm_id:
            if content["data"].get("method") == "update_states":
                if WELCOME not in _json.dumps(content["data"]["states"]):
                    raise RuntimeError(f"arrival {i}: no welcome text in the widgets' state")
                stages["welcome"] = time.monotonic() - t0
                break
    return {"stages": stages, "ws": ws}


EXTRA = [a for a in os.environ.get("BENCH_VOILA_OPTIONS", "").split(" ") if a]
SPARE = "pool_size\":0}}" not in " ".join(EXTRA)


def _wait_until_ready(server, template: bool, timeout_s: float = 300.0) -> None:
    """Until the server has started its kernel template (when it forks kernels) and its preheated
    spare, as a study server has long before its participants arrive; then 3 s for the spare's page."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        text = Path(server.log).read_text(errors="replace")
        if ("is filled with 1 kernel" in text or not SPARE) and (not template or "kernel template ready" in text):
            time.sleep(3.0)
            return
        time.sleep(0.5)
    raise RuntimeError(f"the server was not ready after {timeout_s:.0f} s (log: {server.log})")


def state_burst(n: int, window_s: float, template: bool, seed: int = 29) -> dict:
    """N arrivals within ``window_s`` at the widget-state level (no browser): stages, CPU by process, PSS."""
    import asyncio
    import random

    import aiohttp

    root = Path(tempfile.mkdtemp(prefix="bench-online-burst-"))
    (root / "notebooks").mkdir()
    for name in ("study_online.ipynb", "study_online_pilot.toml"):
        shutil.copy(ROOT / "notebooks" / name, root / "notebooks" / name)
    env = {"MT_WIDGETS_STUDY_LOGS": str(root / "logs"), "MT_KERNEL_TEMPLATE": "on" if template else "off"}
    server = voila(root, f"--Voila.config_file_paths={ROOT / 'deploy' / 'voila'}", *EXTRA, env=env)
    rng = random.Random(seed)  # one generator: a new one per draw gave every arrival the same moment
    offsets = sorted(rng.uniform(0, window_s) for _ in range(n))
    results, errors = [], []

    async def everyone():
        timeout = aiohttp.ClientTimeout(total=900)
        async with aiohttp.ClientSession(timeout=timeout) as session:
            start = time.monotonic()
            outcomes = await asyncio.gather(*(_arrive(session, server, i, offset, start)
                                              for i, offset in enumerate(offsets)), return_exceptions=True)
            for outcome in outcomes:
                (errors.append(repr(outcome)[:300]) if isinstance(outcome, BaseException) else results.append(outcome))
            pss = pss_mib(server)  # every page still open: its websocket is
            for outcome in results:
                await outcome["ws"].close()
            return pss

    try:
        _wait_until_ready(server, template)
        cpu_before, own_before = _cpu_by_kind(server), sum(os.times()[:2])
        (pss, processes) = asyncio.run(everyone())
        cpu = {kind: seconds - cpu_before.get(kind, 0.0) for kind, seconds in _cpu_by_kind(server).items()}
        cpu["client"] = sum(os.times()[:2]) - own_before
    finally:
        server.stop()
        shutil.rmtree(root, ignore_errors=True)
    return {"times": [r["stages"]["welcome"] for r in results], "stages": [r["stages"] for r in results],
            "errors": errors, "pss_mib": pss, "processes": processes, "cpu": cpu}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--participants", default="4,8", help="group sizes, comma-separated (default 4,8)")
    parser.add_argument("--think", type=float, default=3.0, help="seconds between a participant's actions")
    parser.add_argument("--burst", type=int, default=0, help="burst mode: N arrivals (no browser)")
    parser.add_argument("--window", type=float, default=60.0, help="burst mode: within this many seconds")
    parser.add_argument("--compare", action="store_true", help="burst mode: also with kernels started the usual way")
    parser.add_argument("--browser", action="store_true",
                        help="burst mode: each arrival a Chromium tab (default: at the widget-state level, no browser)")
    args = parser.parse_args()
    if args.burst:
        if args.burst < 1 or args.window < 0:
            parser.error(f"--burst/--window: expected N >= 1 and W >= 0, got {args.burst} and {args.window}")
        print(f"burst of {args.burst} within {args.window:.0f} s; load average {os.getloadavg()[0]:.1f} on "
              f"{os.cpu_count()} cores at the start")
        results = {}
        if args.browser:
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
                for template in ([True, False] if args.compare else [True]):
                    results[template] = burst(browser, args.burst, args.window, template)
                browser.close()
        else:
            for template in ([True, False] if args.compare else [True]):
                results[template] = state_burst(args.burst, args.window, template)
        for template, r in results.items():
            label = "forked kernels" if template else "usual kernels"
            t = r["times"] or [float("nan")]
            print(f"{label:>15}: welcome p50 {statistics.median(t):.1f} s, p95 {percentile(t, 0.95):.1f} s, worst "
                  f"{max(t):.1f} s ({len(r['times'])}/{args.burst} arrived); PSS {r['pss_mib']:.0f} MiB, "
                  f"{r['pss_mib'] / args.burst:.0f} MiB per participant ({r['processes']} processes); "
                  f"load average {os.getloadavg()[0]:.1f}   targets p95 <= 5 s, worst <= 10 s, <= 100 MiB", flush=True)
            for error in r["errors"]:
                print("   ", error)
            if "stages" in r and r["stages"]:
                print("    where the time went (s from the request, p50 / p95): " + ", ".join(
                    f"{stage} {percentile([x[stage] for x in r['stages']], 0.5):.2f} / "
                    f"{percentile([x[stage] for x in r['stages']], 0.95):.2f}"
                    for stage in ("head", "kernel", "cells", "welcome")))
                cores = os.cpu_count()
                print("    CPU seconds during the burst: " + ", ".join(
                    f"{kind} {s:.1f} ({s / args.burst:.2f} per arrival)" for kind, s in r["cpu"].items())
                    + f"; {cores} cores over the {args.window:.0f} s window give {cores * args.window:.0f}")
        if args.compare and results[True]["times"] and results[False]["times"]:
            forked, usual = results[True], results[False]
            ratio = percentile(forked["times"], 0.95) / percentile(usual["times"], 0.95)
            print(f"ratio forked/usual: p95 {ratio:.2f}, PSS {forked['pss_mib'] / usual['pss_mib']:.2f}")
        return
    try:
        sizes = [int(n) for n in args.participants.split(",")]
    except ValueError:
        parser.error(f"--participants: expected whole numbers separated by commas, got {args.participants!r}")
    if any(n < 1 for n in sizes):
        parser.error(f"--participants: expected sizes >= 1, got {sizes}")
    print(f"{'participants':>12} {'arrival p50/p95/max':>22} {'response p50/p95/max':>24} {'memory':>9} "
          f"{'kernels':>8} {'per kernel':>11}  target p95 <= 1 s", flush=True)
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        for n in sizes:  # each row as soon as it is measured: a larger group may not fit
            r = run(browser, n, args.think)
            a, s = r["arrivals"], r["responses"]
            total = r["server_mb"] + r["kernels_mb"]
            per = r["kernels_mb"] / max(r["kernels"], 1)
            print(f"{n:>12} {statistics.median(a):>7.1f} /{percentile(a, 0.95):>5.1f} /{max(a):>5.1f} s "
                  f"{statistics.median(s):>8.2f} /{percentile(s, 0.95):>5.2f} /{max(s):>5.2f} s {total:>6.0f} MB "
                  f"{r['kernels']:>8d} {per:>8.0f} MB  {percentile(s, 0.95):.2f}x", flush=True)
        browser.close()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores at the end (browser on the same cores)")


if __name__ == "__main__":
    main()
