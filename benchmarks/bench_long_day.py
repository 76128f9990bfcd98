"""A long day on the class hub: a class at human pace for hours of teaching, without a restart.

Starts deploy/jupyterhub/jupyterhub_config.py as root on loopback (tests/course/hub_support.py) with
a class of N students (system users ``mtt-day-...``, removed at the end), starts every server, and
lets each student teach as a person does, until the simulated day is over:

- a **lesson** lasts 30 simulated minutes: at its start the student opens a new notebook (a new
  kernel; the last lesson's kernel is shut down, as closing a notebook with "shut down kernel" does);
- in a lesson, the student runs **an episode** (a cell: one teaching episode of ``sim-point`` with
  guidance, each arrow given after 3 to 8 s, its progress recorded in the class folder), then
  reads for 20 to 90 s, then the next episode; the lesson's notebook has ``CELLS_PER_LESSON`` such
  cells, run in turn and then again, each run sent with its cell's id as JupyterLab sends it;
- every 5 simulated minutes the machine is sampled: each student's PSS (server, kernel template,
  kernels), the processes and open file descriptors of the whole class (the hub, its proxy, the
  server template, every student's processes), the hub's own resident memory.

``--compression K`` scales a person's pace: every pause is divided by K, so ``--minutes 120
--compression 8`` is two hours of teaching in 15 minutes of wall time (each student's work per
simulated minute is the same; the machine does it K times as often). The figures, and the day's
verdict against issue 46's targets:

- memory per student flat within 10 % after the first ten simulated minutes (each sample's median
  against the sample at minute 10, and the largest single student's change; and the samples at the
  same minute of every lesson against the first lesson's: until 2026-12-05 a lesson's kernel kept
  every episode run in it open, about 1.4 MiB each);
- no growth of processes or file descriptors (the last sample against the one at minute 10);
- no error in any log: the hub's log (hub, proxy, every server) has no error line and no traceback,
  and no execution failed.

    python benchmarks/bench_long_day.py --students 60 --minutes 120 --compression 8   # as root

The load average is printed: on a shared machine a compressed day's feedback is slower than a real one.
"""

from __future__ import annotations

import argparse
import os
import random
import re
import statistics
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]
LESSON_MIN = 30.0
#: Episode cells in a lesson's notebook: the student runs them in turn, then each again (JupyterLab
#: sends each run with its cell's id, so a cell run again retires its last episode: cells.py).
CELLS_PER_LESSON = 4
SAMPLE_EVERY_MIN = 5.0

#: One episode, a cell the student runs: each arrow after a person's pause (scaled), progress recorded.
EPISODE = """
import random as _random, time as _time
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.classroom import ProgressRecorder
_pause = _random.Random({seed})
try:
    _recorder
except NameError:
    _recorder = ProgressRecorder()
episode = EpisodeWidget("sim-point", seed={seed}, guidance=True)
_recorder.attach(episode, "long-day")
for _optimal in episode.optimal:
    _time.sleep(_pause.uniform(3, 8) / {compression})
    episode.demonstrate(_optimal + 0.05)
    episode.next()
print("latency", episode.result.feedback_latency_s)
"""

#: A line of the hub's log that is an error: Jupyter's and JupyterHub's "[E ...", a traceback,
#: the proxy's "error:" (its own 404s for a route being re-added are logged as errors too).
ERROR_LINE = re.compile(r"^\[E |Traceback \(most recent call last\)|\berror\b.*: (?!404 )", re.IGNORECASE)


def _class_processes(hub, students) -> list[psutil.Process]:
    """The hub, its proxy, services and server template, and every student's process."""
    hub_process = psutil.Process(hub.process.pid)
    found = {hub_process.pid: hub_process}
    for child in hub_process.children(recursive=True):
        found[child.pid] = child
    for name in students:
        for process in hub.processes(name):
            found[process.pid] = process
    return list(found.values())


def sample(hub, students, simulated_min: float) -> dict:
    pss = []
    for name in students:
        total = 0
        for process in hub.processes(name):
            try:
                total += process.memory_full_info().pss
            except (psutil.NoSuchProcess, psutil.ZombieProcess):
                continue
        pss.append(total / 2**20)
    processes = _class_processes(hub, students)
    fds, zombies = 0, 0
    for process in processes:
        try:
            fds += process.num_fds()
            zombies += process.status() == psutil.STATUS_ZOMBIE
        except (psutil.NoSuchProcess, psutil.ZombieProcess):
            continue
    return {"minute": simulated_min, "pss": pss, "processes": len(processes), "fds": fds, "zombies": zombies,
            "hub_rss": psutil.Process(hub.process.pid).memory_info().rss / 2**20, "load": os.getloadavg()[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=60)
    parser.add_argument("--minutes", type=float, default=120.0, help="simulated minutes of teaching (120: two hours)")
    parser.add_argument("--compression", type=float, default=1.0,
                        help="a person's pace scaled: every pause divided by this (8: two hours in 15 minutes)")
    args = parser.parse_args()
    if args.students < 1:
        parser.error(f"--students: expected at least 1, got {args.students}")
    if args.minutes < 2 * SAMPLE_EVERY_MIN + 10:
        parser.error(f"--minutes: expected at least {2 * SAMPLE_EVERY_MIN + 10:.0f} (samples after minute 10), "
                     f"got {args.minutes}")
    if args.compression < 1:
        parser.error(f"--compression: expected at least 1 (1: a person's own pace), got {args.compression}")
    if os.geteuid() != 0:
        parser.error("the class hub makes a system user per student: run as root")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]
    from tests.course.hub_support import ClassHub, remove_leftovers, warm_numba_template

    try:
        if remove_leftovers():
            print("removed the accounts a killed earlier run left", flush=True)
    except RuntimeError as error:  # another test hub runs: its accounts are not leftovers
        print(f"({error})", flush=True)
    students = [f"mtt-day-{n:02d}" for n in range(args.students)]
    wall_s = args.minutes * 60 / args.compression
    print(f"{args.students} students, {args.minutes:.0f} simulated minutes at compression {args.compression:g}: "
          f"{wall_s / 60:.1f} minutes of wall time", flush=True)
    with tempfile.TemporaryDirectory(prefix="mtt-bench-day-") as folder:
        template = warm_numba_template(Path(folder) / "numba-template")
        hub = ClassHub(students, numba_template=template, env={"MT_HUB_CULL_IDLE_SECONDS": "0"})
        try:
            hub.create_users(students)
            hub.spawn_class(students)
            log_start = hub.log.stat().st_size  # the day's log: after every server is up
            start = time.monotonic()
            errors, latencies, episodes, lessons = [], [], [0], [0]
            lock = threading.Lock()

            def simulated_min() -> float:
                return (time.monotonic() - start) * args.compression / 60

            def student(item) -> None:
                number, name = item
                pace = random.Random(number)
                # The class does not start in lockstep: a few seconds (scaled) apart.
                time.sleep(pace.uniform(0, 30) / args.compression)
                kernel, lesson, run = None, -1, 0
                while simulated_min() < args.minutes:
                    if int(simulated_min() // LESSON_MIN) != lesson:
                        lesson = int(simulated_min() // LESSON_MIN)
                        if kernel is not None:
                            hub.server_api(name, "DELETE", f"/api/kernels/{kernel}")
                        kernel, run = None, 0
                        with lock:
                            lessons[0] += 1
                    try:
                        # A lesson's notebook has CELLS_PER_LESSON episode cells, run in turn and then again.
                        result = hub.run_in_kernel(name, EPISODE.format(seed=pace.randrange(10**6),
                                                                        compression=args.compression),
                                                   timeout=600, kernel_id=kernel,
                                                   cell=f"lesson-{lesson}-episode-{run % CELLS_PER_LESSON}")
                        run += 1
                    except Exception as error:  # counted: a lost kernel is an error of the day
                        with lock:
                            errors.append(f"{name}: {type(error).__name__}: {error}")
                        kernel = None
                        continue
                    kernel = result["kernel_id"]
                    with lock:
                        episodes[0] += 1
                        if result["error"] or result["died"]:
                            errors.append(f"{name}: {result}")
                        else:
                            latencies.append(float(result["stdout"].split()[-1]))
                    time.sleep(pace.uniform(20, 90) / args.compression)

            samples = []
            done = threading.Event()

            def sampler() -> None:
                next_min = 0.0
                while not done.is_set():
                    if simulated_min() >= next_min:
                        samples.append(sample(hub, students, simulated_min()))
                        print(f"  minute {samples[-1]['minute']:5.1f}: PSS per student p50 "
                              f"{statistics.median(samples[-1]['pss']):.0f} MiB, {samples[-1]['processes']} "
                              f"processes, {samples[-1]['fds']} fds, hub {samples[-1]['hub_rss']:.0f} MiB, "
                              f"{episodes[0]} episodes, load {samples[-1]['load']:.1f}", flush=True)
                        next_min += SAMPLE_EVERY_MIN
                    done.wait(0.5)

            watcher = threading.Thread(target=sampler)
            watcher.start()
            with ThreadPoolExecutor(len(students)) as pool:
                list(pool.map(student, enumerate(students)))
            done.set()
            watcher.join()
            samples.append(sample(hub, students, simulated_min()))
            wall = time.monotonic() - start
            with open(hub.log, errors="replace") as log:
                log.seek(log_start)
                day_log = log.read().splitlines()
        finally:
            hub.stop()
            hub.kept_log.unlink()
    log_errors = [line for line in day_log if ERROR_LINE.search(line)]
    reference = next(s for s in samples if s["minute"] >= 10)
    later = [s for s in samples if s["minute"] >= reference["minute"]]
    median_changes = [statistics.median(s["pss"]) / statistics.median(reference["pss"]) - 1 for s in later]
    student_changes = [after / before - 1 for s in later for before, after in zip(reference["pss"], s["pss"])]
    median_change = max(abs(change) for change in median_changes)
    student_change = max(abs(change) for change in student_changes)
    # A lesson's kernel grows with every episode run in it (each cell run makes new widgets, and a
    # notebook keeps the old ones until they are closed); a new lesson starts a new kernel. So the
    # day's growth is read at the same point of every lesson as well: each sample at minute 10 of a
    # lesson (within half a sample's spacing) against the first lesson's.
    same_point = [s for s in later if abs((s["minute"] - reference["minute"]) % LESSON_MIN) < SAMPLE_EVERY_MIN / 2
                  or abs((s["minute"] - reference["minute"]) % LESSON_MIN - LESSON_MIN) < SAMPLE_EVERY_MIN / 2]
    lesson_change = max(abs(statistics.median(s["pss"]) / statistics.median(reference["pss"]) - 1)
                        for s in same_point)
    last = samples[-1]
    print(f"\nthe day: {args.students} students, {args.minutes:.0f} simulated minutes at compression "
          f"{args.compression:g} in {wall / 60:.1f} minutes of wall time; {lessons[0]} lessons begun (a new kernel "
          f"each), {episodes[0]} episodes; load average (1 min) p50 "
          f"{statistics.median(s['load'] for s in samples):.1f}, max {max(s['load'] for s in samples):.1f} "
          f"({os.cpu_count()} cores)")
    if latencies:
        print(f"feedback latency p50 {statistics.median(latencies) * 1000:.0f} ms, "
              f"max {max(latencies) * 1000:.0f} ms")
    print(f"memory per student (PSS) p50 at minute {reference['minute']:.0f}: "
          f"{statistics.median(reference['pss']):.0f} MiB; the class's median after it changed by at most "
          f"{median_change * 100:.1f} % ({max(median_changes) * 100:+.1f} % up, {min(median_changes) * 100:+.1f} % "
          f"down), one student's by at most {student_change * 100:.1f} % ({max(student_changes) * 100:+.1f} % up, "
          f"{min(student_changes) * 100:+.1f} % down: a new lesson's kernel starts smaller) (target 10 %); at "
          f"minute {reference['minute'] % LESSON_MIN:.0f} of every lesson ("
          + ", ".join(f"{s['minute']:.0f}: {statistics.median(s['pss']):.0f} MiB" for s in same_point)
          + f") by at most {lesson_change * 100:.1f} %")
    print(f"processes {reference['processes']} at minute {reference['minute']:.0f}, {last['processes']} at the "
          f"end (max {max(s['processes'] for s in later)}); file descriptors {reference['fds']} -> {last['fds']} "
          f"(max {max(s['fds'] for s in later)}); zombies at most {max(s['zombies'] for s in samples)}; the hub "
          f"{reference['hub_rss']:.0f} -> {last['hub_rss']:.0f} MiB")
    print(f"errors: {len(errors)} executions failed, {len(log_errors)} error lines in the hub's log")
    for line in (errors + log_errors)[:10]:
        print("   ", line[:300])


if __name__ == "__main__":
    main()
