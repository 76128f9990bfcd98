"""The install tier's distributions and the lab's venv, built once a run and shared by its tests:
tests/install/test_shapes.py checks them, tests/install/test_getting_started_from_wheel.py runs the
getting-started pages in the same venv (no second build, no second install)."""

from __future__ import annotations

import pytest

from .shapes import build_distributions, make_shape


@pytest.fixture(scope="session")
def distributions(tmp_path_factory):
    """(sdist, wheel) of the repository, built once a run."""
    return build_distributions(tmp_path_factory.mktemp("dist"))


@pytest.fixture(scope="session")
def lab_venv(distributions, tmp_path_factory):
    """The Python of a fresh venv holding the wheel with its ``lab`` extra, as ``pip install "mt-widgets[lab]"``."""
    _, wheel = distributions
    return make_shape(wheel, "lab", tmp_path_factory.mktemp("lab") / "venv")
