"""Voila servers for the study pages; Chromium is the shared ``browser`` of tests/conftest.py.

``voila_study`` runs notebooks/study_sim.ipynb (the lab page) and notebooks/study_online.ipynb
(the online page, with the shipped pilot protocol) as participants would get them, each server
in its own process group with its own JUPYTER_* folders and log folder in a temporary
directory; the whole group is ended at teardown. ``voila_shipped`` serves the same with the
shipped configuration (deploy/voila/voila.py: preheated kernels, which wait for the page's query
string). A missing Chromium or Playwright fails the tests, never skips them.
"""

from __future__ import annotations

import shutil

import pytest

from browser_support import REPO, local_page, voila

from .support import EXPERIMENTER_CODE

PAGES = ("study_sim.ipynb", "study_online.ipynb", "study_online_pilot.toml")


def _serve(root, *options):
    (root / "notebooks").mkdir()
    for name in PAGES:
        shutil.copy(REPO / "notebooks" / name, root / "notebooks" / name)
    logs = root / "logs"
    # The pages as participants get them: the real log folder, not the notebooks' test folders.
    server = voila(root, *options, env={"MT_WIDGETS_STUDY_LOGS": str(logs),
                                        "MT_WIDGETS_EXPERIMENTER_CODE": EXPERIMENTER_CODE})
    server.logs = logs
    return server


@pytest.fixture(scope="module")
def voila_study(tmp_path_factory):
    """Voila serving the study pages, with ``.logs``: the study's log folder."""
    server = _serve(tmp_path_factory.mktemp("voila-study"))
    yield server
    server.stop()


@pytest.fixture(scope="module")
def voila_shipped(tmp_path_factory):
    """The study pages with the shipped configuration (deploy/voila/voila.py)."""
    server = _serve(tmp_path_factory.mktemp("voila-shipped"), f"--Voila.config_file_paths={REPO / 'deploy' / 'voila'}")
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
