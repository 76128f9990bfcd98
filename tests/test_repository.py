"""Promises the repository makes: clean notebooks, a pure core, Binder in step with pyproject."""

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser as the tomli package (the test extra has it there)
    import tomli as tomllib

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


def _extra(project, name):
    """An extra's requirements, with ``mt-widgets[a,b]`` (an extra naming others) expanded."""
    requirements = []
    for requirement in project["optional-dependencies"][name]:
        own = re.fullmatch(r"mt-widgets\[([\w,-]+)\]", re.sub(r"\s+", "", requirement))
        if own:
            requirements += [r for other in own.group(1).split(",") for r in _extra(project, other)]
        else:
            requirements.append(requirement)
    return requirements


def test_binder_requirements_agree_with_pyproject():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    expected = _requirement_set(project["dependencies"] + _extra(project, "lab"))
    binder = _requirement_set((REPO / "binder" / "requirements.txt").read_text().splitlines())
    assert binder == expected, f"only in binder: {binder - expected}; only in pyproject: {expected - binder}"


#: The distribution that provides an import name, where the two differ.
_DISTRIBUTION = {"serial": "pyserial", "IPython": "ipython", "PIL": "pillow", "pinocchio": "pin"}


def _third_party_imports(folder: Path) -> set[str]:
    """The distributions the modules below ``folder`` import (anywhere in a module, also inside a function)."""
    names = set()
    for path in folder.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    # tomllib is standard from Python 3.11 (3.10's stdlib_module_names lacks it; there tomli stands in).
    names -= set(sys.stdlib_module_names) | {"mt_widgets", "tomllib"}
    return {_DISTRIBUTION.get(name, name).lower() for name in names}


def _distributions(requirements) -> set[str]:
    return {re.match(r"[A-Za-z0-9_.-]+", requirement).group(0).lower() for requirement in requirements}


def test_the_dependencies_are_what_the_core_imports_and_the_extras_cover_the_rest():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    core = _third_party_imports(REPO / "mt_widgets" / "core")
    assert _distributions(project["dependencies"]) == core, (
        "pyproject.toml's dependencies must be exactly what mt_widgets/core imports; the rest go in extras")
    everything = _third_party_imports(REPO / "mt_widgets")
    installed = _distributions(project["dependencies"] + _extra(project, "lab"))
    # IPython and traitlets come with ipywidgets (the widgets extra), which requires both. pin
    # (pinocchio) is the reference the UR5 is checked against: mt_widgets/robot_models/pinocchio_reference.py,
    # for the tests and the benchmark only, so it is in the test and bench extras.
    missing = everything - installed
    assert missing <= {"ipython", "traitlets", "pin"}, f"imported but in no extra of lab: {missing}"
    assert {"pin", "example-robot-data"} <= _distributions(_extra(project, "test")) & _distributions(
        _extra(project, "bench"))


def test_ci_runs_the_readme_test_command():
    readme = (REPO / "README.md").read_text()
    assert "./scripts/run-tests.sh" in readme and "./scripts/open-lab.sh" in readme
    assert "scripts/run-tests.sh" in (REPO / ".ci" / "run").read_text()


@pytest.mark.parametrize("name", ["open-lab.sh", "run-tests.sh", "setup.sh", "serve-demo.sh", "serve-study.sh",
                                  "test-fast.sh", "python-venv.sh"])
def test_scripts_are_valid_bash(name):
    subprocess.run(["bash", "-n", str(REPO / "scripts" / name)], check=True)


def test_start_here_links_every_tutorial_and_app():
    start = json.loads((REPO / "tutorials" / "00_start_here.ipynb").read_text())
    text = "".join("".join(cell["source"]) for cell in start["cells"])
    for path in sorted((REPO / "tutorials").glob("[0-9][0-9]_*.ipynb")) + sorted((REPO / "notebooks").glob("*.ipynb")):
        if path.name != "00_start_here.ipynb":
            assert f"{path.name})" in text, f"tutorials/00_start_here.ipynb does not link {path.name}"


def test_the_version_is_written_once_in_pyproject():
    import mt_widgets

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert mt_widgets.__version__ == project["version"]
    written = [path.relative_to(REPO) for path in (REPO / "mt_widgets").rglob("*.py")
               if re.search(r"^__version__\s*=\s*['\"]", path.read_text(encoding="utf-8"), re.M)]
    assert not written, f"a version written by hand in {written}: read importlib.metadata instead"
