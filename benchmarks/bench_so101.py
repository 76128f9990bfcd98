"""The SO-101's bus on the simulated arm at 1 Mbit/s timing: a sync read of the six positions, the
hand-teaching read loop, and the feedback after a demonstration by hand.

Run: ``python benchmarks/bench_so101.py [--demonstrations N]``. Targets (issue 43): a SYNC_READ
of the six present positions within 2 ms; the hand-teaching loop (torque off, every joint read) at
50 Hz or faster; feedback after a demonstration by hand within 150 ms at p95.

The feedback is measured on the page's own code (``SO101Teaching`` wiring an ``SO101EpisodePage``,
kernel-free) with a scripted hand moving the simulated arm's gripper (``SimulatedHand``) at each
query state: for each demonstration, the time from the hand's reading ending to its arrow set
(``SO101Teaching.arrow_latencies``, the arrow that is then confirmed) plus the confirmation to
MT's guidance (the optimal arrow) being ready. The loop's rate is that of the same demonstrations'
readings (``HandDemonstration.samples``) while the arm was released.

The simulated bus (mt_widgets/hardware/feetech/sim_bus.py) spends each byte's 10 us on the wire
and each servo's return delay (0 after the connector's set-up), and is served on a pseudo-terminal
by a thread, so a round trip measured here is wire time + this suite's client + pyserial + the pty
+ the simulator. The wire time alone (what a real bus adds) is printed beside it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from mt_widgets.apps.so101_study import open_so101  # noqa: E402
from mt_widgets.hardware.errors import UnsafeMoveError  # noqa: E402
from mt_widgets.hardware.feetech import ARM_JOINTS, SO101, SO101_IDS, SimulatedBus  # noqa: E402
from mt_widgets.hardware.feetech.calibration import calibration_from_dict  # noqa: E402
from mt_widgets.hardware.feetech.packet import OVERHEAD  # noqa: E402
from mt_widgets.hardware.feetech.sim_bus import BYTE_TIME  # noqa: E402
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort  # noqa: E402
from mt_widgets.widgets import EpisodeWidget  # noqa: E402

REPEATS = 1000
TEACH_SECONDS = 3.0
#: How long the scripted hand waits at each query state before it moves the gripper (s).
DWELL_S = 0.3


def wait_until(predicate, teaching, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise RuntimeError(f"timed out; the arm's message: {teaching.panel.message.value}")
        time.sleep(0.005)


def feedback_by_hand(demonstrations: int) -> None:
    """Feedback after ``demonstrations`` demonstrations by hand, over as many episodes as they take."""
    feedback, arrows, guidance, rates = [], [], [], []
    skipped = 0
    teaching = open_so101("sim", speed_scale=20.0, play_on_arm=False)
    try:
        seed = 0
        while len(feedback) < demonstrations:
            episode = EpisodeWidget("so101-reach", seed=seed, guidance=True)
            seed += 1
            try:    # an episode whose query state the arm's envelope refuses is not taught on the arm
                for state in episode.query_states:
                    teaching.arm.envelope.check_joints(dict(zip(ARM_JOINTS, (float(v) for v in state[:5]))))
            except UnsafeMoveError:
                skipped += 1
                continue
            teaching.attach(episode)                               # as SO101EpisodePage does
            length = episode.skill.plant.drawing().action_length
            hand = teaching.hand_views[0].hand
            for k, state in enumerate(episode.query_states):
                if len(feedback) >= demonstrations:
                    break
                wait_until(lambda state=state: teaching.hand_demonstration is not None
                           and teaching.hand_demonstration.released
                           and np.allclose(teaching.hand_demonstration.query_state, state[:5]), teaching)
                move = teaching.hand_demonstration
                time.sleep(DWELL_S)                                        # a person takes the gripper first
                shown = episode.skill.theta @ episode.features[k]          # the target policy's own action
                if not hand.move_tool_by(shown * length):
                    raise RuntimeError(f"the scripted hand could not move the gripper by {shown * length} m")
                wait_until(lambda shown=shown, episode=episode: episode.pending_action is not None
                           and np.linalg.norm(np.subtract(episode.pending_action, shown)) < 0.01, teaching)
                arrow = teaching.arrow_latencies[-1]                      # the arrow now confirmed
                t0 = time.perf_counter()
                episode.teaching.confirm()
                if episode.phase != "guidance":
                    raise RuntimeError(f"no guidance after a confirmation: the episode is in {episode.phase!r}")
                shown_guidance = time.perf_counter() - t0
                feedback.append(arrow + shown_guidance)
                arrows.append(arrow)
                guidance.append(shown_guidance)
                times = [t for t, _ in move.samples[1:]]                  # the loop's readings (not the start)
                if len(times) > 2:
                    rates.append((len(times) - 1) / (times[-1] - times[0]))
                episode.next()
    finally:
        teaching.close()

    def p95(values):
        return float(np.percentile(values, 95)) * 1e3

    print(f"feedback after a demonstration by hand: {len(feedback)} demonstrations over {seed - skipped} episodes "
          f"({skipped} left out: a query state outside the arm's envelope): "
          f"p50 {statistics.median(feedback) * 1e3:.1f} ms  p95 {p95(feedback):.1f} ms  "
          f"max {max(feedback) * 1e3:.1f} ms  target 150 ms at p95: {'met' if p95(feedback) <= 150 else 'MISSED'}")
    print(f"{'  of which reading to arrow':<34}p50 {statistics.median(arrows) * 1e3:.1f} ms  p95 {p95(arrows):.1f} ms")
    print(f"{'  of which confirm to guidance':<34}p50 {statistics.median(guidance) * 1e3:.1f} ms  "
          f"p95 {p95(guidance):.1f} ms")
    print(f"{'hand loop while teaching':<34}{statistics.median(rates):.1f} Hz median, {min(rates):.1f} Hz lowest "
          f"over {len(rates)} demonstrations  target 50 Hz: {'met' if min(rates) >= 50 * 0.99 else 'MISSED'}  "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--demonstrations", type=int, default=30,
                        help="demonstrations by hand for the feedback figure (default 30)")
    args = parser.parse_args()
    if args.demonstrations < 1:
        parser.error(f"--demonstrations: expected a positive count, got {args.demonstrations}")
    calibration = {joint: {"id": i, "drive_mode": 0, "homing_offset": 0, "range_min": 1000, "range_max": 3000}
                   for joint, i in SO101_IDS.items()}
    calibration_from_dict(calibration)
    wire = ((OVERHEAD + 2 + len(SO101_IDS)) + len(SO101_IDS) * (OVERHEAD + 2)) * BYTE_TIME
    print(f"sync read of 6 positions: {wire * 1e3:.3f} ms on the wire at 1 Mbit/s (request 14 B, 6 answers of 8 B)")
    with SimulatedArmPort(SimulatedBus()) as server, SO101(server.path, calibration, timeout=0.5) as arm:
        # (A generous timeout: on a loaded machine the pty's thread may wait for a CPU; the figures
        # below show how long the answers took.)
        for _ in range(50):
            arm.read_steps()
        times = []
        for _ in range(REPEATS):
            t0 = time.perf_counter()
            arm.read_steps()
            times.append(time.perf_counter() - t0)
        p50, p95 = statistics.median(times), statistics.quantiles(times, n=20)[-1]
        print(f"{'sync read round trip':<34}p50 {p50 * 1e3:.3f} ms  p95 {p95 * 1e3:.3f} ms  "
              f"max {max(times) * 1e3:.3f} ms")
        print(f"{'target 2 ms':<34}p50 {'met' if p50 <= 2e-3 else 'MISSED'}, p95 {'met' if p95 <= 2e-3 else 'MISSED'}"
              f"  (load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs: the pty server is a thread)")
        # As fast as the loop goes (rate 1000 asks more than it can give), then at the 50 Hz it needs.
        for rate in (1000.0, 50.0):
            samples = arm.follow_by_hand(TEACH_SECONDS, rate=rate)
            span = samples[-1][0] - samples[0][0]
            achieved = (len(samples) - 1) / span
            gaps = [b[0] - a[0] for a, b in zip(samples, samples[1:])]
            print(f"{f'hand-teaching loop at rate={rate:g}':<34}{achieved:.0f} Hz over {span:.1f} s, "
                  f"longest gap {max(gaps) * 1e3:.1f} ms  target 50 Hz: {'met' if achieved >= 50 * 0.99 else 'MISSED'}")
    feedback_by_hand(args.demonstrations)
    return 0


if __name__ == "__main__":
    sys.exit(main())
