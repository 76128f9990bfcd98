"""A lesson's kernel over many episodes: is its memory flat once the closed views are collected?

A kernel forked from the kernel template (``mt_widgets/kernels/template.py``), as the class hub's
and the study pages' kernels are, runs episodes of ``sim-point`` with guidance in four cells, in
turn and then again, each run sent with its cell's id as JupyterLab sends it: a cell run again
retires the episode it made (``mt_widgets/widgets/cells.py``). No page is open here, so a retired
view closes at the kernel's own fallback, set to 2 s (a page's receipt comes about that soon).

Side by side, in two kernels of one template:

- **shipped**: each close is followed by one full collection and a heap trim
  (``animation._collect_soon``);
- **reference**: Python's own collector alone (``_collect_soon`` switched off in that kernel), as
  before 2026-12-05. In a kernel forked from a frozen template its full collections came about
  every thirty episodes.

Prints the kernel's PSS every four episodes, the growth from episode 8 to the last (the first
episodes warm the kernel up) against issue 46's target (flat within 10 %), and what one full
collection costs in the kernel.

    python benchmarks/bench_lesson_kernel.py                  # 60 episodes each
    python benchmarks/bench_lesson_kernel.py --episodes 8     # a smoke run
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mt_widgets.kernels import ForkingKernelManager  # noqa: E402
from mt_widgets.kernels.provisioner import KernelTemplate  # noqa: E402

CELLS = 4
SETUP = """
import mt_widgets.widgets.animation as _animation
_animation.CLOSE_FALLBACK_S = 2.0  # no page answers receipts here: close about when one would
if {reference}:
    _animation._collect_soon = lambda loop: None  # Python's own collector alone
"""
EPISODE = """
import time as _time
from mt_widgets.widgets import EpisodeWidget
episode = EpisodeWidget("sim-point", seed={seed}, guidance=True)
for _optimal in episode.optimal:
    _time.sleep({pause})
    episode.demonstrate(_optimal + 0.05)
    episode.next()
"""
PROBE = """
import gc as _gc, json as _json, time as _t
from ipywidgets.widgets.widget import _instances as _open
_started = _t.perf_counter(); _gc.collect(); _took = _t.perf_counter() - _started
print(_json.dumps({{"open": len(_open), "collection_ms": 1000 * _took, "frozen": _gc.get_freeze_count()}}))
"""


async def run(client, code: str, cell: str) -> str:
    """Runs ``code`` as cell ``cell`` (its id sent as JupyterLab sends it); what it printed."""
    message = client.session.msg("execute_request", {"code": code, "silent": False, "store_history": True,
                                                     "user_expressions": {}, "allow_stdin": False,
                                                     "stop_on_error": True}, metadata={"cellId": cell})
    client.shell_channel.send(message)
    printed = []
    while True:
        reply = await client.get_iopub_msg(timeout=300)
        if reply["parent_header"].get("msg_id") != message["header"]["msg_id"]:
            continue
        if reply["msg_type"] == "stream":
            printed.append(reply["content"]["text"])
        elif reply["msg_type"] == "error":
            raise RuntimeError("\n".join(reply["content"]["traceback"]))
        elif reply["msg_type"] == "status" and reply["content"]["execution_state"] == "idle":
            return "".join(printed)


async def lesson(reference: bool, episodes: int, pause: float) -> tuple[list[tuple[int, float]], dict]:
    manager = ForkingKernelManager(kernel_name="python3")
    await manager.start_kernel()
    client = manager.client()
    client.start_channels()
    try:
        await client.wait_for_ready(timeout=120)
        if not manager.provisioner.forked:
            raise SystemExit("the kernel was not forked from the template (its log says why)")
        kernel = psutil.Process(manager.provisioner.pid)
        await run(client, SETUP.format(reference=reference), "setup")
        series = []
        for number in range(1, episodes + 1):
            await run(client, EPISODE.format(seed=number, pause=pause), f"cell-{number % CELLS}")
            if number % 4 == 0 or number == episodes:
                await asyncio.sleep(3.0)  # the fallback close of the last retired view
                series.append((number, kernel.memory_full_info().pss / 2**20))
        probe = json.loads((await run(client, PROBE.format(), "probe")).strip().splitlines()[-1])
        return series, probe
    finally:
        client.stop_channels()
        await manager.shutdown_kernel(now=True)


def growth(series: list[tuple[int, float]]) -> tuple[float, float]:
    """(PSS at the sample nearest episode 8, the largest rise after it in percent)."""
    start = min(series, key=lambda sample: abs(sample[0] - 8))
    later = [pss for number, pss in series if number >= start[0]]
    return start[1], 100 * (max(later) - start[1]) / start[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=60)
    parser.add_argument("--pause", type=float, default=0.1, help="seconds before each arrow")
    args = parser.parse_args()
    if args.episodes < 4:
        parser.error(f"--episodes: expected at least 4, got {args.episodes}")
    # A runtime folder of its own: the template's socket lives there.
    runtime = tempfile.mkdtemp(prefix="mt-bench-lesson-")
    os.environ["JUPYTER_RUNTIME_DIR"] = runtime
    try:
        compare(args)
    finally:
        template = KernelTemplate._shared
        if template is not None:
            template.stop()
        shutil.rmtree(runtime, ignore_errors=True)


def compare(args) -> None:
    print(f"a lesson's kernel, forked from the template: {args.episodes} episodes of sim-point in {CELLS} "
          f"cells run again with cell ids, {args.pause:g} s before each arrow", flush=True)
    results = {}
    for name, reference in (("shipped", False), ("reference", True)):
        started = time.perf_counter()
        series, probe = asyncio.run(lesson(reference, args.episodes, args.pause))
        results[name] = series
        start, rise = growth(series)
        print(f"{name:9s} PSS MiB by episode: " + ", ".join(f"{n}: {pss:.1f}" for n, pss in series), flush=True)
        print(f"{name:9s} from episode 8 ({start:.1f} MiB) the largest rise: {rise:+.1f} % (target: within 10 %); "
              f"{probe['open']} widgets open at the end; one full collection {probe['collection_ms']:.1f} ms "
              f"({probe['frozen']} objects frozen in the template); {time.perf_counter() - started:.0f} s",
              flush=True)
    shipped, reference = results["shipped"][-1][1], results["reference"][-1][1]
    print(f"PSS at the last episode: shipped {shipped:.1f} MiB, reference {reference:.1f} MiB "
          f"(ratio {shipped / reference:.2f})")


if __name__ == "__main__":
    main()
