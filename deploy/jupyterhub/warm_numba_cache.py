"""Fills a numba cache folder with mt-widgets' compiled kernels, for the hub to copy to students.

    NUMBA_CACHE_DIR=/srv/mt-hub/numba-template python deploy/jupyterhub/warm_numba_cache.py

Run it once after installing (and after every upgrade) with the same Python and the same
installation the students use: numba keys its cache by the source file's path and time stamp,
so the copy is valid for every student of that installation and recompiles by itself when not.
"""

import os
import sys

import numpy as np

from mt_widgets import SKILLS, RidgeLearner

if not os.environ.get("NUMBA_CACHE_DIR"):
    sys.exit("NUMBA_CACHE_DIR: expected the folder to fill, got nothing")
for skill in SKILLS.values():
    states = skill.query_states(seed=0)
    theta_hat = RidgeLearner().fit(skill.features(states), skill.target_actions(states))
    skill.reproduce(theta_hat)
    skill.reproduce(np.stack([theta_hat, skill.theta]))
print("numba cache ready in", os.environ["NUMBA_CACHE_DIR"])
