"""Ruff, configured in pyproject.toml, finds nothing in the tree (package, tests, benchmarks,
notebooks): no unused import or name, no undefined name, imports in order, lines of at most
120 characters, no likely bug (bugbear). An unused import hides a missing use or a stale one."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def ruff(*args: str) -> subprocess.CompletedProcess:
    """``ruff check`` of this environment (the ``test`` extra installs it), without a cache in the tree."""
    if importlib.util.find_spec("ruff") is None:
        pytest.fail("ruff is not installed: pip install 'mt-widgets[test]'", pytrace=False)
    return subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--output-format", "concise", *args],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)


def test_ruff_reports_nothing_in_the_tree():
    result = ruff(".")
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_configuration_is_in_force(tmp_path):
    # A scratch file checked with the repository's settings: the unused import and the long
    # line are reported, so a green run above means the rules ran.
    scratch = tmp_path / "scratch.py"
    scratch.write_text("import os\n\nx = '" + "a" * 130 + "'\n")
    result = ruff("--config", str(ROOT / "pyproject.toml"), str(scratch))
    assert result.returncode == 1
    assert "F401" in result.stdout and "E501" in result.stdout
