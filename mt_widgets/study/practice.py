"""Neutral practice skills: something to draw on before the study that no phase measures.

The paper gives "two minutes of unstructured practice time" before P1. Practising a measured
skill with its goal and its reproduction would train it before its baseline, so the shipped
protocols practise these instead: the same robot and the same drawing, a goal no phase uses
(a point on the other side of the workspace), and no guidance.
"""

from __future__ import annotations

import numpy as np

from mt_widgets.core import SKILLS, PointTarget, Skill
from mt_widgets.core.targets import SpacePointTarget


def _practice_skills() -> dict[str, Skill]:
    sim, uarm, ur5, so101 = SKILLS["sim-point"], SKILLS["uarm-point"], SKILLS["ur5-reach"], SKILLS["so101-reach"]
    # The simulated arm's practice goal mirrors skill 1's point across the vertical axis.
    sim_goal = (-0.8, 1.2)
    # The uArm's practice goal lies right of skill 1's start, inside the workspace (r 26.6 cm,
    # 20 degrees of yaw), and its start left of it, so the practice reproduction crosses the
    # workspace without meeting skill 1's point (23, 11) cm or the line r1 = 2 r2.
    uarm_goal, uarm_start = (25.0, -9.0), np.array([17.0, 5.0])
    # The UR5's practice goal hangs in the air on the other side of the base from the part
    # (0.55, -0.10, 0.10) m and high above the fixture and the conveyor: no phase's goal.
    ur5_goal = np.array([0.30, 0.30, 0.45])
    # The SO-101's practice goal is high above the table on the other side from the part
    # (0.22, -0.08, 0.06) m and above the fixture (0.18, 0.09, 0.08) m: no phase's goal.
    so101_goal = np.array([0.16, 0.10, 0.14])
    return {skill.key: skill for skill in (
        Skill("sim-practice", "Practice: reach the point (-0.8, 1.2) m", sim.plant, sim.feature_map,
              [[-1, 0, -1, 0, sim_goal[0]], [0, -1, 0, -1, sim_goal[1]]], sim.start, PointTarget(sim_goal),
              "A practice goal that no part of the study uses.", max_condition=sim.max_condition),
        Skill("uarm-practice", "Practice: reach the point (25, -9) cm", uarm.plant, uarm.feature_map,
              [[-0.2, 0, 0.2 * uarm_goal[0]], [0, -0.2, 0.2 * uarm_goal[1]]], uarm_start, PointTarget(uarm_goal),
              "A practice goal that no part of the study uses.", max_condition=uarm.max_condition),
        Skill("ur5-practice", "Practice: reach the point (0.30, 0.30, 0.45) m", ur5.plant, ur5.feature_map,
              np.hstack([-0.8 * np.eye(3), 0.8 * ur5_goal[:, None]]) + 0.0, ur5.start, SpacePointTarget(ur5_goal),
              "A practice goal that no part of the study uses.", max_condition=ur5.max_condition),
        Skill("so101-practice", "Practice: reach the point (0.16, 0.10, 0.14) m", so101.plant, so101.feature_map,
              np.hstack([-0.8 * np.eye(3), 0.8 * so101_goal[:, None]]) + 0.0, so101.start,
              SpacePointTarget(so101_goal), "A practice goal that no part of the study uses.",
              max_condition=so101.max_condition),
    )}


#: Practice skills by key ("sim-practice", "uarm-practice", "ur5-practice", "so101-practice"); protocols
#: name them like skills.
PRACTICE_SKILLS: dict[str, Skill] = _practice_skills()
