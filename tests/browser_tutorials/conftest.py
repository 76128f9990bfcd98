"""A Voila server over the tutorials that have live sliders, and local-only pages (tests/browser_support.py)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from browser_support import local_page, voila

TUTORIALS = Path(__file__).resolve().parents[2] / "tutorials"
SLIDER_TUTORIALS = ["02_ridge_regression.ipynb", "05_query_states_and_conditioning.ipynb"]


@pytest.fixture
def page(browser):
    context, page = local_page(browser, width=1280, height=1400)
    yield page
    context.close()


@pytest.fixture(scope="module")
def tutorial_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("tutorials")
    (root / "notebooks").mkdir()
    for name in SLIDER_TUTORIALS:
        shutil.copy(TUTORIALS / name, root / "notebooks" / name)
    server = voila(root)
    yield server
    server.stop()
