"""Install size and import time of each install shape, from the built wheel.

Run: ``python benchmarks/bench_install.py`` (``--shapes core widgets`` for some; ``--wheel PATH`` to
use a wheel already built). Each shape is installed into a fresh venv from the wheel, exactly as the
install tier does (tests/install/test_shapes.py; its helpers, tests/install/shapes.py, are used here), and measured:

- size: the venv's site-packages, without pip and setuptools (what the shape itself brings);
- install: the seconds ``pip install`` took (with pip's cache as it is: warm on a second run);
- import: the median of 5 fresh interpreters running the shape's import (after one warm-up run, which
  also fills numba's cache), and the first science call for the core: wall-clock seconds, and the CPU
  seconds (user + system) of the interpreter, which a busy machine inflates far less than the wall clock.

No target: the figures are what docs/guide/install.md reports, for users choosing a shape.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from tests.install.shapes import CLEAN_ENV, SHAPES, build_distributions, make_shape  # noqa: E402

#: What a user of each shape imports first.
IMPORTS = {
    "core": "import mt_widgets",
    "widgets": "import mt_widgets.widgets",
    "analysis": "import mt_widgets.analysis",
    "uarm": "import mt_widgets.hardware",
    "lab": "import mt_widgets.widgets, mt_widgets.analysis, mt_widgets.hardware, voila.app",
}
SCIENCE = ("from mt_widgets import SKILLS, RidgeLearner, optimal_actions; s = SKILLS['sim-point']; "
           "P = s.features(s.query_states(seed=0)); "
           "RidgeLearner(lam=0.01).fit(P, optimal_actions(P, s.theta, lam=0.01)).theta")


def site_packages_mb(venv: Path) -> float:
    (site,) = venv.glob("lib/python3.*/site-packages")
    skip = ("pip", "setuptools", "_distutils_hack")
    total = 0
    for path in site.iterdir():
        if path.name.split("-")[0] in skip:
            continue
        files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
        total += sum(p.stat().st_size for p in files)
    return total / 1e6


def import_seconds(python: Path, code: str, cwd: Path, runs: int = 5) -> tuple[float, float]:
    """(wall, CPU) seconds of a fresh interpreter running ``code``, medians of ``runs``."""
    subprocess.run([python, "-c", code], check=True, cwd=cwd, env=CLEAN_ENV, timeout=600)
    wall, cpu = [], []
    for _ in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run([python, "-c", code], check=True, cwd=cwd, env=CLEAN_ENV, timeout=600)
        wall.append(time.perf_counter() - start)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return statistics.median(wall), statistics.median(cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", nargs="+", choices=list(SHAPES), default=list(SHAPES))
    parser.add_argument("--wheel", type=Path, help="a built wheel (default: build one)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        wheel = args.wheel
        if wheel is None:
            start = time.perf_counter()
            _, wheel = build_distributions(scratch / "dist")
            print(f"build sdist + wheel: {time.perf_counter() - start:.1f} s")
        print(f"Python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.1f}")
        print(f"{'shape':<9} {'size MB':>8} {'install s':>10} {'import s':>9} {'import CPU s':>13}")
        for shape in args.shapes:
            start = time.perf_counter()
            python = make_shape(wheel, shape, scratch / shape)
            installed = time.perf_counter() - start
            (scratch / "work").mkdir(exist_ok=True)
            wall, cpu = import_seconds(python, IMPORTS[shape], scratch / "work")
            line = f"{shape:<9} {site_packages_mb(scratch / shape):8.0f} {installed:10.1f} {wall:9.2f} {cpu:13.2f}"
            if shape == "core":
                wall, cpu = import_seconds(python, SCIENCE, scratch / "work")
                line += f"   (import + first fit and optimal actions: {wall:.2f} s, CPU {cpu:.2f} s)"
            print(line, flush=True)


if __name__ == "__main__":
    main()
