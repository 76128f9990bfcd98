"""Benchmark of the arms on the one chain engine (robots as data): reproductions and URDF loading.

Run: ``.venv/bin/python benchmarks/bench_arms.py`` (no extra needed).

1. A 10 s reproduction at 1 kHz (10,000 controlled steps, ``skill.reproduce``, the public path) of
   each shipped 3-D arm's skills: the seven-joint Panda (target 50 ms), the UR5 (before the engine
   took robots as data: 35 ms, docs/guide/industrial-arm.md), the kinematic SO-101. The best of
   five after a warm-up, and the CPU time of the best run (the machine is shared).
2. Loading a URDF into a ready plant, warm numba cache (target 1 s): in a fresh process after
   ``import mt_widgets``, ``read_urdf`` of the shipped Panda file, its ``SerialChain`` and
   ``ChainPlant``, and a first 1 ms rollout (which loads the compiled engine from the cache).
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from mt_widgets import SKILLS

ROOT = Path(__file__).resolve().parents[1]
TARGETS = {"panda": 0.050, "ur5": 0.035}

LOAD = """
import time
start = time.perf_counter()
import mt_widgets
from mt_widgets.core.chain_plant import ChainPlant
from mt_widgets.core.features import ToolFeatures
from mt_widgets.core.serial_chain import SerialChain
from mt_widgets.arms.shipped import PANDA_HOME, PANDA_SCENE, PANDA_TEACHING_BOX
from mt_widgets.robot_models.urdf import read_urdf, shipped_urdf
import numpy as np
imported = time.perf_counter()
imported_cpu = time.process_time()
description = read_urdf(shipped_urdf("panda"), "panda_hand_tcp", ("panda_finger_joint1", "panda_finger_joint2"))
parsed = time.perf_counter()
plant = ChainPlant(SerialChain.from_description(description), PANDA_HOME, PANDA_TEACHING_BOX, PANDA_SCENE,
                   robot="mine", null_gain=2.0)
start_state = np.concatenate([plant.home, np.zeros(7)])
plant.rollout(np.zeros((1, 3, 4)), ToolFeatures(plant), start_state, 0.001)
ready = time.perf_counter()
print(imported - start, parsed - imported, ready - imported, time.process_time() - imported_cpu)
"""


def reproduction_times(key: str, repeat: int = 5) -> tuple[float, float]:
    """(best wall time, its CPU time) of a 10 s reproduction of the skill's own Theta."""
    skill = SKILLS[key]
    theta = skill.theta
    skill.reproduce(theta)   # warm-up (compiles or loads the kernels)
    best = (np.inf, np.inf)
    for _ in range(repeat):
        wall, cpu = time.perf_counter(), time.process_time()
        trajectory = skill.reproduce(theta)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        assert len(trajectory.times) == 10_001
        best = min(best, (wall, cpu))
    return best


def main() -> None:
    print("1. a 10 s reproduction at 1 kHz (10,000 controlled steps), best of 5")
    for key in ("panda-reach", "panda-conveyor", "ur5-reach", "ur5-conveyor", "so101-reach", "so101-place"):
        wall, cpu = reproduction_times(key)
        robot = SKILLS[key].robot
        target = TARGETS.get(robot)
        verdict = f" (target {1000 * target:.0f} ms: {'met' if wall <= target else 'missed'})" if target else ""
        joints = SKILLS[key].plant.n_joints
        kind = "kinematic" if SKILLS[key].plant.kinematic else "dynamic"
        print(f"   {key:15s} {joints} joints, {kind:9s}: {1000 * wall:6.1f} ms wall, {1000 * cpu:6.1f} ms CPU{verdict}")
    print("2. a URDF loaded into a ready plant (warm cache, fresh process; target 1 s)")
    subprocess.run([sys.executable, "-c", LOAD], check=True, cwd=ROOT, capture_output=True)   # warm the cache
    runs = []
    for _ in range(3):
        out = subprocess.run([sys.executable, "-c", LOAD], check=True, cwd=ROOT, capture_output=True, text=True)
        runs.append([float(v) for v in out.stdout.split()])
    imported, parsed, ready, ready_cpu = np.median(np.array(runs), axis=0)
    print(f"   import mt_widgets {imported:.2f} s; then read_urdf {1000 * parsed:.1f} ms, "
          f"URDF -> ready plant (parse + chain + plant + engine from cache) {ready:.2f} s wall, {ready_cpu:.2f} s CPU "
          f"({'met' if ready <= 1.0 else 'missed'}), median of 3")


if __name__ == "__main__":
    main()
