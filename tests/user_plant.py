"""Tutorial 09's own plant and skill, as a user writes them: a 2 kg point mass pushed on a table.

Kept as a plain module (no test in it) so the widget, protocol and browser tests teach the same
user skill the tutorial shows, and a protocol can point at this file with ``[skills] module``.
It defines no drawing and no robot name: the views must draw it from its end-effector alone.
"""

import numpy as np

from mt_widgets.core import ContinuousPlant, FunctionFeatures, PointTarget, Skill, SkillRegistry
from mt_widgets.core.workspace import Box


class PointMass(ContinuousPlant):
    state_names, units, action_units = ("x", "y", "vx", "vy"), "m", "N"
    view = Box((-2, 2), (-2, 2))
    mass = 2.0

    def end_effector(self, states):
        states = self.check_states("states", states)
        return states[..., :2], states[..., 2:]

    def sample_states(self, rng, n):
        return np.c_[rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(-1, 1, (n, 2))]

    def derivative(self, states, force):
        return np.concatenate([states[..., 2:], force / self.mass], axis=-1)


class Drifter(PointMass):
    """The same puck with no view of its own: framed from where its query states lie."""

    view = None


puck = PointMass()
features = FunctionFeatures(puck, lambda s: np.c_[s, np.ones(len(s))], names=("x", "y", "vx", "vy", "1"))
park = Skill("puck-park", "Park the puck at the origin", puck, features,
             theta=[[-2, 0, -2, 0, 0], [0, -2, 0, -2, 0]], start=[1.5, -1.0, 0.0, 0.0], target=PointTarget((0, 0)),
             description="A spring-damper pulling the puck to the origin: force = -2 r - 2 rdot.")

drifter = Drifter()
drift = Skill("puck-drift", "Park a puck framed by its states", drifter,
              FunctionFeatures(drifter, lambda s: np.c_[s, np.ones(len(s))], names=("x", "y", "vx", "vy", "1")),
              theta=[[-2, 0, -2, 0, 0.5], [0, -2, 0, -2, 0.5]], start=[1.0, 1.0, 0.0, 0.0],
              target=PointTarget((0.25, 0.25)))

#: A registry the user owns: the paper's skills plus theirs.
MY_SKILLS = SkillRegistry([park, drift])
