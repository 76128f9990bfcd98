"""A Voila server for the study page; Chromium is the shared ``browser`` of tests/conftest.py.

The server runs notebooks/study_sim.ipynb as a participant would get it, in its own process
group with its own JUPYTER_* folders and log folder in a temporary directory; the whole group
is ended at teardown. A missing Chromium or Playwright fails the tests, never skips them.
"""

from __future__ import annotations

import shutil

import pytest

from browser_support import REPO, local_page, voila


@pytest.fixture(scope="module")
def voila_study(tmp_path_factory):
    """Voila serving the study page, with ``.logs``: the study's log folder."""
    root = tmp_path_factory.mktemp("voila-study")
    (root / "notebooks").mkdir()
    shutil.copy(REPO / "notebooks" / "study_sim.ipynb", root / "notebooks" / "study_sim.ipynb")
    logs = root / "logs"
    # The page as a participant gets it: the real log folder, not the notebook's test folder.
    server = voila(root, env={"MT_WIDGETS_FAST": "0", "MT_WIDGETS_STUDY_LOGS": str(logs)})
    server.logs = logs
    yield server
    server.stop()


@pytest.fixture
def page(browser):
    context, page = local_page(browser, 1280, 1200)
    yield page
    context.close()


@pytest.fixture
def shot(artifacts):
    """Where to keep a screenshot of a step (the shared ``artifacts``)."""
    return artifacts
