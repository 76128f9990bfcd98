"""The command from the built wheel, installed (not editable) with the lab extra into a fresh venv:
``mt-widgets --help``, ``mt-widgets lab --help`` and the tutorials copied into an empty folder,
with no clone in sight (the venv and the folder are outside the repository; the notebooks come
from the wheel's mt_widgets/_data). Measured here: 3 min 37 s with a warm pip cache
(two shared cores)."""

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_the_wheel_installs_the_command_and_ships_the_notebooks():
    # A folder of its own, not pytest's tmp_path: pytest removes old basetemp folders of other runs
    # under the same user, and a run alongside this one's minutes of installing removed its venv.
    with tempfile.TemporaryDirectory(prefix="cliwheel-") as folder:
        _install_and_run(Path(folder))


def _install_and_run(tmp_path: Path):
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", str(dist), str(REPO)],
                   check=True, cwd=tmp_path)
    wheel, = dist.glob("mt_widgets-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    # Without PYTHONPATH: pip would see this clone's mt_widgets.egg-info on it, call mt-widgets
    # installed already and skip the wheel (which is how the command went missing once).
    clean = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    subprocess.run([venv / "bin" / "python", "-m", "pip", "install", "--quiet", f"{wheel}[lab]"], check=True,
                   cwd=tmp_path, env=clean)
    command = venv / "bin" / "mt-widgets"
    assert command.exists(), sorted(p.name for p in (venv / "bin").iterdir())
    empty = tmp_path / "empty"
    empty.mkdir()
    env = {"PATH": f"{venv / 'bin'}:/usr/bin:/bin", "HOME": str(tmp_path)}  # no PYTHONPATH: not this clone

    def run(*argv):
        return subprocess.run([command, *argv], cwd=empty, env=env, capture_output=True, text=True, check=True).stdout

    assert "lab" in run("--help") and "study" in run("--help")
    assert run("lab", "--help").startswith("usage: mt-widgets lab")
    where = subprocess.run([venv / "bin" / "python", "-c", "import mt_widgets.cli.shipped as s; "
                            "print(s.shipped_folder('tutorials'))"], cwd=empty, env=env, capture_output=True,
                           text=True, check=True).stdout.strip()
    assert where.startswith(str(venv)) and where.endswith("mt_widgets/_data/tutorials")
    run("lab", "class", "--copy-only")
    copied = sorted(p.name for p in (empty / "class" / "tutorials").iterdir())
    assert copied == sorted(p.name for p in (REPO / "tutorials").iterdir() if p.suffix in (".ipynb", ".toml"))
    demo = (empty / "class" / "notebooks" / "demo.ipynb").read_bytes()
    assert demo == (REPO / "notebooks" / "demo.ipynb").read_bytes()
    assert sorted(p.name for p in empty.iterdir()) == ["class"]
