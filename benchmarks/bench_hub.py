"""A class on one machine: how long students wait (server, first episode, feedback) and what each costs.

Starts deploy/jupyterhub/jupyterhub_config.py as root on loopback with a roster of N students
(system users ``mtt-bench-...``, removed at the end, as tests/course/test_hub.py does), and:

1. every student logs in through the login form at the same moment (first login: they set
   their password) and their servers are started at once: spawn time from the start request to
   the hub reporting the server ready, p50 / p95 / all;
2. in every student's fresh kernel, at once, one episode, imports included (what a student
   waits for the first time they press run);
3. at human pace: every student teaches three episodes, confirming an arrow every 3 to 8 s at
   random, so episodes end at random times: feedback latency p50 / p95
   (``EpisodeResult.feedback_latency_s``: from the last confirmed arrow to the reproduction
   sent: learning, a 10 s rollout at 1 kHz, the animation message);
4. all at once (the worst case): every student's three episodes with no pauses, together;
5. memory per student (server plus one kernel after its episodes): resident (RSS, as the
   issue measured it) and proportional (PSS: shared libraries split between the processes
   using them, which is what the machine pays).

Targets (issue 16, this 2-core machine, idle): thirty spawns within 30 s; first episode within
3 s; feedback p95 <= 150 ms at human pace; <= 200 MiB per student. The load average is printed
beside the figures: the machine may be shared.

    python benchmarks/bench_hub.py --students 30        # as root

Numba's cache is warmed once and copied to every student at spawn (as a deployment does).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

TARGETS = {"spawn_all_s": 30.0, "first_episode_s": 3.0, "feedback_p95_ms": 150.0, "memory_mib": 200.0}

FIRST_EPISODE = """
import time
started = time.perf_counter()
from mt_widgets import SKILLS
from mt_widgets.widgets import EpisodeWidget
episode = EpisodeWidget("sim-point", seed={number}, guidance=True)
for optimal in episode.optimal:
    episode.demonstrate(optimal)
    episode.next()
print("first-episode", time.perf_counter() - started, episode.result.feedback_latency_s)
"""


def percentile(values, q: float) -> float:
    ordered = sorted(values)
    index = (len(ordered) - 1) * q
    low = int(index)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (index - low)


def paced(code: str, number: int) -> str:
    """EPISODE_CODE with a human's pause of 3 to 8 s (random, per student) before each arrow."""
    return (f"import random as _random, time as _time\n_pause = _random.Random({number})\n"
            + code.replace("        episode.demonstrate(", "        _time.sleep(_pause.uniform(3, 8))\n"
                                                           "        episode.demonstrate("))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=30)
    parser.add_argument("--skip-human-pace", action="store_true", help="leave out step 3 (about a minute)")
    args = parser.parse_args()
    if args.students < 1:
        parser.error(f"--students: expected at least 1, got {args.students}")
    if os.geteuid() != 0:
        parser.error("the class hub makes a system user per student: run as root")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]
    from tests.course.hub_support import EPISODE_CODE, ClassHub, warm_numba_template

    students = [f"mtt-bench-{n:02d}" for n in range(args.students)]
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="mtt-bench-") as folder:
        template = warm_numba_template(Path(folder) / "numba-template")
        started = time.perf_counter()
        hub = ClassHub(students, numba_template=template)
        print(f"hub up in {time.perf_counter() - started:.1f} s")
        try:
            started = time.perf_counter()
            with ThreadPoolExecutor(len(students)) as pool:
                list(pool.map(lambda name: hub.login(name, f"{name} password"), students))
            login_wall = time.perf_counter() - started
            started = time.perf_counter()
            spawn = hub.spawn_class(students)
            spawn_wall = time.perf_counter() - started
            load_spawn = os.getloadavg()
            print(f"{len(students)} logged in at once in {login_wall:.1f} s; spawned at once in {spawn_wall:.1f} s")

            def run(item, code, keep=False):
                number, name = item
                result = hub.run_in_kernel(name, code.format(number=number % 12), timeout=900)
                if result["error"] or result["died"]:
                    raise SystemExit(f"{name}: {result}")
                if not keep:  # one kernel per student at a time, as the memory figure means
                    hub.server_api(name, "DELETE", f"/api/kernels/{result['kernel_id']}")
                return result

            with ThreadPoolExecutor(len(students)) as pool:
                firsts = list(pool.map(lambda item: run(item, FIRST_EPISODE), enumerate(students)))
            first_walls = [float(r["stdout"].split()[1]) for r in firsts]
            single = run((0, students[0]), FIRST_EPISODE)  # a fresh kernel of a student alone
            first_alone = float(single["stdout"].split()[1])

            human = []
            if not args.skip_human_pace:
                with ThreadPoolExecutor(len(students)) as pool:
                    list(pool.map(lambda item: run(item, paced(EPISODE_CODE, item[0])), enumerate(students)))
                human = [latency * 1000 for name in students
                         for latency in hub.read_json(name, "episode-result.json")["latencies_s"]]
                load_human = os.getloadavg()
            with ThreadPoolExecutor(len(students)) as pool:
                list(pool.map(lambda item: run(item, EPISODE_CODE, keep=True), enumerate(students)))
            at_once = [latency * 1000 for name in students
                       for latency in hub.read_json(name, "episode-result.json")["latencies_s"]]
            load_at_once = os.getloadavg()
            rss, pss = [], []
            for name in students:
                processes = hub.processes(name)
                rss.append(sum(p.memory_info().rss for p in processes) / 2**20)
                pss.append(sum(p.memory_full_info().pss for p in processes) / 2**20)
        finally:
            hub.stop()
            hub.kept_log.unlink()
    spawn_times = list(spawn.values())
    print(f"load average (1 min) before {load_before[0]:.1f}, after spawning {load_spawn[0]:.1f}"
          + (f", after the human-pace episodes {load_human[0]:.1f}" if human else "")
          + f", after all at once {load_at_once[0]:.1f}")
    print(f"spawn: p50 {percentile(spawn_times, 0.5):.1f} s, p95 {percentile(spawn_times, 0.95):.1f} s, "
          f"all ready {max(spawn_times):.1f} s (target {TARGETS['spawn_all_s']:.0f} s)")
    print(f"first episode in a fresh kernel, imports included: alone {first_alone:.2f} s; {len(students)} at once "
          f"p50 {percentile(first_walls, 0.5):.2f} s, p95 {percentile(first_walls, 0.95):.2f} s "
          f"(target {TARGETS['first_episode_s']:.0f} s)")
    if human:
        print(f"feedback latency at human pace (an arrow every 3-8 s): p50 {percentile(human, 0.5):.0f} ms, "
              f"p95 {percentile(human, 0.95):.0f} ms (target {TARGETS['feedback_p95_ms']:.0f} ms)")
    print(f"feedback latency all at once ({len(students)} students' episodes together): "
          f"p50 {percentile(at_once, 0.5):.0f} ms, p95 {percentile(at_once, 0.95):.0f} ms")
    print(f"memory per student (server + one kernel): RSS p50 {statistics.median(rss):.0f} MiB "
          f"(max {max(rss):.0f}), PSS p50 {statistics.median(pss):.0f} MiB (target {TARGETS['memory_mib']:.0f} MiB)")


if __name__ == "__main__":
    main()
