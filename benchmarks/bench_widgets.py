"""Widget speed: kernel feedback latency, animation message size, Chromium playback and pointer latency.

Run: ``python benchmarks/bench_widgets.py`` (add ``--no-browser`` for the kernel part only).
Targets (issue 3): median feedback latency <= 50 ms; one animation message of 10 s at 60 fps
<= 150 KB; playback >= 55 fps in Chromium; pointer-to-arrow latency reported.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import ipycanvas
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def kernel_figures(repeats: int = 15) -> dict:
    """Latency from the last demonstration to the animation sent, and the message's bytes."""
    from mt_widgets.widgets import EpisodeWidget
    manager = ipycanvas.canvas._CANVAS_MANAGER
    sent = []
    original = manager._send_custom
    manager._send_custom = lambda command, buffers=(): sent.append((command, list(buffers)))
    try:
        import json
        latencies, sizes = [], []
        for repeat in range(repeats + 1):
            episode = EpisodeWidget("sim-point", seed=repeat, guidance=False, duration=10.0)
            for action in episode.optimal[:-1]:
                episode.demonstrate(1.2 * action)
            sent.clear()
            started = time.perf_counter()
            episode.demonstrate(1.2 * episode.optimal[-1])       # the last one triggers learning + animation
            elapsed = time.perf_counter() - started
            command, buffers = max(sent, key=lambda m: len(json.dumps(m[0])))
            size = len(json.dumps(command).encode()) + sum(memoryview(b).nbytes for b in buffers)
            if repeat:                                            # the first run compiles the rollout
                latencies.append(elapsed)
                sizes.append(size)
        return {"latency_ms": [1000 * v for v in latencies], "bytes": sizes}
    finally:
        manager._send_custom = original


def browser_figures() -> dict:
    """Playback fps (requestAnimationFrame) and pointer-to-arrow latency in Chromium via Voila."""
    sys.path.insert(0, str(ROOT))
    from playwright.sync_api import sync_playwright

    from tests.browser.conftest import CHROMIUM, CHROMIUM_ARGS, Server, _copy_pages, _free_port
    from tests.browser.helpers import ee_pixel, reference_episode, to_page, wait_for_color, OKABE

    root = Path(tempfile.mkdtemp(prefix="bench-widgets-"))
    _copy_pages(root)
    port = _free_port()
    server = Server([str(Path(sys.executable).parent / "voila"), str(root / "notebooks"), "--no-browser",
                     f"--port={port}", "--Voila.ip=127.0.0.1"], port, root, "voila", f"http://127.0.0.1:{port}")
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 1100})
            page.route("**/*", lambda r: r.continue_() if r.request.url.startswith(
                ("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:")) else r.abort())
            page.goto(server.url("/voila/render/episode_sim.ipynb"), timeout=60_000)
            reference = reference_episode()
            ee = ee_pixel(reference)
            wait_for_color(page, 0, *ee, OKABE["yellow"], timeout=60_000)

            # Pointer-to-arrow: time from the browser's mousemove to the rubber band's pixels.
            page.evaluate("""() => { const c = document.querySelectorAll('canvas')[0];
                window._moves = []; c.addEventListener('mousemove', () => window._moves.push(performance.now())); }""")
            start = to_page(page, 0, *ee)
            page.locator("canvas").first.scroll_into_view_if_needed()
            page.mouse.move(*start)
            page.mouse.down()
            latencies = []
            for k in range(1, 16):
                tip = ee + np.array([6.0 * k + 30, -40.0 - 2.0 * k])
                probe = tip + 4 * (ee - tip) / np.hypot(*(ee - tip))
                # Poll every animation frame until the canvas differs from what it showed before.
                page.evaluate("""() => { window._seen = null; const c = document.querySelectorAll('canvas')[0];
                    const ctx = c.getContext('2d');
                    const hash = () => { const d = ctx.getImageData(0, 0, c.width, c.height).data;
                        let h = 0; for (let i = 0; i < d.length; i += 16) { h = (h * 31 + d[i]) | 0; } return h; };
                    const before = hash();
                    const poll = () => { if (hash() !== before) { window._seen = performance.now(); }
                                         else { requestAnimationFrame(poll); } };
                    requestAnimationFrame(poll); }""")
                page.mouse.move(*to_page(page, 0, *tip))
                page.wait_for_function("() => window._seen !== null", timeout=5000)
                latencies.append(page.evaluate("() => window._seen - window._moves[window._moves.length - 1]"))
            page.mouse.up()

            # Playback: count the frames whose pixels changed, sampled every animation frame.
            for action in reference.optimal:
                reference.demonstrate(action)
                reference.next()
            final = reference.player.view.transform.to_pixel(reference.result.trajectory.positions[-1])
            page.evaluate("""() => { const c = document.querySelectorAll('canvas')[1]; const ctx = c.getContext('2d');
                window._changes = []; let last = null;
                const tick = (t) => { const d = ctx.getImageData(0, 0, c.width, c.height).data;
                    let h = 0; for (let i = 0; i < d.length; i += 64) { h = (h * 31 + d[i]) | 0; }
                    if (last !== null && h !== last) window._changes.push(t); last = h;
                    if (window._changes.length < 100000) requestAnimationFrame(tick); };
                requestAnimationFrame(tick); }""")
            page.get_by_role("button", name="test: finish with optimal").click()
            wait_for_color(page, 1, *final, OKABE["yellow"], timeout=30_000)
            changes = page.evaluate("() => window._changes")
            browser.close()
    finally:
        server.stop()
    # Playback spans from the first to the last changed frame; the steady part is what counts.
    span_s = (changes[-1] - changes[0]) / 1000.0 if len(changes) > 1 else float("nan")
    return {"pointer_ms": latencies, "frames": len(changes), "playback_s": span_s,
            "fps": (len(changes) - 1) / span_s if span_s > 0 else float("nan")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-browser", action="store_true", help="skip the Chromium measurements")
    args = parser.parse_args()
    kernel = kernel_figures()
    print(f"feedback latency (last demonstration -> animation sent; fit, optimal actions, 10 s reproduction, "
          f"encoding): median {statistics.median(kernel['latency_ms']):.1f} ms, "
          f"max {max(kernel['latency_ms']):.1f} ms over {len(kernel['latency_ms'])} episodes (target <= 50 ms)")
    print(f"animation message, 10 s at 60 fps: {max(kernel['bytes']) / 1000:.1f} KB (target <= 150 KB)")
    if args.no_browser:
        return
    browser = browser_figures()
    print(f"Chromium playback: {browser['fps']:.1f} fps ({browser['frames']} changed frames in "
          f"{browser['playback_s']:.2f} s of a 2 s reproduction; target >= 55)")
    print(f"pointer-to-arrow latency while dragging: median {statistics.median(browser['pointer_ms']):.0f} ms, "
          f"max {max(browser['pointer_ms']):.0f} ms over {len(browser['pointer_ms'])} moves")


if __name__ == "__main__":
    main()
