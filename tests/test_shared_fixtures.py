"""The fixtures every test gets (tests/conftest.py): a fresh estimate of the browser's canvas queue."""

import time

import pytest

from mt_widgets.widgets import animation


@pytest.mark.parametrize("run", [1, 2])
def test_each_test_starts_with_the_canvas_queue_free(run):
    # The second run fails if the first one's ten minutes of queued playback leaked into it.
    assert animation._Queue.drained_in() == 0.0
    assert animation._Queue.add(600.0) >= time.monotonic() + 599.0
