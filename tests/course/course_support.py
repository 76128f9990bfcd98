"""Running nbgrader on a copy of course/: shared by the course tests and the hub test."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat

REPO = Path(__file__).resolve().parents[2]
COURSE = REPO / "course"
ASSIGNMENTS = sorted(p.name for p in (COURSE / "source").iterdir() if p.is_dir())


def course_env(**extra) -> dict:
    """The environment nbgrader needs: the venv's bin first on PATH (nbgrader runs `alembic` by
    name), this checkout first on PYTHONPATH, and no class folder (grading records nothing)."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = f"{REPO}{os.pathsep}{env['PYTHONPATH']}" if env.get("PYTHONPATH") else str(REPO)
    env.pop("MT_WIDGETS_CLASS_FOLDER", None)
    env.update(extra)
    return env


def nbgrader(course: Path, *args, env=None, timeout=600) -> subprocess.CompletedProcess:
    """Runs ``nbgrader ARGS`` in ``course`` and returns the finished process (output as text)."""
    return subprocess.run([str(Path(sys.executable).parent / "nbgrader"), *args], cwd=course, env=env or course_env(),
                          capture_output=True, text=True, timeout=timeout)


def copy_course(target: Path) -> Path:
    """A copy of course/ (config and sources only) to grade in, so no gradebook lands in the repository."""
    shutil.copytree(COURSE, target, ignore=shutil.ignore_patterns("gradebook.db", "release", "submitted",
                                                                  "autograded", "feedback", ".ipynb_checkpoints"))
    return target


def source_notebook(assignment: str) -> nbformat.NotebookNode:
    return nbformat.read(COURSE / "source" / assignment / f"{assignment}.ipynb", as_version=4)


def grade_id(cell) -> str | None:
    return cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")


def max_points(assignment: str) -> float:
    return sum(float(c.metadata["nbgrader"].get("points", 0)) for c in source_notebook(assignment).cells
               if c.metadata.get("nbgrader", {}).get("grade"))
