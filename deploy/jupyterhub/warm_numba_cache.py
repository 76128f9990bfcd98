"""Fills a numba cache folder with mt-widgets' compiled kernels, for the hub to copy to students.

    NUMBA_CACHE_DIR=/srv/mt-hub/numba-template python deploy/jupyterhub/warm_numba_cache.py

Run it once after installing (and after every upgrade) with the same Python and the same
installation the students use: numba keys its cache by the source file's path and time stamp,
so the copy is valid for every student of that installation and recompiles by itself when not.
It runs what a student's episode runs, for every paper skill: numba compiles one version per
argument type (a skill's read-only Theta and a learnt, writable one differ), so warming with
anything less leaves compiles for the students' first episode.
"""

import os
import sys

from mt_widgets import SKILLS, TeachingEpisode
from mt_widgets.core.skills import PAPER_SKILL_KEYS
from mt_widgets.widgets import EpisodeWidget

if not os.environ.get("NUMBA_CACHE_DIR"):
    sys.exit("NUMBA_CACHE_DIR: expected the folder to fill, got nothing")
for key in SKILLS:
    if key not in PAPER_SKILL_KEYS:
        # The UR5's skills have no planar widget: warm their episode and reproduction kernels.
        episode = TeachingEpisode(SKILLS[key], seed=0)
        for action in episode.optimal_actions:
            episode.demonstrate(action + 0.01)
        assert not episode.reproduction.diverged
        continue
    for guidance in (True, False):
        episode = EpisodeWidget(key, seed=0, guidance=guidance)
        for action in episode.optimal:
            episode.demonstrate(action + 0.1)
            if episode.phase == "guidance":
                episode.next()
        SKILLS[key].reproduce(SKILLS[key].theta)
print("numba cache ready in", os.environ["NUMBA_CACHE_DIR"])
