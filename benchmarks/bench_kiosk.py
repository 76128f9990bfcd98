"""The kiosk: server memory after N visits and time to interactive, shipped config vs stock Voila.

Run: ``python benchmarks/bench_kiosk.py`` (``--loads N``, default 20; ``--no-study`` skips the
study page). Each visit is a visitor in the kiosk's one Chromium: open the page, wait until it is
interactive, close the tab (``beforeunload`` runs, as when a person closes it). Before each visit
the server is left to settle (no CPU for 0.6 s), so "warm" means the previous visit is over and,
with preheating, the spare kernel has run the page.

- memory: resident set sizes of the Voila server and every process under it (its kernels),
  after the N visits, and the number of kernels left;
- demo page, time to interactive: navigation -> the arm drawn on the canvas and a skill
  button's click answered by the new skill's canvas (the page's ``performance.now()``); p50 and
  p95 over the warm visits (all but the first, which also fills the browser's cache); and where
  that time went (medians): the HTML received, DOMContentLoaded, the load event (every script and
  style), the first canvas element (widgets rendered), the arm drawn; requests and megabytes;
- study page: navigation -> the experimenter panel's "Start new participant" button shown.

Three servers: stock Voila (the reference), the shipped deploy/voila/voila.py, and the shipped
file with preheating off (what the spare kernel buys). Ratios are shipped / stock.

The browser keeps its HTTP cache between visits, as a kiosk's browser does: pages are kept on
127.0.0.1 by Chromium's host resolver (``kiosk.LOCAL_ONLY_ARGS``), not by Playwright's request
interception, which turns the cache off (``--no-cache`` measures that way: every visit fetches the
page's 5.3 MB again, as the benchmark did before).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]

from playwright.sync_api import sync_playwright  # noqa: E402

import tests.browser.kiosk as kiosk  # noqa: E402
from browser_support import CHROMIUM, CHROMIUM_ARGS  # noqa: E402

STUDY = ROOT / "notebooks" / "study_sim.ipynb"
SERVERS = {
    "stock Voila": dict(shipped_config=False),
    "shipped config": dict(shipped_config=True),
    "shipped, no preheat": dict(shipped_config=True, overrides=("--VoilaConfiguration.preheat_kernel=False",)),
}


def study_visit(context, server) -> float:
    """Navigation -> the lab page's first control (the experimenter's code prompt) shown, in ms; then the tab
    is closed."""
    page = context.new_page()
    page.goto(server.url(kiosk.DEMO_URL_PATH), wait_until="commit", timeout=60_000)
    page.get_by_role("button", name=re.compile(r"Open the experimenter panel")).wait_for(timeout=60_000)
    shown = page.evaluate("performance.now()")
    page.close(run_before_unload=True)
    return shown


PHASES = ("html_ms", "dom_ms", "load_ms", "canvas_ms", "drawn_ms", "requests", "transfer_mb", "body_mb")


def run(browser, notebook: Path | None, loads: int, options: dict, cache: bool = True) -> dict:
    root = Path(tempfile.mkdtemp(prefix="bench-kiosk-"))
    server = kiosk.start_page_server(root, **({"notebook": notebook} if notebook else {}), **options)
    context = kiosk.kiosk_context(browser, cache=cache)
    times, phases = [], []
    try:
        kiosk.wait_until_quiet(server)
        before = kiosk.memory_mb(server)
        for _ in range(loads):
            kiosk.wait_until_quiet(server)
            if notebook is None:
                visit = kiosk.visit(context, server)
                times.append(visit.answered_ms)
                phases.append({**visit.phases, "drawn_ms": visit.drawn_ms})
            else:
                times.append(study_visit(context, server))
        kiosk.wait_until_quiet(server)
        after = kiosk.memory_mb(server)
    finally:
        context.close()
        server.stop()
    warm = sorted(times[1:]) or times
    warm_phases = phases[1:] or phases
    return {"before": before, "after": after, "first_ms": times[0], "p50_ms": statistics.median(warm),
            "p95_ms": warm[round(0.95 * (len(warm) - 1))],
            "phases": {key: statistics.median(p[key] for p in warm_phases) for key in PHASES} if phases else None}


def _print(page: str, loads: int, results: dict) -> None:
    stock = results["stock Voila"]
    print(f"\n{page}, {loads} visits (each tab closed as a visitor closes it)")
    print(f"{'server':<22} {'memory after':>13} {'kernels':>8} {'first':>8} {'p50 warm':>9} {'p95 warm':>9}"
          f"  {'memory / stock':>14} {'p50 / stock':>11}")
    for name, r in results.items():
        own, children, kernels = r["after"]
        total = own + children
        stock_total = sum(stock["after"][:2])
        print(f"{name:<22} {total:>10.0f} MB {kernels:>8d} {r['first_ms'] / 1000:>6.2f} s {r['p50_ms'] / 1000:>7.2f} s"
              f" {r['p95_ms'] / 1000:>7.2f} s  {total / stock_total:>13.2f}x {r['p50_ms'] / stock['p50_ms']:>10.2f}x")
    if all(r.get("phases") for r in results.values()):
        print("\nwhere a warm visit's time went (medians, s from navigation; then what was fetched)")
        print(f"{'server':<22} {'HTML':>6} {'DOM':>6} {'load':>6} {'canvas':>7} {'drawn':>6} {'answered':>9}"
              f" {'requests':>9} {'wire MB':>8} {'body MB':>8}")
        for name, r in results.items():
            p = r["phases"]
            print(f"{name:<22} {p['html_ms'] / 1000:>6.2f} {p['dom_ms'] / 1000:>6.2f} {p['load_ms'] / 1000:>6.2f}"
                  f" {p['canvas_ms'] / 1000:>7.2f} {p['drawn_ms'] / 1000:>6.2f} {r['p50_ms'] / 1000:>9.2f}"
                  f" {p['requests']:>9.0f} {p['transfer_mb']:>8.2f} {p['body_mb']:>8.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", type=int, default=20, help="visits per server (default 20)")
    parser.add_argument("--no-study", action="store_true", help="skip the study page")
    parser.add_argument("--no-cache", action="store_true",
                        help="turn the browser's HTTP cache off (Playwright's interception, as before)")
    args = parser.parse_args()
    if args.loads < 2:
        parser.error(f"--loads: expected an integer >= 2 (one cold visit and warm ones), got {args.loads}")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS + kiosk.LOCAL_ONLY_ARGS)
        cache = not args.no_cache
        load_before = os.getloadavg()[0]
        demo = {name: run(browser, None, args.loads, options, cache) for name, options in SERVERS.items()}
        study = None if args.no_study else {name: run(browser, STUDY, args.loads, options, cache)
                                            for name, options in SERVERS.items()}
        browser.close()
    print(f"load average {load_before:.1f} at the start, {os.getloadavg()[0]:.1f} at the end, "
          f"on {os.cpu_count()} cores;"
          f" browser HTTP cache {'on' if cache else 'off'}")
    print("demo page: interactive = the arm drawn and a skill button's click answered")
    _print("demo page (notebooks/demo.ipynb)", args.loads, demo)
    if study:
        print("\nstudy page: interactive = the experimenter's code prompt shown")
        _print("study page (notebooks/study_sim.ipynb)", args.loads, study)


if __name__ == "__main__":
    main()
