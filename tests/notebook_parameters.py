"""The one switch that shortens notebook work under test: each notebook's cell tagged ``parameters``.

A notebook that does long work (a whole study, hundreds of simulated studies, a real arm) keeps its
knobs in one code cell tagged ``parameters`` (papermill's convention), with the values a learner
runs it with. Under test, conftest.py (at the repository's root, so a run of one notebook gets it
too) appends to that cell the values below, as papermill injects a cell after it: every cell still
runs, on smaller inputs. The library itself never asks whether it runs under test.

A notebook without an entry here, or without a tagged cell, runs as it is. An entry whose notebook
has no tagged cell, or which names a parameter the cell does not assign, stops the run
(``ParametersError``, which the root conftest.py reports as pytest's usage error): a renamed
parameter must not quietly make a test run a learner's hours.

The documentation's build (docs/conf.py) shortens the notebooks it executes with the same values, and
runs with exactly the ``docs`` extra: this module imports nothing beyond the standard library
(tests/docs/test_docs_sources.py checks it without the test extra's packages).
"""

from __future__ import annotations

import ast
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

#: The tag of the cell whose values the test run overrides.
TAG = "parameters"


class ParametersError(ValueError):
    """``NOTEBOOK_PARAMETERS`` does not fit a notebook: no single cell tagged ``parameters``, or a
    value for a parameter the cell does not assign."""


@dataclass(frozen=True)
class Scratch:
    """A fresh folder for one test run, shared by the notebooks that name it (tutorials 10 and 11)."""

    name: str


#: The arm tests drive: the simulated one, 50x faster than real time (mt_widgets/hardware/bridge.py's
#: FAST_SIMULATOR_URL; tests/test_notebook_parameters.py checks the two agree).
SIMULATED_ARM = "uarm-sim://?firmware=4&boot=0.01&motion_scale=0.02"

#: Notebook (path from the repository's root) -> the values the test run gives its parameters.
NOTEBOOK_PARAMETERS: dict[str, dict[str, object]] = {
    # A synthetic novice plays into a scratch folder instead of enrolling "me" in ~/mt-widgets-lessons.
    "tutorials/10_protocol_capstone.ipynb": {"LET_A_SYNTHETIC_NOVICE_PLAY": True, "LOG_FOLDER": Scratch("capstone")},
    "tutorials/11_reading_the_results.ipynb": {"CAPSTONE_FOLDER": Scratch("capstone"), "N_STUDIES": 30},
    "tutorials/12_the_uarm.ipynb": {"PORT": SIMULATED_ARM, "DURATION": 3.0},
    "tutorials/13_teaching_an_industrial_arm.ipynb": {"N_QUERY_SETS": 5},
    "tutorials/14_when_the_robot_learns_differently.ipynb": {"N_SETS": 10, "N_STATES_MANY": 40},
    "tutorials/15_the_so101.ipynb": {"PORT": "sim", "CALIBRATION": None, "DURATION": 2.0},
    "tutorials/appendix_a_widget_api.ipynb": {"DURATION": 2.0},
    "notebooks/study_sim.ipynb": {"LOG_FOLDER": Scratch("study_sim")},
    "notebooks/study_online.ipynb": {"LOG_FOLDER": Scratch("study_online"), "CHECK_REFUSED_WITHOUT_LINK": True},
    "notebooks/study_uarm.ipynb": {"LOG_FOLDER": Scratch("study_uarm"), "PORT": SIMULATED_ARM},
    "notebooks/study_so101.ipynb": {"LOG_FOLDER": Scratch("study_so101"), "PORT": "sim", "LEADER_PORT": None},
    "notebooks/analysis.ipynb": {"FAST": True},
    # The switch's own test: the notebook asserts it got these values, not its own.
    "tests/data/parameters_cell.ipynb": {"N_STUDIES": 3, "LABEL": "under test", "FOLDER": Scratch("parameters_cell")},
}


def assigned_names(source: str) -> set[str]:
    """The names a cell's code assigns at its top level (IPython magics and shell lines left out)."""
    code = "\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!")))
    names = set()
    for node in ast.parse(code).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, (ast.AnnAssign, ast.AugAssign)) else []
        for target in targets:
            names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
    return names


def injected_source(source: str, values: dict[str, object], scratch_root: Path, notebook: str) -> str:
    """The parameters cell's ``source`` with the test run's ``values`` assigned after it.

    Raises:
        ParametersError: a value names a parameter the cell does not assign.
    """
    missing = sorted(set(values) - assigned_names(source))
    if missing:
        raise ParametersError(f"{notebook}: NOTEBOOK_PARAMETERS (tests/notebook_parameters.py) sets {missing}, "
                                f"which its cell tagged {TAG!r} does not assign")
    lines = [source.rstrip("\n"), "",
             "# Set by the test run (tests/notebook_parameters.py): the same work, shorter."]
    for name, value in values.items():
        if isinstance(value, Scratch):
            value = str(scratch_root / value.name)
        lines.append(f"{name} = {value!r}")
    return "\n".join(lines) + "\n"


def scratch_root(rootpath: Path) -> Path:
    """The folder of this checkout's scratch folders (one per checkout: worktrees run side by side)."""
    tag = re.sub(r"[^A-Za-z0-9_-]", "_", rootpath.resolve().name)
    return Path(tempfile.gettempdir()) / f"mt-widgets-notebook-tests-{tag}"


def inject(items, rootpath: Path) -> None:
    """Overrides the parameters cell of every collected notebook that ``NOTEBOOK_PARAMETERS`` names.

    Called once the items are selected: the scratch folders the selected notebooks name are made
    fresh (emptied), so a capstone run never continues an earlier test run's participant.

    Raises:
        ParametersError: a notebook named here has not exactly one cell tagged ``parameters``, or its
            cell does not assign a parameter named here.
    """
    root = scratch_root(rootpath)
    tagged: dict[str, list] = {}
    for item in items:
        cell = getattr(item, "cell", None)   # nbval's IPyNbCell
        if cell is None or item.path.suffix != ".ipynb":
            continue
        try:
            notebook = item.path.resolve().relative_to(rootpath.resolve()).as_posix()
        except ValueError:
            continue
        tagged.setdefault(notebook, [])
        if TAG in cell.get("metadata", {}).get("tags", []):
            tagged[notebook].append(cell)
    for notebook, cells in tagged.items():
        values = NOTEBOOK_PARAMETERS.get(notebook)
        if values is None:
            continue
        if len(cells) != 1:
            raise ParametersError(f"{notebook}: NOTEBOOK_PARAMETERS (tests/notebook_parameters.py) names it, so it "
                                    f"needs exactly one code cell tagged {TAG!r}; it has {len(cells)}")
        for value in values.values():
            if isinstance(value, Scratch):
                shutil.rmtree(root / value.name, ignore_errors=True)
                (root / value.name).mkdir(parents=True)
        cells[0].source = injected_source(cells[0].source, values, root, notebook)
