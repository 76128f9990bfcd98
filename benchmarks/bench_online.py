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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--participants", default="4,8", help="group sizes, comma-separated (default 4,8)")
    parser.add_argument("--think", type=float, default=3.0, help="seconds between a participant's actions")
    args = parser.parse_args()
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
