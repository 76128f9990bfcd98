"""The test run's settings for every path, a single notebook included (``pytest --nbval-lax tutorials/10_x.ipynb``).

It lives at the repository's root so that a run of one tutorial gets it too: without it, the
capstone (tutorial 10) would run as a student's session, enrol "me" in ~/mt-widgets-lessons and
wait for a person. The test-suite's own settings and marks are in tests/conftest.py.
"""

import pytest
import zmq
from jupyter_client.client import KernelClient

from tests.notebook_parameters import inject


def _unbounded_receive_context(self) -> zmq.Context:
    """nbval reads a cell's iopub messages only once the cell has finished, and ZeroMQ keeps at most
    1000 unread messages at each end by default (high-water marks), then drops the rest: a cell whose
    widgets send more (tutorial 10's synthetic novice: about 4300 widget messages) lost its final
    idle status, and nbval failed it with "Timeout of 5 seconds exceeded waiting for output". An
    unbounded receive queue on the test run's side keeps every message."""
    self._created_context = True
    context = zmq.Context()
    context.setsockopt(zmq.RCVHWM, 0)
    return context


KernelClient._context_default = _unbounded_receive_context


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Each selected notebook's cell tagged ``parameters`` gets the test run's values
    (tests/notebook_parameters.py): the one switch that shortens notebook work under test. After
    the selection (``trylast``), so only the notebooks that will run get fresh scratch folders."""
    inject(items, config.rootpath)
