"""Shared test settings."""

import os

# Notebooks run by nbval inherit this: the one documented switch that shortens long work.
os.environ.setdefault("MT_WIDGETS_FAST", "1")

# Pages that browser tests serve through Voila or JupyterLab: they are driven by a browser,
# not executed by nbval.
collect_ignore_glob = ["*/pages/*.ipynb", "*/pages/**/*.ipynb"]


import pytest  # noqa: E402

from browser_support import CHROMIUM, CHROMIUM_ARGS, artifact_path  # noqa: E402
from tiers import SLOW_TESTS  # noqa: E402


@pytest.fixture(scope="session")
def browser():
    """Debian's Chromium through Playwright, one for the whole run; fails when either is missing."""
    from pathlib import Path

    if not Path(CHROMIUM).exists():
        pytest.fail(f"Chromium not found at {CHROMIUM}: install it with `apt-get install -y chromium` "
                    f"(or set MT_WIDGETS_CHROMIUM)", pytrace=False)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError as error:
        pytest.fail(f"playwright is not installed ({error}): pip install 'mt-widgets[test]'", pytrace=False)
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


def pytest_collection_modifyitems(config, items):
    """Marks for the fast tier (``-m "not browser and not slow"``, scripts/test-fast.sh): every
    test that drives Chromium is ``browser`` (it takes the ``browser`` fixture, or lives in a
    folder named ``browser*``), every notebook run by nbval and every test of ``SLOW_TESTS`` is
    ``slow``."""
    for item in items:
        try:
            folders = item.path.relative_to(config.rootpath).parts[:-1]
        except ValueError:  # a path outside the repository (a temporary folder)
            folders = ()
        if "browser" in getattr(item, "fixturenames", ()) or any(f.startswith("browser") for f in folders):
            item.add_marker(pytest.mark.browser)
        if item.path.suffix == ".ipynb" or item.nodeid.startswith(SLOW_TESTS):
            item.add_marker(pytest.mark.slow)


@pytest.fixture
def artifacts(request):
    """Where to keep screenshots: ``artifacts(step)`` -> test-artifacts/<test name>-<step>.png."""
    return lambda step: artifact_path(request.node.name, step)
