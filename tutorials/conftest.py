"""Running a tutorial under pytest (``pytest --nbval-lax tutorials/NN_x.ipynb``) is running it under test.

The switch that shortens notebook work under test, MT_WIDGETS_FAST=1 (``mt_widgets/core/fast_mode.py``),
is set by ``tests/conftest.py`` for the whole suite; a run of the tutorials alone does not load that
file. Without the switch the capstone (10) would run as a student's session: enrol "me" in
~/mt-widgets-lessons/capstone and wait for a person. Kernels that nbval starts inherit this.
"""

import os

os.environ.setdefault("MT_WIDGETS_FAST", "1")
