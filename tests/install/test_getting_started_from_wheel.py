"""The getting-started pages as a newcomer without a clone follows them: the built wheel with its
``lab`` extra in a fresh venv (the install tier's, tests/install/conftest.py), no repository file on
the path (no PYTHONPATH; the page runs in an empty folder with an empty home), ``mt-widgets`` the
venv's own command, each page's blocks top to bottom (tests/docs/getting_started_pages.py; a block
that cannot run says why in its marker)."""

from __future__ import annotations

import pytest

from tests.docs.getting_started_pages import PAGES, run_page, runnable

from .shapes import CLEAN_ENV

pytestmark = pytest.mark.install


@pytest.mark.parametrize("page", [page for page in PAGES if runnable(page)], ids=lambda page: page.name)
def test_the_page_runs_top_to_bottom_from_the_wheel(page, lab_venv, tmp_path):
    venv = lab_venv.parents[1]
    # The venv's bin first, then only the system's: no other Python's mt-widgets can answer.
    environment = {**CLEAN_ENV, "PATH": f"{venv / 'bin'}:/usr/bin:/bin"}
    run = run_page(page, lab_venv, environment, tmp_path)
    assert run.returncode == 0, run.stderr[-6000:]
    where = run.stdout.splitlines()[-1]
    assert where.startswith(f"mt_widgets from {venv}/lib/"), f"the page's mt_widgets is not the wheel's: {where}"
