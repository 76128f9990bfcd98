"""Shared test settings: the tiers' marks, the browser. A notebook's shortening under test is the
root conftest.py's (tests/notebook_parameters.py)."""

# Pages that browser tests serve through Voila or JupyterLab: they are driven by a browser,
# not executed by nbval.
collect_ignore_glob = ["*/pages/*.ipynb", "*/pages/**/*.ipynb"]


import sys  # noqa: E402

import pytest  # noqa: E402

from browser_support import CHROMIUM, CHROMIUM_ARGS, RUNNING, artifact_path  # noqa: E402
from tiers import DOCS_TESTS, HUB_TESTS, LINT_TESTS  # noqa: E402


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
    """The tiers' marks (tests/tiers.py): ``lint`` for tests/test_lint.py; ``browser`` for a test
    that drives Chromium (it takes the ``browser`` fixture, or lives in a folder named
    ``browser*``); ``notebook`` (and ``slow``) for every notebook cell run by nbval; ``hub`` for
    the tests that start a JupyterHub (tests/course/test_hub.py). ``slow`` is otherwise written
    on the slow tests themselves (``@pytest.mark.slow``)."""
    for item in items:
        try:
            relative = item.path.relative_to(config.rootpath)
        except ValueError:  # a path outside the repository (a temporary folder)
            relative = item.path
        folders = relative.parts[:-1]
        if "browser" in getattr(item, "fixturenames", ()) or any(f.startswith("browser") for f in folders):
            item.add_marker(pytest.mark.browser)
        if item.path.suffix == ".ipynb":
            item.add_marker(pytest.mark.notebook)
            item.add_marker(pytest.mark.slow)
        if relative.as_posix() in LINT_TESTS:
            item.add_marker(pytest.mark.lint)
        if relative.as_posix() in HUB_TESTS:
            item.add_marker(pytest.mark.hub)
        if relative.as_posix() in DOCS_TESTS:
            item.add_marker(pytest.mark.docs)


@pytest.fixture
def artifacts(request):
    """Where to keep screenshots: ``artifacts(step)`` -> test-artifacts/<test name>-<step>.png."""
    return lambda step: artifact_path(request.node.name, step)


@pytest.fixture(autouse=True)
def fresh_animation_queue(monkeypatch):
    """Every test starts as a fresh page: the widgets' estimate of when the browser's canvas queue
    is free (``mt_widgets.widgets.animation._Queue.free_at``, process-global) starts empty, not
    behind what earlier tests' animations sent (a whole study app's pushes it minutes ahead).
    Only once the widgets are imported: a core test does not import them for this."""
    animation = sys.modules.get("mt_widgets.widgets.animation")
    if animation is not None:
        monkeypatch.setattr(animation._Queue, "free_at", 0.0)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """A failing test's report ends with the last lines of every test server still running: what
    the server saw is often the cause (a kernel that died, a cell's error)."""
    outcome = yield
    report = outcome.get_result()
    if report.failed and call.when == "call":
        for server in RUNNING:
            text = server.log.read_text(errors="replace") if server.log.exists() else "(no log)"
            report.sections.append((f"{server.log} (its end)", text[-4000:]))
