"""The install tier's helpers: build the sdist and the wheel, and install the wheel in a shape (its extras)
into a fresh venv. tests/install/test_shapes.py, tests/install/conftest.py and benchmarks/bench_install.py
use them."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
#: shape -> the extras installed (the core is no extra).
SHAPES = {"core": "", "widgets": "widgets", "analysis": "analysis", "uarm": "uarm", "lab": "lab"}
#: The environment of the shapes' Pythons: no PYTHONPATH, which would bring the checkout's package in.
CLEAN_ENV = {name: value for name, value in os.environ.items() if name not in ("PYTHONPATH", "VIRTUAL_ENV")}


def build_distributions(out: Path) -> tuple[Path, Path]:
    """(sdist, wheel) of the repository, built into ``out``."""
    subprocess.run([sys.executable, "-m", "build", "--outdir", str(out), str(ROOT)], check=True,
                   capture_output=True, timeout=900)
    (sdist,) = out.glob("mt_widgets-*.tar.gz")
    (wheel,) = out.glob("mt_widgets-*.whl")
    return sdist, wheel


def make_shape(wheel: Path, shape: str, venv: Path) -> Path:
    """A fresh venv at ``venv`` with the wheel installed in the shape ``shape``; its Python."""
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, capture_output=True, timeout=300)
    python = venv / "bin" / "python"
    requirement = f"{wheel}[{SHAPES[shape]}]" if SHAPES[shape] else str(wheel)
    # --no-compile: no byte-compiling of every installed module (a third of the lab's install time);
    # Python compiles what a shape imports the first time it is imported, as for any user.
    subprocess.run([python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-compile",
                    requirement],
                   check=True, capture_output=True, text=True, timeout=1800, env=CLEAN_ENV)
    return python
