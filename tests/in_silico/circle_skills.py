"""A user's own target, a circle, on the simulated arm: a target the package has never seen.

Kept as a plain module (no test in it) so a protocol can point at it with ``[skills] module``.
"""

from dataclasses import replace

import numpy as np

from mt_widgets.core import SKILLS, SkillRegistry, Target, TargetShape
from mt_widgets.core.validation import as_float_array


class CircleTarget(Target):
    """Anywhere on the circle of ``radius`` around ``centre``."""

    noun = "circle"
    dimension = 1

    def __init__(self, centre, radius):
        self.centre, self.radius = np.asarray(centre, dtype=float), float(radius)

    def nearest(self, positions):
        positions = as_float_array("positions", positions, shape=(2,))
        away = positions - self.centre
        length = np.linalg.norm(away, axis=-1, keepdims=True)
        # At the centre every point of the circle is nearest: take the one to the right.
        away = np.where(length > 0, away / np.where(length > 0, length, 1.0), np.array([1.0, 0.0]))
        return self.centre + self.radius * away

    def shape(self, view):
        angles = np.linspace(0.0, 2 * np.pi, 73)
        points = self.centre + self.radius * np.c_[np.cos(angles), np.sin(angles)]
        return TargetShape(points, self.centre + [self.radius, 0.0])


CIRCLE = CircleTarget((0.8, 1.2), 0.3)
ring = replace(SKILLS["sim-point"], key="sim-ring", title="Reach the ring around (0.8, 1.2) m", target=CIRCLE)

MY_SKILLS = SkillRegistry([ring])
