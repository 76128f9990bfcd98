"""A class on one machine: how long students wait (server, first episode, feedback) and what each costs.

Starts deploy/jupyterhub/jupyterhub_config.py as root on loopback with a roster of N students
(system users ``mtt-bench-...``, removed at the end, as tests/course/test_hub.py does), and:

1. a lecture's first minute: every student logs in through the login form at the same moment
   (first login: they set their password), their servers are started at once, and each student
   runs a first teaching episode in a fresh kernel as soon as their own server is ready: spawn
   time from the start request to the hub reporting the server ready (p50, all), the first
   episode from asking the server for the kernel to its end, after the student's own server was
   ready (p50, p95, worst), the CPU time a server and a kernel took (which load does not
   inflate: a class needs at least their sum over the cores), and the CPU seconds of every part
   of the machine during that minute (this benchmark's own client, which reads every student's
   websocket as their browser would, the hub and proxy, servers, kernels, the server template,
   anything else);
2. first episode in a fresh kernel, imports included: one student alone, then (the worst case)
   every student at the same moment once all are ready. Two figures each: inside the kernel
   (from the cell's first import to the reproduction sent) and from asking the server for the
   kernel (kernel start included);
3. at human pace, in that same kernel: every student teaches three episodes, confirming an
   arrow every 3 to 8 s at random, so episodes end at random times: feedback latency p50 / p95
   (``EpisodeResult.feedback_latency_s``: from the last confirmed arrow to the reproduction
   sent: learning, a 10 s rollout at 1 kHz, the animation message);
4. all at once (the worst case): every student's three episodes with no pauses, together;
5. memory per student, server (with its kernel template) plus their one kernel after its
   episodes: resident (RSS), proportional (PSS: pages shared with other processes, such as a
   shared library's code or the server template's imports, divided between them: what the
   machine pays per student in a class) and unique (USS: pages of that student's alone), the
   server and the kernel apart, then with the server template's PSS shared out among the class;
6. students per core at that pace: the CPU time every student's server and kernel used during
   step 3 (``psutil``'s user + system time, which a loaded machine does not inflate as it does
   wall time), plus a student's share of the hub's and the proxy's, over the phase's wall time,
   is the fraction of a core one student keeps busy; a core holds its inverse.

Targets (issue 33, this 2-core machine, idle): thirty servers all ready within 20 s and each
first episode within 5 s of the student's server being ready at p95; sixty all ready within 45 s
with at most 150 MiB PSS per student; feedback p95 <= 150 ms at human pace (issue 16). The load
average is printed beside the figures: the machine may be shared. About three minutes for thirty
students.

    python benchmarks/bench_hub.py --students 30        # as root
    python benchmarks/bench_hub.py --students 60 --skip-human-pace
    python benchmarks/bench_hub.py --students 100 --lecture-hall   # issue 46: a lecture's start only

``--lecture-hall`` runs step 1 alone on a hub whose capacity (``MT_HUB_SERVER_LIMIT``) is the class,
counting lost spawns instead of stopping at the first: every spawn kept, all ready and every first
episode done from the start (target 30 s), PSS per student (target 100 MiB), and the page the next
student, one beyond the capacity, gets.

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

import psutil

ROOT = Path(__file__).resolve().parents[1]

TARGETS = {"spawn_all_s": 20.0, "first_episode_s": 5.0, "feedback_p95_ms": 150.0, "memory_mib": 150.0}
#: Issue 33's figures (landed main before kernels were forked from a template, idle machine, 30 students).
BEFORE = "30 students before forked kernels (issue 33, idle): all ready 33.2 s (p50 29.8 s), first episode worst " \
         "20.3 s after ready, 175 MiB PSS per student"

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


def _cpu_seconds(processes) -> float:
    total = 0.0
    for process in processes:
        try:
            times = process.cpu_times()
            total += times.user + times.system
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
    return total


def _hub_processes(hub) -> list:
    """The hub and its proxy: the processes under the hub that run as the hub's user, except the
    server template. (Every student's server and kernel is under the hub too, forked by the
    template or started by the spawner; until 2026-12-04 they were counted here as well, so the
    hub's share at human pace held the students' own CPU a second time.)"""
    hub_process = psutil.Process(hub.process.pid)
    own = [hub_process]
    for process in hub_process.children(recursive=True):
        try:
            if (process.uids().real == hub_process.uids().real
                    and "mt_widgets.kernels.server_template" not in " ".join(process.cmdline())):
                own.append(process)
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
    return own


def _is_kernel(process) -> bool:
    # ipykernel's launcher, or the students' (deploy/jupyterhub/student-site/mt_hub_kernel.py),
    # or a kernel forked from a server's template (mt_widgets/kernels/): a template's child. The
    # template itself counts with the server (what a student's server costs beside its kernels).
    try:
        if any(part in ("ipykernel_launcher", "mt_hub_kernel") for part in process.cmdline()):
            return True
        parent = process.parent()
        return parent is not None and any(name in " ".join(parent.cmdline()) for name in (
            "mt_widgets.kernels.template", "mt-widgets kernel template"))
    except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
        return False


def _cpu_by_part(hub, students) -> dict[str, float]:
    """CPU seconds so far of every process on the machine, by part: this benchmark's own client
    (it reads every student's websocket as their browser would, on the same two cores), the hub
    and its proxy, students' servers (with their kernel templates), students' kernels, the
    server template, and everything else (other work on the machine)."""
    import pwd

    uids = {pwd.getpwnam(name).pw_uid for name in students}
    hub_tree = {p.pid for p in _hub_processes(hub)}
    parts = dict.fromkeys(("benchmark client", "hub and proxy", "servers", "kernels", "server template", "other"), 0.0)
    for process in psutil.process_iter(["uids", "cmdline"]):
        try:
            times = process.cpu_times()
            cpu = times.user + times.system
            if process.pid == os.getpid():
                part = "benchmark client"
            elif process.info["uids"] and process.info["uids"].real in uids:
                part = "kernels" if _is_kernel(process) else "servers"
            elif "mt_widgets.kernels.server_template" in " ".join(process.info["cmdline"] or ()):
                part = "server template"
            elif process.pid in hub_tree:
                part = "hub and proxy"
            else:
                part = "other"
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
        parts[part] += cpu
    return parts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--students", type=int, default=30)
    parser.add_argument("--skip-human-pace", action="store_true", help="leave out steps 3 and 6 (about 90 s)")
    parser.add_argument("--lecture-hall", action="store_true",
                        help="only a lecture's start, the class server's capacity being the class: every spawn "
                             "kept, ready and first episode done from the start, PSS, the next student's page")
    args = parser.parse_args()
    if args.students < 1:
        parser.error(f"--students: expected at least 1, got {args.students}")
    if os.geteuid() != 0:
        parser.error("the class hub makes a system user per student: run as root")
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT)]
    if args.lecture_hall:
        lecture_hall(args.students)
        return
    from tests.course.hub_support import EPISODE_CODE, ClassHub, remove_leftovers, warm_numba_template

    if remove_leftovers():  # an earlier run that was killed left its accounts
        print("removed the accounts a killed earlier run left", flush=True)

    bench_started = time.perf_counter()
    students = [f"mtt-bench-{n:02d}" for n in range(args.students)]
    load_before = os.getloadavg()
    kernels = {}
    with tempfile.TemporaryDirectory(prefix="mtt-bench-") as folder:
        template = warm_numba_template(Path(folder) / "numba-template")
        started = time.perf_counter()
        hub = ClassHub(students, numba_template=template)
        print(f"hub up in {time.perf_counter() - started:.1f} s", flush=True)
        try:
            started = time.perf_counter()
            with ThreadPoolExecutor(len(students)) as pool:
                list(pool.map(lambda name: hub.login(name, f"{name} password"), students))
            login_wall = time.perf_counter() - started

            def run(item, code, fresh=False):
                number, name = item
                result = hub.run_in_kernel(name, code.format(number=number % 12), timeout=900,
                                           kernel_id=None if fresh else kernels.get(name))
                if result["error"] or result["died"]:
                    raise SystemExit(f"{name}: {result}")
                if not fresh:
                    kernels[name] = result["kernel_id"]  # each student goes on in their one kernel
                return result

            def lecture_start(item):
                # A student's first minute: their server is started with everyone else's, and they run
                # their first episode as soon as their own server is ready.
                ready_s = hub.spawn(item[1])
                return ready_s, run(item, FIRST_EPISODE)

            cpu_before, started = _cpu_by_part(hub, students), time.perf_counter()
            with ThreadPoolExecutor(len(students)) as pool:
                lecture = dict(zip(students, pool.map(lecture_start, enumerate(students))))
            lecture_wall = time.perf_counter() - started
            lecture_cpu = {part: seconds - cpu_before.get(part, 0.0)
                           for part, seconds in _cpu_by_part(hub, students).items()}
            spawn = {name: ready_s for name, (ready_s, _) in lecture.items()}
            lecture_firsts = [result["total_s"] for _, result in lecture.values()]
            load_spawn = os.getloadavg()
            # CPU of a server's start (the server and its kernel template, whole life so far, which
            # load does not inflate as it does wall time) and of a kernel's start and first episode.
            spawn_cpu = [_cpu_seconds([p for p in hub.processes(name) if not _is_kernel(p)]) for name in students]
            first_cpu = [_cpu_seconds([p for p in hub.processes(name) if _is_kernel(p)]) for name in students]
            print(f"{len(students)} logged in at once in {login_wall:.1f} s; spawned at once, each running their "
                  f"first episode once ready, in {lecture_wall:.1f} s", flush=True)

            alone = hub.run_in_kernel(students[0], FIRST_EPISODE.format(number=0), timeout=900)
            if alone["error"] or alone["died"]:
                raise SystemExit(f"{students[0]} alone: {alone}")
            hub.server_api(students[0], "DELETE", f"/api/kernels/{alone['kernel_id']}")
            first_alone, first_alone_total = float(alone["stdout"].split()[1]), alone["total_s"]
            # The worst case: every student asks for a fresh kernel at the same moment, once all are ready.
            cpu_before, firsts_started = _cpu_by_part(hub, students), time.perf_counter()
            with ThreadPoolExecutor(len(students)) as pool:
                firsts = list(pool.map(lambda item: run(item, FIRST_EPISODE, fresh=True), enumerate(students)))
            firsts_wall = time.perf_counter() - firsts_started
            firsts_cpu = {part: seconds - cpu_before.get(part, 0.0)
                          for part, seconds in _cpu_by_part(hub, students).items()}
            for name, result in zip(students, firsts):
                hub.server_api(name, "DELETE", f"/api/kernels/{result['kernel_id']}")
            first_walls = [float(r["stdout"].split()[1]) for r in firsts]
            first_totals = [r["total_s"] for r in firsts]
            print("first episodes done", flush=True)

            human, per_core = [], None
            if not args.skip_human_pace:
                members = {name: hub.processes(name) for name in students}
                hub_processes = _hub_processes(hub)
                cpu_before = {name: _cpu_seconds(processes) for name, processes in members.items()}
                hub_cpu_before = _cpu_seconds(hub_processes)
                started = time.perf_counter()
                with ThreadPoolExecutor(len(students)) as pool:
                    list(pool.map(lambda item: run(item, paced(EPISODE_CODE, item[0])), enumerate(students)))
                human_wall = time.perf_counter() - started
                student_cpu = [_cpu_seconds(members[name]) - cpu_before[name] for name in students]
                hub_cpu = _cpu_seconds(hub_processes) - hub_cpu_before
                human = [latency * 1000 for name in students
                         for latency in hub.read_json(name, "episode-result.json")["latencies_s"]]
                load_human = os.getloadavg()
                # One student keeps this fraction of a core busy at human pace; a core holds its inverse.
                core_share = (statistics.mean(student_cpu) + hub_cpu / len(students)) / human_wall
                per_core = 1 / core_share
                print("human pace done", flush=True)
            with ThreadPoolExecutor(len(students)) as pool:
                list(pool.map(lambda item: run(item, EPISODE_CODE), enumerate(students)))
            at_once = [latency * 1000 for name in students
                       for latency in hub.read_json(name, "episode-result.json")["latencies_s"]]
            load_at_once = os.getloadavg()
            memory = {"server": {"rss": [], "pss": [], "uss": []}, "kernel": {"rss": [], "pss": [], "uss": []}}
            totals = {"rss": [], "pss": [], "uss": []}
            for name in students:
                processes = hub.processes(name)
                kinds = [p for p in processes if _is_kernel(p)], [p for p in processes if not _is_kernel(p)]
                # One kernel; the server, with its kernel template (mt_widgets/kernels/) when it has one.
                if len(kinds[0]) != 1 or not 1 <= len(kinds[1]) <= 2:
                    raise SystemExit(f"{name}: expected a server (and its template) and one kernel, found {processes}")
                for kind, group in zip(("kernel", "server"), kinds):
                    infos = [process.memory_full_info() for process in group]
                    for measure in ("rss", "pss", "uss"):
                        memory[kind][measure].append(sum(getattr(info, measure) for info in infos) / 2**20)
                for measure in totals:
                    totals[measure].append(memory["server"][measure][-1] + memory["kernel"][measure][-1])
            # The server template (root's, no student's): its PSS is what the class pays for it.
            template_pss = sum(p.memory_full_info().pss for p in psutil.process_iter(["cmdline"])
                               if "mt_widgets.kernels.server_template" in " ".join(p.info["cmdline"] or ())) / 2**20
        finally:
            hub.stop()
            hub.kept_log.unlink()
    spawn_times = list(spawn.values())
    print(f"\nas in a lecture's first minute ({len(students)} servers started at once, each student running "
          f"their first episode, in a fresh kernel, as soon as their own server is ready): all ready "
          f"{max(spawn_times):.1f} s (p50 {percentile(spawn_times, 0.5):.1f} s; target 20 s); first episode done after "
          f"the student's own server was ready p50 {percentile(lecture_firsts, 0.5):.2f} s, p95 "
          f"{percentile(lecture_firsts, 0.95):.2f} s, worst {max(lecture_firsts):.2f} s (target p95 5 s); "
          f"the whole in {lecture_wall:.1f} s; CPU seconds by part: "
          + ", ".join(f"{part} {seconds:.1f}" for part, seconds in lecture_cpu.items()))
    print(f"\n{len(students)} students; load average (1 min) before {load_before[0]:.1f}, after spawning "
          f"{load_spawn[0]:.1f}" + (f", after the human-pace episodes {load_human[0]:.1f}" if human else "")
          + f", after all at once {load_at_once[0]:.1f} ({os.cpu_count()} cores)")
    print(f"spawn: p50 {percentile(spawn_times, 0.5):.1f} s, p95 {percentile(spawn_times, 0.95):.1f} s, "
          f"all ready {max(spawn_times):.1f} s (target {TARGETS['spawn_all_s']:.0f} s); CPU per server start "
          f"p50 {statistics.median(spawn_cpu):.2f} s, so {len(students)} need at least "
          f"{sum(spawn_cpu) / os.cpu_count():.0f} s of all {os.cpu_count()} cores")
    print(f"first episode in a fresh kernel, imports included (target {TARGETS['first_episode_s']:.0f} s): "
          f"alone {first_alone:.2f} s in the kernel, {first_alone_total:.2f} s with its start; "
          f"{len(students)} at once p50 {percentile(first_walls, 0.5):.2f} s / "
          f"p95 {percentile(first_walls, 0.95):.2f} s in the kernel, p50 {percentile(first_totals, 0.5):.2f} s / "
          f"p95 {percentile(first_totals, 0.95):.2f} s / worst {max(first_totals):.2f} s with its start (after the "
          f"servers were ready); CPU per kernel start and first episode "
          f"p50 {statistics.median(first_cpu):.2f} s")
    print(f"CPU seconds during the {len(students)} first episodes ({firsts_wall:.1f} s, at most "
          f"{firsts_wall * os.cpu_count():.0f} CPU-s): " + ", ".join(f"{part} {seconds:.1f}"
                                                                    for part, seconds in firsts_cpu.items()))
    if human:
        print(f"feedback latency at human pace (an arrow every 3-8 s): p50 {percentile(human, 0.5):.0f} ms, "
              f"p95 {percentile(human, 0.95):.0f} ms (target {TARGETS['feedback_p95_ms']:.0f} ms)")
    print(f"feedback latency all at once ({len(students)} students' episodes together): "
          f"p50 {percentile(at_once, 0.5):.0f} ms, p95 {percentile(at_once, 0.95):.0f} ms")
    print(f"memory per student, server + one kernel (target {TARGETS['memory_mib']:.0f} MiB), p50: "
          + "; ".join(f"{measure.upper()} {statistics.median(totals[measure]):.0f} MiB (server "
                      f"{statistics.median(memory['server'][measure]):.0f} + kernel "
                      f"{statistics.median(memory['kernel'][measure]):.0f})" for measure in ("rss", "pss", "uss")))
    print(f"the server template: {template_pss:.0f} MiB PSS, {template_pss / len(students):.1f} MiB per student; "
          f"PSS per student with it: {statistics.median(totals['pss']) + template_pss / len(students):.0f} MiB")
    if human:
        print(f"CPU at human pace: {statistics.mean(student_cpu):.1f} s per student (server + kernel) and "
              f"{hub_cpu:.1f} s for the hub and proxy over {human_wall:.0f} s: students per core at that pace "
              f"{per_core:.0f} (= {human_wall:.0f} s / ({statistics.mean(student_cpu):.2f} s + "
              f"{hub_cpu:.2f} s / {len(students)}))")
    print(BEFORE)
    print(f"benchmark took {time.perf_counter() - bench_started:.0f} s")


def _pss_per_student(hub, students) -> tuple[float, float]:
    """The median PSS (MiB) of a student's server, kernel template and kernels, and the server
    template's PSS shared out among the class."""
    per_student = [sum(p.memory_full_info().pss for p in hub.processes(name)) / 2**20 for name in students]
    template_pss = sum(p.memory_full_info().pss for p in psutil.process_iter(["cmdline"])
                       if "mt_widgets.kernels.server_template" in " ".join(p.info["cmdline"] or ())) / 2**20
    return statistics.median(per_student), template_pss / len(students)


def lecture_hall(count: int) -> None:
    """Issue 46's lecture hall: ``count`` students log in and start at once on a hub whose capacity
    (``MT_HUB_SERVER_LIMIT``) is the class; each runs a first episode as soon as their server is
    ready. Every spawn must be kept (none lost, no retry); the figure is the time from the start to
    the last student's first episode done (target 30 s). Then the PSS per student (target 100 MiB)
    and what the next student, one beyond the capacity, sees."""
    import requests

    from tests.course.hub_support import ClassHub, remove_leftovers, warm_numba_template

    if remove_leftovers():
        print("removed the accounts a killed earlier run left", flush=True)
    students = [f"mtt-bench-{n:03d}" for n in range(count)]
    beyond = f"mtt-bench-{count:03d}"
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="mtt-bench-") as folder:
        template = warm_numba_template(Path(folder) / "numba-template")
        hub = ClassHub([*students, beyond], numba_template=template,
                       env={"MT_HUB_SERVER_LIMIT": str(count), "MT_HUB_CULL_IDLE_SECONDS": "0"})
        try:
            with ThreadPoolExecutor(count) as pool:
                list(pool.map(lambda name: hub.login(name, f"{name} password"), students))
            cpu_before = _cpu_by_part(hub, students)
            start = time.perf_counter()

            def lecture_start(item):
                number, name = item
                try:
                    ready = hub.spawn(name)
                    ready_at = time.perf_counter() - start
                    result = hub.run_in_kernel(name, FIRST_EPISODE.format(number=number % 12), timeout=900)
                    if result["error"] or result["died"]:
                        return {"error": f"first episode: {result}"}
                    return {"ready_s": ready, "ready_at_s": ready_at, "done_at_s": time.perf_counter() - start}
                except Exception as error:  # a lost spawn is counted, not retried
                    return {"error": f"{type(error).__name__}: {str(error)[:300]}"}

            with ThreadPoolExecutor(count) as pool:
                outcomes = dict(zip(students, pool.map(lecture_start, enumerate(students))))
            load_after = os.getloadavg()
            cpu = {part: seconds - cpu_before.get(part, 0.0) for part, seconds in _cpu_by_part(hub, students).items()}
            lost = {name: outcome["error"] for name, outcome in outcomes.items() if "error" in outcome}
            kept = [outcome for outcome in outcomes.values() if "error" not in outcome]
            pss, template_share = _pss_per_student(hub, [n for n in students if n not in lost])
            browser = hub.login(beyond, f"{beyond} password")
            page = browser.get(f"{hub.url}/hub/spawn", timeout=120)
            heading = page.text.split('id="mt-hub-refusal"', 1)[-1].split(">", 1)[-1].split("<", 1)[0].strip()
            beyond_processes = len(hub.processes(beyond))
        except requests.RequestException as error:
            raise SystemExit(f"the hub stopped answering: {error}\n{hub.tail()}") from error
        finally:
            hub.stop()
            hub.kept_log.unlink()
    ready = [outcome["ready_at_s"] for outcome in kept]
    done = [outcome["done_at_s"] for outcome in kept]
    print(f"\nlecture hall: {count} students started at once ({os.cpu_count()} cores; load average (1 min) "
          f"{load_before[0]:.1f} before, {load_after[0]:.1f} after)")
    print(f"spawns kept {len(kept)} of {count}" + (f"; lost: {list(lost.items())[:3]}" if lost else ""))
    if kept:
        print(f"from the start: all ready {max(ready):.1f} s (p50 {percentile(ready, 0.5):.1f} s); every first "
              f"episode done {max(done):.1f} s (p50 {percentile(done, 0.5):.1f} s, p95 {percentile(done, 0.95):.1f} s;"
              f" target 30 s)")
        print(f"PSS per student (server, kernel template, kernel) p50 {pss:.0f} MiB, with the server template's "
              f"share {pss + template_share:.0f} MiB (target 100 MiB)")
    print("CPU seconds during the start, by part: "
          + ", ".join(f"{part} {seconds:.1f}" for part, seconds in cpu.items()))
    print(f"student {count + 1}: HTTP {page.status_code}, page heading {heading!r}, {beyond_processes} processes")


if __name__ == "__main__":
    main()
