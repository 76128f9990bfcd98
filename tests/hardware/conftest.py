"""Fixtures for the hardware tests: connected simulated arms of both firmware generations."""

from __future__ import annotations

import pytest

from mt_widgets.hardware import SwiftPro

from .helpers import sim_url


@pytest.fixture
def arm4():
    with SwiftPro(sim_url(firmware=4), timeout=1.0) as arm:
        yield arm


@pytest.fixture
def arm3():
    with SwiftPro(sim_url(firmware=3), timeout=1.0) as arm:
        yield arm
