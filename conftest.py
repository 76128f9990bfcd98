"""The test run's settings for every path, a single notebook included (``pytest --nbval-lax tutorials/10_x.ipynb``).

It lives at the repository's root so that a run of one tutorial gets it too: without it, the
capstone (tutorial 10) would run as a student's session, enrol "me" in ~/mt-widgets-lessons and
wait for a person. The test-suite's own settings and marks are in tests/conftest.py.
"""

import pytest

from tests.notebook_parameters import inject


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Each selected notebook's cell tagged ``parameters`` gets the test run's values
    (tests/notebook_parameters.py): the one switch that shortens notebook work under test. After
    the selection (``trylast``), so only the notebooks that will run get fresh scratch folders."""
    inject(items, config.rootpath)
