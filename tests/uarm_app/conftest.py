"""Fixtures of the uArm app tests: a connected simulated arm and its bridge."""

from __future__ import annotations

import pytest

from mt_widgets.apps.uarm_bridge import UArmBridge
from mt_widgets.hardware import SwiftPro

from .helpers import sim_url


@pytest.fixture
def arm():
    with SwiftPro(sim_url(), timeout=1.0) as connected:
        yield connected


@pytest.fixture
def bridge(arm):
    return UArmBridge(arm)


# The canvas recorder of the kernel-free widget tests, reused rather than copied.
from widgets.conftest import recorder  # noqa: E402,F401
