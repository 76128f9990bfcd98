"""Benchmark of the UR5 (issue 31): agreement and speed beside pinocchio and MuJoCo, in one run.

Run: ``.venv/bin/python benchmarks/bench_ur5.py`` (needs the ``bench`` extra: mujoco, pin,
example-robot-data).

1. Agreement: a 10 s reproduction of each ``ur5-`` skill (its Theta perturbed, so the arm keeps
   moving) against (a) pinocchio's ABA stepped from Python with the same controller and RK4 hold
   scheme (mt_widgets/robot_models/pinocchio_reference.py), and (b) MuJoCo loading the same URDF
   (meshes stripped), RK4 at 1 ms with ``qfrc_applied`` set each step to the torque of the same
   controller computed from MuJoCo's own Jacobian, mass matrix and gravity. The largest
   difference of any state component must stay under 1e-9 (the script fails otherwise).
2. Speed: one 10 s reproduction at 1 kHz through the public path (``skill.reproduce``), target
   50 ms, beside the same 10,000 controlled steps with pinocchio's ABA from Python, with MuJoCo
   from Python, and MuJoCo's own ``mj_step(m, d, nstep=10_000)`` under a constant torque (the
   dynamics alone, no controller: a floor no Python-driven loop reaches).
3. Feedback latency of an episode's science: fit + optimal actions + the 10 s reproduction.
"""

from __future__ import annotations

import os
import re
import statistics
import sys
import time

import numpy as np

from mt_widgets import SKILLS, RidgeLearner, TeachingEpisode, optimal_actions

try:
    import mujoco
    import pinocchio

    from mt_widgets.robot_models.pinocchio_reference import PinocchioUR5
    from mt_widgets.robot_models.urdf import example_robot_data_urdf
except ImportError as error:  # the bench extra is missing: say how to get it, do not pretend
    raise SystemExit("benchmarks/bench_ur5.py needs mujoco, pin and example-robot-data: "
                     "pip install -e '.[bench]'") from error

KEYS = ("ur5-reach", "ur5-place", "ur5-conveyor")
TOLERANCE = 1e-9


def mujoco_model() -> mujoco.MjModel:
    """The UR5 from the same URDF, its meshes stripped (MuJoCo cannot resolve package:// paths)."""
    text = example_robot_data_urdf("ur5").read_text(encoding="utf-8")
    text = re.sub(r"<visual>.*?</visual>|<collision>.*?</collision>", "", text, flags=re.S)
    text = re.sub(r"(<robot [^>]*>)", r'\1<mujoco><compiler discardvisual="true" balanceinertia="false"/></mujoco>',
                  text, count=1)
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep = 0.001
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    return model


class MujocoUR5:
    """MuJoCo stepping the UR5 under the plant's tool-velocity controller, computed from MuJoCo's quantities."""

    def __init__(self, plant):
        self.plant = plant
        self.model = mujoco_model()
        self.data = mujoco.MjData(self.model)
        self.still = mujoco.MjData(self.model)   # the same pose at rest: its bias is g(q)
        self.wrist = self.model.nbody - 1
        self.tool_offset = plant.chain.tool_p
        self.jacobian = np.zeros((3, self.model.nv))
        self.mass = np.zeros((self.model.nv, self.model.nv))

    def rollout(self, theta, start, duration: float) -> np.ndarray:
        plant, model, data, still = self.plant, self.model, self.data, self.still
        n = model.nv
        mujoco.mj_resetData(model, data)
        data.qpos[:], data.qvel[:] = start[:n], start[n:2 * n]
        phase = list(start[2 * n:])
        speed = plant.conveyor.speed if plant.conveyor is not None else 0.0
        n_steps = int(round(duration * plant.control_rate))
        states = np.empty((n_steps + 1, len(start)))
        limits, efforts = plant.chain.velocity_limit, plant.chain.effort_limit
        for k in range(n_steps + 1):
            states[k, :n], states[k, n:2 * n], states[k, 2 * n:] = data.qpos, data.qvel, phase
            if k == n_steps:
                break
            mujoco.mj_forward(model, data)
            tool = data.xpos[self.wrist] + data.xmat[self.wrist].reshape(3, 3) @ self.tool_offset
            mujoco.mj_jac(model, data, self.jacobian, None, tool, self.wrist)
            mujoco.mj_fullM(model, data, self.mass)
            still.qpos[:] = data.qpos
            mujoco.mj_forward(model, still)
            velocity = theta @ np.concatenate([tool, phase, [1.0]])
            J = self.jacobian
            reference = J.T @ np.linalg.solve(J @ J.T + plant.damping**2 * np.eye(3), velocity)
            over = np.abs(reference) / limits
            if over.max() > 1.0:
                reference = reference / over.max()
            tau = still.qfrc_bias + self.mass @ (plant.velocity_gain * (reference - data.qvel))
            data.qfrc_applied[:] = np.clip(tau, -efforts, efforts)
            mujoco.mj_step(model, data)
            phase = [p + speed * model.opt.timestep for p in phase]
        return states


def timed(function, repeat: int) -> list[float]:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return times


def main() -> int:
    print(f"mt-widgets UR5 benchmark; pinocchio {pinocchio.__version__}, MuJoCo {mujoco.__version__}; "
          f"{os.cpu_count()} cores; load average {os.getloadavg()[0]:.2f}")
    failed = False
    print("\n1. agreement of 10 s reproductions (largest |state difference|)")
    for key in KEYS:
        skill = SKILLS[key]
        theta = skill.theta + 0.1 * np.random.default_rng(1).standard_normal(skill.theta.shape)
        ours = skill.reproduce(theta).states
        pin_states = PinocchioUR5(skill.plant).rollout(theta, skill.start, 10.0)
        mj_states = MujocoUR5(skill.plant).rollout(theta, skill.start, 10.0)
        to_pin, to_mj = np.abs(ours - pin_states).max(), np.abs(ours - mj_states).max()
        failed |= not (to_pin < TOLERANCE and to_mj < TOLERANCE)
        print(f"   {key:<13} vs pinocchio {to_pin:.1e}   vs MuJoCo {to_mj:.1e}   (tolerance {TOLERANCE:.0e})")

    print("\n2. one 10 s reproduction at 1 kHz (10,000 controlled RK4 steps)")
    skill = SKILLS["ur5-reach"]
    skill.reproduce(skill.theta)   # compiled (or loaded from numba's cache) before timing
    cpu_start = time.process_time()
    ours = timed(lambda: skill.reproduce(skill.theta), 7)
    cpu = (time.process_time() - cpu_start) / len(ours)
    best, median = min(ours), statistics.median(ours)
    # Best of 7, as bench_core.py; the CPU time per run shows what a shared machine's load adds.
    verdict = "met" if best <= 0.050 else "missed"
    print(f"   mt-widgets (skill.reproduce)            best {best * 1e3:6.1f} ms  median {median * 1e3:6.1f} ms"
          f"  CPU {cpu * 1e3:5.1f} ms  (target 50 ms: {verdict})")
    pin_time = min(timed(lambda: PinocchioUR5(skill.plant).rollout(skill.theta, skill.start, 10.0), 2))
    print(f"   pinocchio ABA stepped from Python        {pin_time * 1e3:6.1f} ms   "
          f"mt-widgets is {pin_time / best:5.1f}x faster")
    mj = MujocoUR5(skill.plant)
    mj_time = min(timed(lambda: mj.rollout(skill.theta, skill.start, 10.0), 2))
    print(f"   MuJoCo stepped from Python (controller)  {mj_time * 1e3:6.1f} ms   "
          f"mt-widgets is {mj_time / best:5.1f}x faster")
    model, data = mj.model, mj.data

    def mujoco_alone():
        mujoco.mj_resetData(model, data)
        data.qpos[:] = skill.start[:6]
        data.qfrc_applied[:] = 0.0
        mujoco.mj_step(model, data, nstep=10_000)

    floor = min(timed(mujoco_alone, 5))
    print(f"   MuJoCo mj_step(nstep=10000), no control  {floor * 1e3:6.1f} ms   ratio mt-widgets / MuJoCo "
          f"{best / floor:5.2f}")

    print("\n3. feedback: fit + optimal actions + the 10 s reproduction of the learnt skill")
    for key in KEYS:
        skill = SKILLS[key]
        latencies = []
        for seed in range(20):
            episode = TeachingEpisode(skill, seed=seed)
            actions = episode.optimal_actions + 0.01 * np.random.default_rng(seed).standard_normal(
                episode.optimal_actions.shape)
            start = time.perf_counter()
            theta_hat = RidgeLearner(lam=episode.lam).fit(episode.features, actions)
            optimal_actions(episode.features, skill.theta, episode.lam)
            skill.reproduce(theta_hat, record_every=20)
            latencies.append(time.perf_counter() - start)
        p50, p95 = np.percentile(latencies, [50, 95]) * 1e3
        print(f"   {key:<13} p50 {p50:5.1f} ms  p95 {p95:5.1f} ms  (target p95 <= 150 ms)")
    if failed:
        print("\nFAILED: a reproduction disagrees with the reference beyond the tolerance")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
