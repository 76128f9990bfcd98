"""The test run's settings for every path, a single notebook included (``pytest --nbval-lax tutorials/10_x.ipynb``).

It lives at the repository's root so that a run of one tutorial gets it too: without it, the
capstone (tutorial 10) would run as a student's session, enrol "me" in ~/mt-widgets-lessons and
wait for a person. The test-suite's own settings and marks are in tests/conftest.py.
"""

import nbval.kernel
import pytest
import zmq
from jupyter_client.manager import KernelManager

from tests.notebook_parameters import ParametersError, inject


def _start_kernel_keeping_every_message(startup_timeout=60, kernel_name="python", **kwargs):
    """nbval's ``start_new_kernel`` (nbval/kernel.py), with a client whose receive queues are unbounded.

    nbval reads a cell's iopub messages only once the cell has finished, and ZeroMQ keeps at most
    1000 unread messages at each end by default (high-water marks), then drops the rest: a cell
    whose widgets send more (tutorial 10's synthetic novice: about 4300 widget messages) lost its
    final idle status, and nbval failed it with "Timeout of 5 seconds exceeded waiting for output".
    With no receive limit, ZeroMQ's I/O thread drains the kernel's socket into memory as the
    messages come (as JupyterLab's server does), and the kernel's own limit is never reached.
    The context goes to ``client()`` because a client makes its own otherwise (a default set on
    ``KernelClient`` does not reach ``BlockingKernelClient``); tests/data/many_iopub_messages.ipynb
    fails without this.
    """
    manager = KernelManager(kernel_name=kernel_name, kernel_spec_manager=nbval.kernel.NbvalKernelspecManager())
    manager.start_kernel(**kwargs)
    context = zmq.Context()
    context.setsockopt(zmq.RCVHWM, 0)
    client = manager.client(context=context)
    client.start_channels()
    try:
        client.wait_for_ready(timeout=startup_timeout)
    except RuntimeError:
        client.stop_channels()
        manager.shutdown_kernel()
        context.term()
        raise
    return manager, client


nbval.kernel.start_new_kernel = _start_kernel_keeping_every_message


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Each selected notebook's cell tagged ``parameters`` gets the test run's values
    (tests/notebook_parameters.py): the one switch that shortens notebook work under test. After
    the selection (``trylast``), so only the notebooks that will run get fresh scratch folders."""
    try:
        inject(items, config.rootpath)
    except ParametersError as error:
        raise pytest.UsageError(str(error)) from error
