"""Every install shape, from the built wheel: the way users meet the package (``pip install mt-widgets``,
with only the extras they need), not the clone's editable install of everything.

The tier ``install`` (tests/tiers.py) builds the sdist and the wheel (``python -m build``: the wheel is
built from the sdist, so both are checked), then installs each shape into a fresh venv from the wheel
and runs its smoke script (tests/install/smoke_<shape>.py) with that venv's Python, in an empty folder
outside the repository. pip's cache keeps the repeated downloads local; the sizes and import times of
the shapes are measured by benchmarks/bench_install.py (docs/guide/install.md).
"""

from __future__ import annotations

import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:   # Python 3.10
    import tomli as tomllib

import pytest

from .shapes import CLEAN_ENV, HERE, ROOT, SHAPES, make_shape

pytestmark = pytest.mark.install


def test_the_sdist_and_the_wheel_hold_the_package_and_its_data(distributions):
    sdist, wheel = distributions
    with zipfile.ZipFile(wheel) as archive:
        in_wheel = set(archive.namelist())
    with tarfile.open(sdist) as archive:
        in_sdist = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    for path in ("mt_widgets/core/ridge_kernels.py", "mt_widgets/study/protocols/paper_sim.toml",
                 "mt_widgets/analysis/data/synthetic-sim/study.json",
                 # The widgets' front ends (anywidget ES modules and a style sheet).
                 "mt_widgets/widgets/canvas_access.js", "mt_widgets/widgets/canvas_access.css",
                 "mt_widgets/apps/study/navigation.js"):
        assert path in in_wheel and path in in_sdist, path
    # The pages' Voila template, without a CDN (deploy/voila/voila.py selects it), in its folders.
    for name in ("index.html.j2", "conf.json"):
        path = f"deploy/voila/jupyter/voila/templates/mt-widgets/{name}"
        assert f"mt_widgets/_data/{path}" in in_wheel and path in in_sdist, path
    assert {"pyproject.toml", "LICENSE"} <= in_sdist
    assert not any(name.startswith(("tests/", "notebooks/")) for name in in_wheel)


def test_the_sdist_and_the_wheel_are_versioned_and_pass_twine_check(distributions):
    # What a release uploads (docs/release.md): the version of pyproject.toml in both names, and the
    # metadata and README the package index would render (twine check --strict: warnings fail too).
    sdist, wheel = distributions
    version = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["version"]
    assert sdist.name == f"mt_widgets-{version}.tar.gz" and wheel.name == f"mt_widgets-{version}-py3-none-any.whl"
    check = subprocess.run([sys.executable, "-m", "twine", "check", "--strict", str(sdist), str(wheel)],
                           capture_output=True, text=True, timeout=120)
    assert check.returncode == 0 and check.stdout.count("PASSED") == 2, check.stdout + check.stderr


@pytest.mark.parametrize("shape", list(SHAPES))
def test_each_shape_installs_from_the_wheel_and_runs_its_smoke_test(distributions, shape, tmp_path, request):
    _, wheel = distributions
    # The lab's venv is the session's (tests/install/conftest.py): the getting-started pages run in it too.
    python = request.getfixturevalue("lab_venv") if shape == "lab" else make_shape(wheel, shape, tmp_path / "venv")
    work = tmp_path / "work"  # an empty folder: mt_widgets can only come from the venv
    work.mkdir()
    where = subprocess.run([python, "-c", "import mt_widgets; print(mt_widgets.__file__)"], cwd=work,
                           capture_output=True, text=True, check=True, timeout=300, env=CLEAN_ENV).stdout
    assert where.startswith(str(python.parents[1])), f"mt_widgets imported from {where}, not the shape's venv"
    result = subprocess.run([python, str(HERE / f"smoke_{shape}.py")], cwd=work, capture_output=True, text=True,
                            timeout=900, env=CLEAN_ENV)
    assert result.returncode == 0, f"{shape}:\n{result.stdout}\n{result.stderr[-4000:]}"
    assert result.stdout.startswith(f"{shape}:"), result.stdout
    if shape == "lab":
        check_the_command(python.parent, tmp_path)


def check_the_command(bin_dir: Path, tmp_path: Path) -> None:
    """``mt-widgets`` after ``pip install "mt-widgets[lab]"``, in an empty folder with no clone in sight:
    its help, and the tutorials and notebooks copied from the wheel's mt_widgets/_data (one copy of each
    notebook lives in the repository; setup.py ships them into the wheel)."""
    empty = tmp_path / "empty"
    empty.mkdir()
    env = {"PATH": f"{bin_dir}:/usr/bin:/bin", "HOME": str(tmp_path)}  # no PYTHONPATH: not this clone

    def run(*argv):
        return subprocess.run([bin_dir / "mt-widgets", *argv], cwd=empty, env=env, capture_output=True, text=True,
                              check=True, timeout=300).stdout

    assert "lab" in run("--help") and "study" in run("--help")
    assert run("lab", "--help").startswith("usage: mt-widgets lab")
    where = subprocess.run([bin_dir / "python", "-c", "import mt_widgets.cli.shipped as s; "
                            "print(s.shipped_folder('tutorials'))"], cwd=empty, env=env, capture_output=True,
                           text=True, check=True, timeout=300).stdout.strip()
    assert where.startswith(str(bin_dir.parent)) and where.endswith("mt_widgets/_data/tutorials"), where
    run("lab", "class", "--copy-only")
    copied = sorted(p.name for p in (empty / "class" / "tutorials").iterdir())
    assert copied == sorted(p.name for p in (ROOT / "tutorials").iterdir() if p.suffix in (".ipynb", ".toml"))
    demo = (empty / "class" / "notebooks" / "demo.ipynb").read_bytes()
    assert demo == (ROOT / "notebooks" / "demo.ipynb").read_bytes()
    assert sorted(p.name for p in empty.iterdir()) == ["class"]
