"""Shared test settings."""

import os

# Notebooks run by nbval inherit this: the one documented switch that shortens long work.
os.environ.setdefault("MT_WIDGETS_FAST", "1")
