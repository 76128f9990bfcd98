"""Shared test settings."""

import os

# Notebooks run by nbval inherit this: the one documented switch that shortens long work.
os.environ.setdefault("MT_WIDGETS_FAST", "1")

# Pages that browser tests serve through Voila or JupyterLab: they are driven by a browser,
# not executed by nbval.
collect_ignore_glob = ["*/pages/*.ipynb", "*/pages/**/*.ipynb"]
