"""The core shape (``pip install mt-widgets``): the README's science in five lines, and nothing more installed.

Run by tests/install/test_shapes.py with the shape's own Python, outside the repository."""

import importlib.util

from mt_widgets import SKILLS, RidgeLearner, optimal_actions, teaching_risk

skill = SKILLS["sim-point"]                      # also "sim-line", "uarm-point", "uarm-line"
Phi = skill.features(skill.query_states(seed=0))  # 5 well-conditioned query states -> (5, 5) features
U_bar = optimal_actions(Phi, skill.theta, lam=0.01)
risk = teaching_risk(RidgeLearner(lam=0.01).fit(Phi, U_bar).theta, skill.theta)
trajectory = skill.reproduce(skill.theta)         # 10 s of RK4 at 1 kHz, with a `diverged` flag

assert risk < 1e-9, f"the optimal demonstration teaches exactly, got a risk of {risk}"
assert not trajectory.diverged
# The core is numpy and numba: none of the extras' libraries came with it.
extras = [name for name in ("scipy", "pandas", "matplotlib", "ipywidgets", "serial") if importlib.util.find_spec(name)]
assert extras == [], f"the core install brought {extras}"
print(f"core: risk {risk:.1e}")
