"""No test switch in the library: notebooks take their shortening from a cell tagged ``parameters``
that the test run overrides (tests/notebook_parameters.py, the root conftest.py); the simulated
arm takes its speed as an argument."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.bridge import FAST_SIMULATOR_SPEED, FAST_SIMULATOR_URL, connect_arm, default_simulator_url
from mt_widgets.hardware.connector import SIMULATOR_URL
from notebook_parameters import (
    NOTEBOOK_PARAMETERS,
    SIMULATED_ARM,
    TAG,
    ParametersError,
    Scratch,
    assigned_names,
    injected_source,
)

REPO = Path(__file__).resolve().parents[1]


def tracked(*patterns: str) -> list[Path]:
    names = subprocess.run(["git", "ls-files", *patterns], cwd=REPO, capture_output=True, text=True, check=True).stdout
    return [REPO / name for name in names.split()]


def code_cells(path: Path) -> list[dict]:
    return [cell for cell in json.loads(path.read_text(encoding="utf-8"))["cells"] if cell["cell_type"] == "code"]


@pytest.mark.parametrize("notebook", sorted(NOTEBOOK_PARAMETERS))
def test_each_listed_notebook_has_one_parameters_cell_assigning_what_the_test_run_sets(notebook):
    path = REPO / notebook
    assert path.is_file(), f"NOTEBOOK_PARAMETERS names {notebook}, which does not exist"
    tagged = [cell for cell in code_cells(path) if TAG in cell["metadata"].get("tags", [])]
    assert len(tagged) == 1, f"{notebook}: {len(tagged)} code cells tagged {TAG!r}"
    source = "".join(tagged[0]["source"])
    assert set(NOTEBOOK_PARAMETERS[notebook]) <= assigned_names(source)


def test_nothing_asks_whether_it_runs_under_test():
    files = tracked("mt_widgets/*.py", "*.ipynb", "course/*.py", "deploy/*.py")
    assert files
    asking = [path.relative_to(REPO).as_posix() for path in files
              if "running_under_test" in path.read_text(encoding="utf-8")]
    assert not asking, f"ask for a parameter instead (tests/notebook_parameters.py): {asking}"


def test_the_override_comes_after_the_cells_own_values_and_names_only_what_it_assigns(tmp_path):
    source = 'N_STUDIES = 300\nFOLDER = "~/study"\n'
    injected = injected_source(source, {"N_STUDIES": 30, "FOLDER": Scratch("x")}, tmp_path, "a.ipynb")
    namespace: dict = {}
    exec(injected, namespace)
    assert namespace["N_STUDIES"] == 30 and namespace["FOLDER"] == str(tmp_path / "x")
    assert injected.startswith(source.rstrip("\n"))
    with pytest.raises(ParametersError, match=r"a.ipynb: .*\['N_STUDY'\].* does not assign"):
        injected_source(source, {"N_STUDY": 30}, tmp_path, "a.ipynb")
    assert assigned_names("%matplotlib inline\nA = 1\nB: int = 2\nC, (D, E) = 3, (4, 5)\nprint(F)\n") == set("ABCDE")


@pytest.mark.slow
def test_a_run_of_one_notebook_gets_the_test_values():
    # The root conftest.py is loaded for any path in the repository: the notebook asserts the values.
    result = subprocess.run([sys.executable, "-m", "pytest", "--nbval-lax", "-q", "-p", "no:cacheprovider",
                             "tests/data/parameters_cell.ipynb"], cwd=REPO, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0 and "2 passed" in result.stdout, result.stdout + result.stderr


def test_the_simulated_arms_speed_is_an_argument(monkeypatch):
    assert SIMULATED_ARM == FAST_SIMULATOR_URL == default_simulator_url(FAST_SIMULATOR_SPEED)
    assert default_simulator_url() == SIMULATOR_URL and "motion_scale=0.5" in default_simulator_url(2)
    with pytest.raises(ValueError, match="speed"):
        default_simulator_url(0)
    monkeypatch.setenv("MT_WIDGETS_FAST", "1")   # the retired switch changes nothing
    monkeypatch.setattr(SwiftPro, "find_ports", staticmethod(lambda: []))
    for speed, url in ((1.0, SIMULATOR_URL), (FAST_SIMULATOR_SPEED, FAST_SIMULATOR_URL)):
        arm = connect_arm(None, simulator_speed=speed, timeout=5.0)
        try:
            assert arm.port_used == url
        finally:
            arm.close()
