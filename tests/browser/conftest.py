"""Real-browser fixtures of the widget tests: Voila and JupyterLab serving the test pages.

Chromium, the servers' process groups and local-only pages come from ``tests/browser_support.py``
and the ``browser`` fixture of ``tests/conftest.py``.

Each server runs in its own process group with its own JUPYTER_* directories in a
temporary folder and is ended (the whole group) at teardown. Pages may only talk to
127.0.0.1: everything else is aborted (Voila asks a CDN for a font). A missing Chromium or
Playwright fails the tests, never skips them (docs/browser-testing.md).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from browser_support import BIN, IPC_KERNELS, Server, free_port, local_page, voila

PAGES = Path(__file__).parent / "pages"
DEMO = Path(__file__).resolve().parents[2] / "notebooks" / "demo.ipynb"      # the visitors' page, served as is
USER_PLANT = Path(__file__).resolve().parents[1] / "user_plant.py"             # tutorial 09's plant, for a page


def _copy_pages(root: Path) -> None:
    notebooks = root / "notebooks"
    notebooks.mkdir(parents=True, exist_ok=True)
    for page in [*PAGES.glob("*.ipynb"), DEMO, USER_PLANT]:
        shutil.copy(page, notebooks / page.name)


@pytest.fixture
def page(browser):
    """A fresh page that may only reach 127.0.0.1."""
    context, page = local_page(browser)
    yield page
    context.close()


@pytest.fixture(scope="session")
def voila_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("voila")
    _copy_pages(root)
    # Preheated kernels: Voila runs each page's notebook before it is asked for, so opening a
    # page takes about 3 s instead of 5-6 s here. The widgets must then draw into views that
    # attach after the kernel ran, which is the ipycanvas #322 case these tests are about.
    server = voila(root, "--preheat_kernel=True", "--pool_size=1")
    yield server
    server.stop()


@pytest.fixture(scope="session")
def lab_server(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    _copy_pages(root)
    port, token = free_port(), "mt-widgets-test"
    server = Server([str(BIN / "jupyter"), "lab", "--no-browser", "--ip=127.0.0.1", f"--port={port}",
                     "--port-retries=0", "--allow-root", IPC_KERNELS, f"--IdentityProvider.token={token}",
                     f"--ServerApp.root_dir={root / 'notebooks'}", "--LabApp.extension_manager=readonly"],
                    port, root, "lab", f"http://127.0.0.1:{port}", token)
    yield server
    server.stop()


@pytest.fixture
def lab_page(page, lab_server):
    """A page for JupyterLab; every kernel session it started is ended afterwards."""
    yield page
    # Kernels outlive pages: end every session this test started.
    api = page.context.request
    headers = {"Authorization": f"token {lab_server.token}"}
    for session in api.get(lab_server.url("/api/sessions"), headers=headers).json():
        api.delete(lab_server.url(f"/api/sessions/{session['id']}"), headers=headers)
