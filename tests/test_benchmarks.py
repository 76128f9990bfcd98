"""The benchmark scripts still run and print their figures (a smoke test: speed is reported by
the scripts, never asserted here; bench_core does fail on disagreement with MuJoCo, a
correctness check)."""

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

EXPECTED = {
    "bench_arms.py": ["a 10 s reproduction at 1 kHz", "panda-reach", "so101-reach", "a URDF loaded into a ready plant"],
    "bench_online.py": ["participants", "arrival p50/p95/max", "response p50/p95/max", "load average"],
    "bench_kiosk.py": ["demo page (notebooks/demo.ipynb)", "stock Voila", "shipped config", "memory after"],
    "bench_core.py": ["agreement with MuJoCo", "(a) one 10 s rollout", "(b) 1000 rollouts", "fit + optimal_actions"],
    "bench_study.py": ["in-silico study, 32 participants", "power by simulation"],
    "bench_uarm.py": ["P2220 round trip", "worst overhead per round trip"],
    "bench_so101.py": ["sync read round trip", "target 2 ms", "hand-teaching loop at rate=50",
                       "feedback after a demonstration by hand", "hand loop while teaching"],
    "bench_ur5.py": ["agreement of 10 s reproductions", "pinocchio ABA stepped from Python",
                     "MuJoCo stepped from Python", "feedback: fit + optimal actions"],
    "bench_widgets.py": ["feedback latency", "animation message", "Chromium playback", "pointer-to-arrow latency"],
    "bench_install.py": ["build sdist + wheel", "size MB", "import + first fit and optimal actions"],
    "bench_learners.py": ["MT against the target's and random actions", "machine teaching per learner",
                          "feedback latency per learner", "guidance per learner in silico",
                          "batched in-silico study per learner", "power by simulation, reward-sim"],
    "bench_kill_soak.py": ["SIGKILLs (before", "nothing lost, nothing duplicated"],
    "bench_lesson_kernel.py": ["a lesson's kernel, forked from the template", "the largest rise",
                               "one full collection", "PSS at the last episode"],
}
# Shorter runs where a full one takes minutes (the figures are reported, never asserted).
ARGS = {"bench_kiosk.py": ["--loads", "2", "--no-study"], "bench_online.py": ["--participants", "2", "--think", "1"],
        "bench_install.py": ["--shapes", "core"],
        "bench_so101.py": ["--demonstrations", "3"], "bench_learners.py": ["--quick"],
        "bench_kill_soak.py": ["--kills", "1", "--protocols", "paper-sim"],
        "bench_lesson_kernel.py": ["--episodes", "4"]}


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_benchmark_runs_and_prints_its_figures(script):
    command = [sys.executable, str(REPO / "benchmarks" / script), *ARGS.get(script, [])]
    result = subprocess.run(command, capture_output=True, text=True, cwd=REPO, timeout=900)
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-3000:]
    for line in EXPECTED[script]:
        assert line in result.stdout, f"{script} no longer prints {line!r}:\n{result.stdout[-2000:]}"
