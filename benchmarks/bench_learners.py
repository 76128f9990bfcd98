"""The per-learner figures of the learners' closing note, in one run.

Run: ``.venv/bin/python benchmarks/bench_learners.py`` (needs the ``bench`` extra, as bench_core).
``--quick`` runs every part small (a smoke run; its figures mean little).

1. Machine teaching against the baselines: over 100 random query sets per skill (the skill's S
   states; 8 for the reward learner, as its study), the policy risk the target's own actions and
   random actions leave, divided by MT's (``compare_with_baselines``): median factors, and in how
   many sets MT beats both. The paper's four skills and the four nonlinear ones.
2. MT's time per learner against the issue's targets (exact kernel MT within 20 ms at 5 states,
   approximate MT's p95 within 1 s): ``bench_core.bench_learners``.
3. The episode widget's feedback latency per learner beside ridge's: ``bench_widgets.learner_latencies``.
4. How much guidance helps per learner in silico: the same synthetic teachers through paper-uarm
   with each learner (``mt_widgets.analysis.guidance_by_learner``): each group's change in percent of
   its baseline error, and Hedges' g of guided against unguided.
5. The batched in-silico engine per learner: one study of 1,000 synthetic participants through
   paper-uarm with each learner (reward-sim for the reward learner), teaching only (no rollouts),
   against the issue's 60 s for a linear smoother, ridge's figure beside; and power by simulation
   for reward-sim (1,000 studies of 2 x 16 against 10 minutes; ``--power-studies`` measures fewer
   and extrapolates linearly, and says so).

``--batched-only`` runs part 5 alone.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import numpy as np

from mt_widgets import SKILLS
from mt_widgets.core.learner_teaching import LEARNERS, compare_with_baselines, make_learner
from mt_widgets.core.nonlinear_skills import NONLINEAR_SKILLS


def baselines(n_sets: int) -> None:
    print(f"MT against the target's and random actions ({n_sets} random query sets per skill; factor = "
          f"baseline risk / MT's risk, median; 'beats' = sets where MT's risk is below both)")
    for key, skill in {**SKILLS, **NONLINEAR_SKILLS}.items():
        for name in LEARNERS:
            if name == "reward" and skill.plant.robot != "uarm":
                continue   # the reward learner is defined on the uArm's kinematic plane
            started = time.perf_counter()
            result = compare_with_baselines(make_learner(name, skill), skill, n_sets=n_sets,
                                            n_states=8 if name == "reward" else None)
            tiny = np.finfo(float).tiny
            target = np.median(result.target / np.maximum(result.mt, tiny))
            random = np.median(result.random / np.maximum(result.mt, tiny))
            beats = int(np.sum((result.mt <= result.target) & (result.mt < result.random)))
            print(f"  {key:<14} {name:<17} MT risk median {np.median(result.mt):9.3g}; target x{target:9.3g}, "
                  f"random x{random:9.3g}; beats both in {beats}/{n_sets} ({time.perf_counter() - started:.1f} s)")


def latencies(repeats: int) -> None:
    from bench_widgets import learner_latencies

    print(f"\nepisode widget feedback latency per learner, uarm-point ({repeats} episodes each; last "
          f"demonstration -> reproduction sent)")
    figures = learner_latencies(repeats)
    for name, values in figures.items():
        print(f"  {name:<17} median {statistics.median(values):7.1f} ms, max {max(values):7.1f} ms")


def guidance(n_participants: int) -> None:
    from mt_widgets.analysis import guidance_by_learner

    print(f"\nguidance per learner in silico (paper-uarm, {n_participants} synthetic teachers per learner, the same "
          f"for each; change in % of the phase's baseline error; g: guided against unguided, negative = helps)")
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        table = guidance_by_learner(folder, n_participants=n_participants)
    for row in table.itertuples():
        print(f"  {row.learner:<17} {row.label:<11} guided {row.target_percent_change:+7.1f} %, unguided "
              f"{row.control_percent_change:+7.1f} %, g {row.hedges_g:+7.2f}, p {row.p:.3g}")
    print(f"  ({time.perf_counter() - started:.1f} s)")


def batched(n_participants: int, power_studies: int) -> None:
    from mt_widgets.analysis import protocol_with_learner
    from mt_widgets.analysis.power import simulated_power
    from mt_widgets.core.learner import is_linear_smoother
    from mt_widgets.in_silico.engine import run_in_silico
    from mt_widgets.in_silico.plan import episode_plan, resolve_protocol

    print(f"\nbatched in-silico study per learner ({n_participants} participants, teaching only, no rollouts; "
          f"target 60 s for a linear smoother)")
    run_in_silico(2, protocol="paper-uarm", reproduce=False, progress=False)   # warm-up: compiled kernels
    for name in LEARNERS:
        protocol = resolve_protocol("reward-sim") if name == "reward" else \
            protocol_with_learner(resolve_protocol("paper-uarm"), name)
        skill = protocol.skill(episode_plan(protocol)[0]["skill"])
        smoother = is_linear_smoother(make_learner(name, skill))
        started = time.perf_counter()
        run_in_silico(n_participants, protocol=protocol, reproduce=False, progress=False)
        seconds = time.perf_counter() - started
        verdict = f"; ratio to 60 s {seconds / 60:.2f}" if smoother else ""
        kind = "linear smoother" if smoother else "batched fit"
        print(f"  {protocol.name:<30} {name:<17} {kind:<16} {seconds:7.2f} s{verdict}")
    started = time.perf_counter()
    simulated_power(n_per_group=16, n_studies=power_studies, seed=0, progress=False, protocol="reward-sim")
    seconds = time.perf_counter() - started
    note = "" if power_studies == 1000 else f" (measured with {power_studies} studies, extrapolated linearly)"
    per_1000 = seconds * 1000 / power_studies
    print(f"power by simulation, reward-sim, {power_studies} studies of 2 x 16: {seconds:.1f} s; 1,000 studies: "
          f"{per_1000:.0f} s{note}; target 600 s, ratio {per_1000 / 600:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="every part small (a smoke run)")
    parser.add_argument("--batched-only", action="store_true", help="only the batched in-silico engine (part 5)")
    parser.add_argument("--power-studies", type=int, default=1000, help="reward-sim power: simulated studies")
    args = parser.parse_args()
    print(f"cores available: {os.cpu_count()}; load average {os.getloadavg()[0]:.1f}")
    if args.batched_only:
        batched(20 if args.quick else 1000, 4 if args.quick else args.power_studies)
        return
    baselines(2 if args.quick else 100)
    from bench_core import bench_learners

    bench_learners(3 if args.quick else 40)
    latencies(1 if args.quick else 10)
    guidance(4 if args.quick else 16)
    batched(20 if args.quick else 1000, 4 if args.quick else args.power_studies)


if __name__ == "__main__":
    main()
