"""Fixtures of the uArm app tests: a connected simulated arm and its bridge."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

# Chromium (``browser``) and ``artifacts`` are the shared fixtures of tests/conftest.py.
from browser_support import local_page, voila
from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.bridge import UArmBridge

# The canvas recorder of the kernel-free widget tests, reused rather than copied.
from widgets.conftest import recorder  # noqa: F401

from .helpers import sim_url


@pytest.fixture
def arm():
    with SwiftPro(sim_url(), timeout=1.0) as connected:
        yield connected


@pytest.fixture
def bridge(arm):
    return UArmBridge(arm)


PAGES = Path(__file__).parent / "pages"


@pytest.fixture(scope="session")
def uarm_voila(tmp_path_factory):
    """Voila serving this folder's pages (one server, its own JUPYTER_* dirs, ended as a group)."""
    root = tmp_path_factory.mktemp("uarm-voila")
    (root / "notebooks").mkdir()
    for page in PAGES.glob("*.ipynb"):
        shutil.copy(page, root / "notebooks" / page.name)
    server = voila(root)
    yield server
    server.stop()


@pytest.fixture
def tall_page(browser):
    """A page tall enough for the texts above a 700 px pinned screen canvas; only 127.0.0.1."""
    context, page = local_page(browser, 1280, 1500)
    yield page
    context.close()
