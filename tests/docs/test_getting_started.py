"""The getting-started pages run as a newcomer follows them, with this checkout's package: each page's
code blocks top to bottom (tests/docs/getting_started_pages.py says how), with ``mt-widgets`` the
command of this checkout. The same pages run from the built wheel in a fresh venv, without the
repository on the path, in the install tier (tests/install/test_getting_started_from_wheel.py).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from tests.docs.getting_started_pages import CONTENT, LANGUAGES, PAGES, ROOT, SKIP, blocks, run_page


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
def test_the_page_runs_top_to_bottom(page, tmp_path):
    run = run_page(page, Path(sys.executable), _command_shim(tmp_path / "bin"), tmp_path)
    assert run.returncode == 0, run.stderr[-6000:]
    assert run.stdout.splitlines()[-1] in ("mt_widgets from none",
                                           f"mt_widgets from {ROOT / 'mt_widgets' / '__init__.py'}"), run.stdout[-2000:]
