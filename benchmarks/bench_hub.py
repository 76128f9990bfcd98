"""A class on one machine: how long students wait for their servers, for feedback, and what each costs.

Starts deploy/jupyterhub/jupyterhub_config.py on loopback (as tests/course/test_hub.py does),
spawns N students at once, then runs three teaching episodes in every student's kernel, all
students at the same time, and prints:

- spawn time p50 / p95 (from the start request to the hub reporting the server ready);
- feedback latency p50 / p95 under that load (``EpisodeResult.feedback_latency_s``: from the
  last confirmed arrow to the reproduction sent: learning, a 10 s rollout at 1 kHz, the
  animation message), and the whole episode's wall time in the kernel;
- resident memory per student (server plus one kernel), p50 and max.

    python benchmarks/bench_hub.py --students 12

Numba's cache is warmed once and copied to every student at spawn (as a deployment does),
so the figures are for a class whose install step ran, not for a first-ever compile.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def percentile(values, q: float) -> float:
    ordered = sorted(values)
    index = (len(ordered) - 1) * q
    low = int(index)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (index - low)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=12)
    args = parser.parse_args()
    if args.students < 1:
        parser.error(f"--students: expected at least 1, got {args.students}")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]
    from tests.course.hub_support import EPISODE_CODE, ClassHub, warm_numba_template

    students = [f"student{n:02d}" for n in range(args.students)]
    with tempfile.TemporaryDirectory(prefix="bench-hub-") as folder:
        root = Path(folder)
        template = warm_numba_template(root / "numba-template")
        started = time.perf_counter()
        hub = ClassHub(root / "hub", numba_template=template)
        print(f"hub up in {time.perf_counter() - started:.1f} s")
        try:
            hub.create_users(students)
            started = time.perf_counter()
            spawn = hub.spawn_class(students)
            print(f"{len(students)} students spawned at once in {time.perf_counter() - started:.1f} s")
            with ThreadPoolExecutor(len(students)) as pool:
                runs = list(pool.map(lambda item: hub.run_in_kernel(item[1], EPISODE_CODE.format(number=item[0] % 12)),
                                     enumerate(students)))
            failed = [run["error"] for run in runs if run["error"]]
            if failed:
                raise SystemExit(f"episodes failed: {failed[:3]}")
            results = [hub.read_json(name, "episode-result.json") for name in students]
            latencies = [latency * 1000 for r in results for latency in r["latencies_s"]]
            walls = [run["seconds"] for run in runs]
            memory = [hub.memory(name) / 2**20 for name in students]
        finally:
            hub.stop()
    spawn_times = list(spawn.values())
    print(f"spawn time: p50 {percentile(spawn_times, 0.5):.1f} s, p95 {percentile(spawn_times, 0.95):.1f} s")
    print(f"feedback latency under load ({len(students)} students' episodes at once): "
          f"p50 {percentile(latencies, 0.5):.0f} ms, p95 {percentile(latencies, 0.95):.0f} ms")
    print(f"three episodes in a fresh kernel (imports included): p50 {percentile(walls, 0.5):.1f} s, "
          f"p95 {percentile(walls, 0.95):.1f} s")
    print(f"memory per student (server + one kernel): p50 {statistics.median(memory):.0f} MiB, "
          f"max {max(memory):.0f} MiB")


if __name__ == "__main__":
    main()
