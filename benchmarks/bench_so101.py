"""The SO-101's bus on the simulated arm at 1 Mbit/s timing: a sync read of the six positions, and
the hand-teaching read loop.

Run: ``python benchmarks/bench_so101.py``. Targets (issue 43): a SYNC_READ of the six present
positions within 2 ms; the hand-teaching loop (torque off, every joint read) at 50 Hz or faster.

The simulated bus (mt_widgets/hardware/feetech/sim_bus.py) spends each byte's 10 us on the wire
and each servo's return delay (0 after the connector's set-up), and is served on a pseudo-terminal
by a thread, so a round trip measured here is wire time + this suite's client + pyserial + the pty
+ the simulator. The wire time alone (what a real bus adds) is printed beside it.
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mt_widgets.hardware.feetech import SO101, SO101_IDS, SimulatedBus  # noqa: E402
from mt_widgets.hardware.feetech.calibration import calibration_from_dict  # noqa: E402
from mt_widgets.hardware.feetech.packet import OVERHEAD  # noqa: E402
from mt_widgets.hardware.feetech.sim_bus import BYTE_TIME  # noqa: E402
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort  # noqa: E402

REPEATS = 1000
TEACH_SECONDS = 3.0


def main() -> int:
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
