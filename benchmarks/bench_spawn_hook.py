"""The hub's event loop while a class spawns: is it ever blocked by the warm cache's copy?

JupyterHub awaits each spawn's ``pre_spawn_hook`` on its one event loop, which serves every other
login, page and API call meanwhile. The class hub's hook (deploy/jupyterhub/jupyterhub_config.py)
copies the warm numba cache into the student's home in a thread; until issue 46 it copied on the loop.
This starts the class hub as root on loopback (tests/course/hub_support.py) with N students, spawns
every server at once, and measures, during the spawns:

- **the loop's lag, inside the hub**: a task on the hub's loop asks to wake every 5 ms and records how
  late it woke (the longest any callback, the copy included, held the loop); max and p99;
- **a ping from outside**: ``GET /hub/api/`` straight to the hub (not through the proxy) every 50 ms,
  its response time; max and p99 (what any other student's page waits on top of its own work).

Each N is run twice: the hook as shipped (``thread``), and as a reference the same copy made on the
loop before the hook runs (``loop``: what the hook did before; the shipped hook then finds the cache in
place and copies nothing). Both load the class hub's own config through a small wrapper config that
adds the lag monitor (and, for ``loop``, the on-loop copy); nothing else differs.

    python benchmarks/bench_spawn_hook.py --students 30 60     # as root; about 5 minutes

The load average is printed beside the figures: on a shared machine the lag includes other work's.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import requests

ROOT = Path(__file__).resolve().parents[1]

#: Loaded by the hub instead of the class hub's config: that config, a lag monitor on the hub's loop,
#: and, with MT_BENCH_COPY=loop, the cache's copy made on the loop (the reference).
WRAPPER = '''
import asyncio, os, pwd, shutil, time
from pathlib import Path

c = get_config()  # noqa: F821
load_subconfig({config!r})  # noqa: F821
_hook = c.Spawner.pre_spawn_hook
_LAGS = Path(os.environ["MT_BENCH_LAGS"])
_monitor = []


async def _watch_the_loop():
    """Every 5 ms, how late the loop woke this task; one line per second: its wall time, the lags."""
    loop = asyncio.get_running_loop()
    pending, flushed = [], time.monotonic()
    while True:
        asked = loop.time()
        await asyncio.sleep(0.005)
        pending.append(loop.time() - asked - 0.005)
        if time.monotonic() - flushed >= 1.0:
            with open(_LAGS, "a") as lags:
                lags.write(f"{{time.time()}} " + " ".join(f"{{lag:.5f}}" for lag in pending) + "\\n")
            pending, flushed = [], time.monotonic()


async def _bench_hook(spawner):
    if not _monitor:
        _monitor.append(asyncio.get_running_loop().create_task(_watch_the_loop()))
    template = os.environ.get("MT_HUB_NUMBA_TEMPLATE")
    if os.environ.get("MT_BENCH_COPY") == "loop" and template:
        # The reference: the copy as the hook made it before issue 46, on the loop.
        user = pwd.getpwnam(spawner.user.name)
        cache = Path(os.environ["MT_HUB_HOMES"], spawner.user.name, ".cache", "numba")
        if not cache.exists():
            cache.parent.mkdir(exist_ok=True)
            os.chown(cache.parent, user.pw_uid, user.pw_gid)
            shutil.copytree(template, cache)
            for path in [cache, *cache.rglob("*")]:
                os.chown(path, user.pw_uid, user.pw_gid)
    await _hook(spawner)


c.Spawner.pre_spawn_hook = _bench_hook
'''


def percentile(values, q: float) -> float:
    ordered = sorted(values)
    index = (len(ordered) - 1) * q
    low = int(index)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (index - low)


def _ping(url: str, stop: threading.Event, times: list) -> None:
    """GET ``url`` every 50 ms until ``stop``; (wall time, response seconds) each."""
    session = requests.Session()
    while not stop.is_set():
        asked = time.perf_counter()
        try:
            session.get(url, timeout=30)
            times.append((time.time(), time.perf_counter() - asked))
        except requests.RequestException:
            times.append((time.time(), float("inf")))
        stop.wait(0.05)


def run(students: int, copy: str, template: Path, folder: Path) -> dict:
    from tests.course.hub_support import CONFIG, ClassHub

    names = [f"mtt-hook-{n:02d}" for n in range(students)]
    config = folder / f"bench_config_{copy}.py"
    config.write_text(WRAPPER.format(config=str(CONFIG)))
    lags_file = folder / f"lags-{copy}-{students}.txt"
    hub = ClassHub(names, numba_template=template, config=config,
                   env={"MT_BENCH_LAGS": str(lags_file), "MT_BENCH_COPY": copy, "MT_HUB_CULL_IDLE_SECONDS": "0"})
    try:
        hub.create_users(names)
        stop, pings = threading.Event(), []
        pinger = threading.Thread(target=_ping, args=(f"http://127.0.0.1:{hub.hub_port}/hub/api/", stop, pings))
        pinger.start()
        time.sleep(1.0)  # a second of the idle loop first
        began, load_before = time.time(), os.getloadavg()[0]
        spawn = hub.spawn_class(names)
        ended, load_after = time.time(), os.getloadavg()[0]
        time.sleep(1.5)  # the monitor's last second reaches its file
        stop.set()
        pinger.join()
        for name in names[:1]:  # the copy was made, whole, and is the student's
            cache = hub.homes / name / ".cache" / "numba"
            if not any(cache.iterdir()) or cache.stat().st_uid != os.stat(hub.homes / name).st_uid:
                raise SystemExit(f"{name}'s warm cache was not copied as theirs")
    finally:
        hub.stop()
        hub.kept_log.unlink()
    lags = []
    for line in lags_file.read_text().splitlines():
        stamp, *values = line.split()
        # a line holds the second before its stamp: keep the seconds that overlap the spawns
        if began - 1.0 <= float(stamp) <= ended + 1.0:
            lags.extend(float(value) for value in values)
    window = [seconds for stamp, seconds in pings if began <= stamp <= ended]
    return {"students": students, "copy": copy, "spawn_all_s": max(spawn.values()),
            "lag_max_ms": max(lags) * 1000, "lag_p99_ms": percentile(lags, 0.99) * 1000,
            "lag_samples": len(lags), "ping_max_ms": max(window) * 1000,
            "ping_p99_ms": percentile(window, 0.99) * 1000, "ping_p50_ms": statistics.median(window) * 1000,
            "pings": len(window), "load": (load_before, load_after)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, nargs="+", default=[30, 60])
    parser.add_argument("--copy", choices=("thread", "loop"), nargs="+", default=["thread", "loop"],
                        help="thread: the shipped hook; loop: the reference, the copy made on the loop")
    args = parser.parse_args()
    if any(n < 1 for n in args.students):
        parser.error(f"--students: expected counts of at least 1, got {args.students}")
    if os.geteuid() != 0:
        parser.error("the class hub makes a system user per student: run as root")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]
    from tests.course.hub_support import remove_leftovers, warm_numba_template

    if remove_leftovers():
        print("removed the accounts a killed earlier run left", flush=True)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mtt-bench-hook-") as folder:
        template = warm_numba_template(Path(folder) / "numba-template")
        size = sum(p.stat().st_size for p in template.rglob("*") if p.is_file())
        files = sum(1 for p in template.rglob("*") if p.is_file())
        print(f"warm cache: {files} files, {size / 2**20:.1f} MiB", flush=True)
        results = []
        for students in args.students:
            for copy in args.copy:
                result = run(students, copy, template, Path(folder))
                results.append(result)
                print(f"{students} spawns at once, copy {'in a thread' if copy == 'thread' else 'on the loop'}: "
                      f"all ready {result['spawn_all_s']:.1f} s; the loop's lag max {result['lag_max_ms']:.0f} ms, "
                      f"p99 {result['lag_p99_ms']:.0f} ms ({result['lag_samples']} samples); GET /hub/api/ "
                      f"p50 {result['ping_p50_ms']:.0f} ms, p99 {result['ping_p99_ms']:.0f} ms, max "
                      f"{result['ping_max_ms']:.0f} ms ({result['pings']} pings); load average "
                      f"{result['load'][0]:.1f} -> {result['load'][1]:.1f} ({os.cpu_count()} cores)", flush=True)
    print(f"benchmark took {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
