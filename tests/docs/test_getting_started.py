"""The getting-started pages run as a newcomer follows them: each page's code blocks top to bottom.

Every fenced ``bash`` and ``python`` block of docs/getting-started/*.md runs in order, in a fresh
folder with a fresh home: the shell blocks line by line through bash (``set -e``), with
``mt-widgets`` the command of this checkout's package; the Python blocks in one namespace per page,
as in one Python session. A block that cannot run here (a server that runs until it is stopped, a
clone's scripts, an install) is preceded by the marker ``<!-- not run by
tests/docs/test_getting_started.py: REASON -->``, and says why.

What this does not do yet: install the built wheel into a fresh venv first (the install tier,
tests/install/test_shapes.py, installs every shape from the wheel and runs the ``mt-widgets``
command there).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted((ROOT / "docs" / "getting-started").glob("*.md"))
#: The marker before a block this test leaves out, and why (the reason is required).
SKIP = re.compile(r"^<!-- not run by tests/docs/test_getting_started\.py: (?P<reason>.*\S.*) -->$")
LANGUAGES = ("bash", "python")
#: Blocks that show a file's content rather than something to type, left as they are.
CONTENT = ("toml", "text", "json")


@dataclass(frozen=True)
class Block:
    language: str
    code: str
    line: int
    skipped_because: str | None


def blocks(page: Path) -> list[Block]:
    """The page's fenced code blocks (those inside list items too), with the skip marker before each."""
    lines = page.read_text(encoding="utf-8").splitlines()
    found, i = [], 0
    while i < len(lines):
        opening = re.match(r"^(\s*)```(\S*)\s*$", lines[i])
        if not opening:
            i += 1
            continue
        indent, language = len(opening.group(1)), opening.group(2)
        end = next(j for j in range(i + 1, len(lines)) if re.match(r"^\s*```\s*$", lines[j]))
        before = next((lines[j].strip() for j in range(i - 1, -1, -1) if lines[j].strip()), "")
        marker = SKIP.match(before)
        code = "\n".join(line[indent:] for line in lines[i + 1:end]) + "\n"
        if not language.startswith("{"):   # a MyST directive (```{toctree}), not code
            found.append(Block(language, code, i + 1, marker.group("reason") if marker else None))
        i = end + 1
    return found


def test_every_block_of_the_pages_is_bash_or_python_and_every_skip_says_why():
    every = [(page.name, block) for page in PAGES for block in blocks(page)]
    assert any(block.skipped_because is None for _, block in every)
    for name, block in every:
        assert block.language in LANGUAGES + CONTENT, (
            f"{name}:{block.line}: a ```{block.language} block; the test runs {LANGUAGES} and leaves {CONTENT}")
    for page in PAGES:
        for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if "not run by tests/docs/test_getting_started.py" in line:
                assert SKIP.match(line.strip()), f"{page.name}:{number}: a skip marker without its reason: {line!r}"


def _command_shim(folder: Path) -> dict:
    """A ``mt-widgets`` on PATH that runs this checkout's command with this run's Python."""
    folder.mkdir()
    shim = folder / "mt-widgets"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m mt_widgets.cli "$@"\n')
    shim.chmod(0o755)
    return {**os.environ, "PATH": f"{folder}{os.pathsep}{os.environ['PATH']}", "PYTHONPATH": str(ROOT)}


@pytest.mark.slow   # the researcher's page runs an in-silico pilot and 100 simulated studies: 10-25 s
@pytest.mark.parametrize("page", PAGES, ids=lambda page: page.name)
def test_the_page_runs_top_to_bottom(page, tmp_path, monkeypatch):
    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir()
    work.mkdir()
    environment = {**_command_shim(tmp_path / "bin"), "HOME": str(home)}
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    namespace: dict = {"__name__": "__getting_started__"}
    for block in blocks(page):
        if block.skipped_because is not None or block.language in CONTENT:
            continue
        where = f"{page.relative_to(ROOT)}:{block.line}"
        if block.language == "bash":
            run = subprocess.run(["bash", "-euo", "pipefail", "-c", block.code], cwd=work, env=environment,
                                 capture_output=True, text=True, timeout=300)
            assert run.returncode == 0, f"{where}: {block.code}\n{run.stdout}\n{run.stderr}"
        else:
            exec(compile(block.code, where, "exec"), namespace)
