"""Command round trip over the simulated uArm Swift Pro vs the line time at 115200 baud.

Run: ``python benchmarks/bench_uarm.py``. Target: the connector's overhead, the time a
round trip takes beyond putting its bytes on the wire, is at most 1 ms.

Two ways to read it:

* ``wire=off``: the simulated arm answers at once and its bytes take no time, so the whole
  measured round trip is overhead (connector, reader thread, pyserial layer, simulator);
* ``wire=on``: the simulated arm also spends each reply's line time at 115200 baud
  (10 bits a byte), so overhead = round trip - reply line time.

The line time printed is that of request plus reply, what a real link would add.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mt_widgets.hardware import SwiftPro  # noqa: E402

BAUD = 115200
REPEATS = 400


def line_time_s(n_bytes: int) -> float:
    """Seconds for ``n_bytes`` on the wire at 115200 baud, 10 bits a byte (8N1)."""
    return 10.0 * n_bytes / BAUD


def measure(arm: SwiftPro, action, repeats: int = REPEATS) -> list[float]:
    for _ in range(20):  # warm up
        action()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        action()
        times.append(time.perf_counter() - t0)
    return times


def main() -> int:
    request = len("#1234 P2220\n")
    reply = len("$1234 ok X200.0000 Y0.0000 Z100.0000\n")
    both = line_time_s(request + reply)
    print(f"P2220: request {request} B + reply {reply} B = {both * 1e3:.3f} ms line time at {BAUD} baud")
    print(f"{'case':<34}{'median':>10}{'p90':>10}{'overhead':>10}{'ratio':>8}")
    worst = 0.0
    for wire in (False, True):
        url = "uarm-sim://?boot=0.01&motion_scale=0&latency=0" + (f"&baud={BAUD}" if wire else "")
        with SwiftPro(url) as arm:
            rt = measure(arm, arm.position)
            median, p90 = statistics.median(rt), statistics.quantiles(rt, n=10)[-1]
            overhead = median - (line_time_s(reply) if wire else 0.0)
            worst = max(worst, overhead)
            ratio = (overhead + both) / both
            print(f"{'P2220 round trip, wire=' + ('on' if wire else 'off'):<34}{median * 1e3:>8.3f}ms"
                  f"{p90 * 1e3:>8.3f}ms{overhead * 1e3:>8.3f}ms{ratio:>8.2f}")

            targets = [(200.0, 0.0), (205.0, 0.0)]
            state = {"i": 0}

            def short_move(targets=targets, state=state):  # bound now: the loop rebinds both names
                state["i"] += 1
                arm.move_to(*targets[state["i"] % 2], speed=100.0)

            # A move is two round trips (M2222 then G1) plus the envelope checks; the arm
            # moves instantly here (motion_scale=0), so this is the connector's cost only.
            mv = measure(arm, short_move, repeats=REPEATS // 2)
            m_median = statistics.median(mv)
            m_reply = line_time_s(len("$1234 ok V1\n")) + line_time_s(len("$1234 ok\n"))
            m_over = (m_median - (m_reply if wire else 0.0)) / 2
            m_both = line_time_s(len("#1234 M2222 X205 Y0 Z80 P0\n") + len("#1234 G1 X205 Y0 Z80 F100\n")) \
                + m_reply
            print(f"{'5 mm move (2 round trips), wire=' + ('on' if wire else 'off'):<34}{m_median * 1e3:>8.3f}ms"
                  f"{statistics.quantiles(mv, n=10)[-1] * 1e3:>8.3f}ms{m_over * 1e3:>8.3f}ms"
                  f"{(2 * m_over + m_both) / m_both:>8.2f}")
            worst = max(worst, m_over)
    verdict = "OK" if worst <= 1e-3 else "ABOVE TARGET"
    print(f"worst overhead per round trip: {worst * 1e3:.3f} ms (target <= 1 ms): {verdict}")
    print("overhead = round trip beyond line time; ratio = (line time + overhead) / line time")
    return 0


if __name__ == "__main__":
    sys.exit(main())
