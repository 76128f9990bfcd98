"""Promises the repository makes: clean notebooks, a pure core, Binder in step with pyproject."""

import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def tracked(pattern: str) -> list[Path]:
    names = subprocess.run(["git", "ls-files", pattern], cwd=REPO, capture_output=True, text=True, check=True).stdout
    return [REPO / name for name in names.split()]


def test_committed_notebooks_carry_no_outputs():
    notebooks = tracked("*.ipynb")
    assert notebooks, "expected tutorials and notebooks in the repository"
    dirty = []
    for path in notebooks:
        cells = json.loads(path.read_text())["cells"]
        if any(c.get("outputs") or c.get("execution_count") for c in cells if c["cell_type"] == "code"):
            dirty.append(path.relative_to(REPO))
    assert not dirty, f"strip the outputs of {dirty}"


def test_core_imports_no_jupyter_widget_or_serial_code():
    code = ("import sys, mt_widgets.core, mt_widgets; "
            "bad = [m for m in sys.modules if m.split('.')[0] in "
            "('ipywidgets', 'ipycanvas', 'IPython', 'ipykernel', 'serial', 'traitlets', 'matplotlib')]; "
            "print(bad); sys.exit(bool(bad))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def _requirement_set(lines):
    return {re.sub(r"\s+", "", line) for line in lines if line.strip() and not line.lstrip().startswith("#")}


def test_binder_requirements_agree_with_pyproject():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    expected = _requirement_set(project["dependencies"] + project["optional-dependencies"]["lab"])
    binder = _requirement_set((REPO / "binder" / "requirements.txt").read_text().splitlines())
    assert binder == expected, f"only in binder: {binder - expected}; only in pyproject: {expected - binder}"


def test_ci_runs_the_readme_test_command():
    readme = (REPO / "README.md").read_text()
    assert "./scripts/run-tests.sh" in readme and "./scripts/open-lab.sh" in readme
    assert "scripts/run-tests.sh" in (REPO / ".ci" / "run").read_text()


@pytest.mark.parametrize("name", ["open-lab.sh", "run-tests.sh", "setup.sh", "serve-demo.sh", "serve-study.sh",
                                  "test-fast.sh"])
def test_scripts_are_valid_bash(name):
    subprocess.run(["bash", "-n", str(REPO / "scripts" / name)], check=True)


def test_start_here_links_every_tutorial_and_app():
    start = json.loads((REPO / "tutorials" / "00_start_here.ipynb").read_text())
    text = "".join("".join(cell["source"]) for cell in start["cells"])
    for path in sorted((REPO / "tutorials").glob("[0-9][0-9]_*.ipynb")) + sorted((REPO / "notebooks").glob("*.ipynb")):
        if path.name != "00_start_here.ipynb":
            assert f"{path.name})" in text, f"tutorials/00_start_here.ipynb does not link {path.name}"
