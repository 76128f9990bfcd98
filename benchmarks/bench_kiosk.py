"""The kiosk: server memory after N visits and time to interactive, shipped config vs stock Voila.

Run: ``.venv/bin/python benchmarks/bench_kiosk.py`` (about 6 minutes on an idle 2-core machine).
Arguments:

- ``--loads N``: visits per server and page (default 11: one cold visit, then 10 warm ones whose
  p50 and p95 are reported);
- ``--no-study``: skip the study page (notebooks/study_sim.ipynb), measure the demo page only;
- ``--no-cache``: turn the browser's HTTP cache off (Playwright's request interception), as a
  visitor's first visit, or every visit of a browser that keeps no cache;
- ``--server NAME=OPTIONS``: add a server: the shipped file with these Voila options on top
  (space-separated ``--Class.trait=value``), e.g. ``--server "no refill delay=--VoilaKernelManager.fill_delay=0"``;
  repeat it to compare several. This is how each of the shipped file's choices is priced.

Each visit is a visitor in the kiosk's one Chromium: open the page, wait until it is
interactive, close the tab (``beforeunload`` runs, as when a person closes it). The servers run
side by side and are visited in turn (one visit of each, then the next round), so a machine whose
load changes during the run slows every server alike and the ratios stay fair; before each visit
every server has refilled its pool of preheated kernels and all of them are left to settle (no CPU
for 0.6 s): "warm" means the previous visits are over and, with preheating, the spare kernel has
run the page.

- memory: resident set sizes of each Voila server and every process under it (its kernels),
  after the N visits, and the number of kernels left;
- demo page, time to interactive: navigation -> the arm drawn on the canvas and a skill
  button's click answered by the new skill's canvas (the page's ``performance.now()``, each taken in
  the page when it happened, not when Playwright heard of it: ``NOTE_FIRST_CANVAS`` in
  tests/browser/kiosk.py says why); p50 and
  p95 over the warm visits (all but the first, which also fills the browser's cache); and where
  that time went (medians, from navigation): the HTML received, DOMContentLoaded, the load event
  (the page's own scripts and styles), the kernel asked for (Voila's app has loaded its
  extensions and connects the widget manager), the first canvas element (widgets rendered), the
  arm drawn, the click answered; requests, those the server answered (the rest came from the
  browser's cache), megabytes over the wire and of bodies;
- study page: navigation -> the lab page's first control shown.

Servers: stock Voila (the reference), the shipped deploy/voila/voila.py, the shipped file with
preheating off (what the spare kernel buys), and any ``--server``. Ratios are to stock Voila in
the same run. The load average is printed at the start and the end: on a machine shared with
other work the times grow with it, the ratios much less.

Each server has its own Chromium, whose profile (and HTTP cache) on disk is kept between visits,
as a kiosk's browser keeps it (one Chromium's in-memory contexts for several servers were seen
to lose their cached scripts between visits). Pages are kept on 127.0.0.1 by Chromium's host
resolver (``kiosk.LOCAL_ONLY_ARGS``), not by Playwright's request interception, which turns the
cache off (``--no-cache`` measures that way).
"""

from __future__ import annotations

import argparse
import os
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
    # Checked in the page on every animation frame, so the time is the page's (kiosk.NOTE_FIRST_CANVAS
    # says why not Playwright's own wait).
    shown = page.wait_for_function("""() => { for (const b of document.querySelectorAll('button'))
            if (b.textContent.includes('Open the experimenter panel') && b.offsetParent !== null)
                return performance.now();
        return false; }""", polling="raf", timeout=60_000).json_value()
    page.close(run_before_unload=True)
    return shown


PHASES = ("html_ms", "dom_ms", "load_ms", "kernel_ms", "canvas_ms", "drawn_ms", "requests", "served",
          "transfer_mb", "body_mb")


def _browser_context(playwright, cache: bool):
    """A kiosk's browser: with its cache, a Chromium of its own with a profile on disk (as a kiosk's
    browser keeps its cache, and no other server's visits evict it); without, a context of one
    shared Chromium whose every request goes through Playwright's router."""
    if not cache:
        return kiosk.kiosk_context(playwright["shared"](), cache=False)
    return playwright["api"].chromium.launch_persistent_context(
        tempfile.mkdtemp(prefix="bench-kiosk-profile-"), executable_path=CHROMIUM,
        args=CHROMIUM_ARGS + kiosk.LOCAL_ONLY_ARGS, viewport={"width": 1280, "height": 1100})


def run(browser, notebook: Path | None, loads: int, servers: dict, cache: bool = True) -> dict:
    """Visit every server ``loads`` times, in turn; {name: figures}."""
    started, results, contexts = {}, {}, {}
    try:
        for name, options in servers.items():
            root = Path(tempfile.mkdtemp(prefix="bench-kiosk-"))
            started[name] = kiosk.start_page_server(root, **({"notebook": notebook} if notebook else {}), **options)
        for name in servers:
            contexts[name] = _browser_context(browser, cache)
        for server in started.values():
            kiosk.wait_until_quiet(server)
        times = {name: [] for name in servers}
        phases = {name: [] for name in servers}
        loadavg = {name: [] for name in servers}
        before = {name: kiosk.memory_mb(server) for name, server in started.items()}
        for _ in range(loads):
            for name, server in started.items():
                for other in started.values():             # nobody's refill runs during a visit
                    kiosk.wait_until_quiet(other)
                loadavg[name].append(os.getloadavg()[0])
                if notebook is None:
                    visit = kiosk.visit(contexts[name], server)
                    times[name].append(visit.answered_ms)
                    phases[name].append({**visit.phases, "drawn_ms": visit.drawn_ms})
                else:
                    times[name].append(study_visit(contexts[name], server))
        for name, server in started.items():
            kiosk.wait_until_quiet(server)
            warm = sorted(times[name][1:]) or times[name]
            warm_phases = phases[name][1:] or phases[name]
            results[name] = {
                "before": before[name], "after": kiosk.memory_mb(server), "first_ms": times[name][0],
                "p50_ms": statistics.median(warm), "p95_ms": warm[round(0.95 * (len(warm) - 1))],
                "load": statistics.median(loadavg[name]),
                "phases": ({key: statistics.median(p[key] for p in warm_phases) for key in PHASES}
                           if warm_phases else None)}
    finally:
        for context in contexts.values():
            context.close()
        for server in started.values():
            server.stop()
    return results


def _print(page: str, loads: int, results: dict) -> None:
    stock = results["stock Voila"]
    w = max(24, *(len(name) + 1 for name in results))
    print(f"\n{page}, {loads} visits per server (each tab closed as a visitor closes it)")
    print(f"{'server':<{w}} {'memory after':>13} {'kernels':>8} {'first':>8} {'p50 warm':>9} {'p95 warm':>9}"
          f"  {'memory / stock':>14} {'p50 / stock':>11} {'load avg':>9}")
    for name, r in results.items():
        own, children, kernels = r["after"]
        total = own + children
        stock_total = sum(stock["after"][:2])
        print(f"{name:<{w}} {total:>10.0f} MB {kernels:>8d} {r['first_ms'] / 1000:>6.2f} s {r['p50_ms'] / 1000:>7.2f} s"
              f" {r['p95_ms'] / 1000:>7.2f} s  {total / stock_total:>13.2f}x {r['p50_ms'] / stock['p50_ms']:>10.2f}x"
              f" {r['load']:>9.1f}")
    if all(r.get("phases") for r in results.values()):
        print("\nwhere a warm visit's time went (medians, s from navigation; then what was fetched)")
        print(f"{'server':<{w}} {'HTML':>6} {'DOM':>6} {'load':>6} {'kernel':>7} {'canvas':>7} {'drawn':>6}"
              f" {'answered':>9} {'requests':>9} {'served':>7} {'wire MB':>8} {'body MB':>8}")
        for name, r in results.items():
            p = r["phases"]
            print(f"{name:<{w}} {p['html_ms'] / 1000:>6.2f} {p['dom_ms'] / 1000:>6.2f} {p['load_ms'] / 1000:>6.2f}"
                  f" {p['kernel_ms'] / 1000:>7.2f} {p['canvas_ms'] / 1000:>7.2f} {p['drawn_ms'] / 1000:>6.2f}"
                  f" {r['p50_ms'] / 1000:>9.2f} {p['requests']:>9.0f} {p['served']:>7.0f} {p['transfer_mb']:>8.2f}"
                  f" {p['body_mb']:>8.2f}")


def _server_option(text: str) -> tuple[str, dict]:
    name, sep, options = text.partition("=")
    if not sep or not name.strip() or not all(o.startswith("--") for o in options.split()):
        raise argparse.ArgumentTypeError(f"expected NAME=--Class.trait=value [...], got {text!r}")
    return name.strip(), dict(shipped_config=True, overrides=tuple(options.split()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loads", type=int, default=11, help="visits per server (default 11: 1 cold, 10 warm)")
    parser.add_argument("--no-study", action="store_true", help="skip the study page")
    parser.add_argument("--no-cache", action="store_true",
                        help="turn the browser's HTTP cache off (Playwright's interception)")
    parser.add_argument("--server", type=_server_option, action="append", default=[], metavar="NAME=OPTIONS",
                        help="also measure the shipped file with these Voila options on top (repeatable)")
    args = parser.parse_args()
    if args.loads < 2:
        parser.error(f"--loads: expected an integer >= 2 (one cold visit and warm ones), got {args.loads}")
    servers = {**SERVERS, **dict(args.server)}
    with sync_playwright() as playwright:
        shared = []

        def shared_browser():
            if not shared:
                shared.append(playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS))
            return shared[0]

        browsers = {"api": playwright, "shared": shared_browser}
        cache = not args.no_cache
        load_before = os.getloadavg()[0]
        demo = run(browsers, None, args.loads, servers, cache)
        study = None if args.no_study else run(browsers, STUDY, args.loads, servers, cache)
        for browser in shared:
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
