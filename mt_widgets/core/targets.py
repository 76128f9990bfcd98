"""Targets: where a skill drives the end-effector, as objects that say how far, how drawn, how named.

Every consumer (the views, the synthetic teachers, the figures) asks a target through these
methods and never tells targets apart by their attributes:

- ``distance(positions)``: how far positions are from the target;
- ``nearest(positions)``: the target's nearest points (so ``nearest(p) - p`` is the way to it);
- ``shape(view)``: a ``TargetShape`` (a point, or a segment clipped to the view) to draw;
- ``dimension``: 0 for a point, 1 for a line;
- ``noun`` and ``describe(color, label)``: the target in words, e.g. "the orange point marked goal".

A user's target subclasses ``Target`` and implements the same four.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .drawing import TargetShape, clip_line
from .validation import as_float_array
from .workspace import Box


class Target:
    """Base class of skill targets (what the end-effector should reach)."""

    #: What the target is, in a word or two ("point", "vertical line").
    noun: str = "target"
    #: Its geometric dimension: 0 for a point (one place to reach), 1 for a line (anywhere on it).
    dimension: int = 0

    def nearest(self, positions) -> np.ndarray:
        """The target's nearest point to each position: (..., 2) -> (..., 2)."""
        raise NotImplementedError

    def distance(self, positions) -> np.ndarray:
        """Distance from each position (..., 2) to the target -> (...)."""
        positions = as_float_array("positions", positions, shape=(2,))
        return np.linalg.norm(self.nearest(positions) - positions, axis=-1)

    def shape(self, view: Box) -> TargetShape:
        """How the target is drawn inside the world rectangle ``view``."""
        raise NotImplementedError

    def describe(self, color: str | None = None, label: str | None = None) -> str:
        """The target in words, as a person sees it: "the orange point marked goal".

        Args:
            color: the colour's name as drawn (from the theme in use), or None.
            label: the word written beside it on the canvas, or None.
        """
        words = "the " + (f"{color} " if color else "") + self.noun
        return words + (f" marked {label}" if label else "")


@dataclass(frozen=True)
class PointTarget(Target):
    """The skill drives the end-effector to ``point``."""

    point: tuple[float, float]
    noun = "point"
    dimension = 0

    def __post_init__(self):
        point = as_float_array("point", self.point, ndim=1, shape=(2,))
        object.__setattr__(self, "point", (float(point[0]), float(point[1])))

    def nearest(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(2,))
        return np.broadcast_to(np.asarray(self.point), positions.shape).copy()

    def shape(self, view: Box) -> TargetShape:
        point = np.asarray(self.point, dtype=float)
        return TargetShape(point[None, :], point)


@dataclass(frozen=True)
class LineTarget(Target):
    """The skill drives the end-effector onto the line through ``point`` along ``direction``."""

    point: tuple[float, float]
    direction: tuple[float, float]
    dimension = 1

    def __post_init__(self):
        point = as_float_array("point", self.point, ndim=1, shape=(2,))
        direction = as_float_array("direction", self.direction, ndim=1, shape=(2,))
        norm = float(np.hypot(*direction))
        if norm == 0:
            raise ValueError("direction: expected a non-zero vector, got (0, 0)")
        object.__setattr__(self, "point", (float(point[0]), float(point[1])))
        object.__setattr__(self, "direction", (float(direction[0] / norm), float(direction[1] / norm)))

    @property
    def noun(self) -> str:
        dx, dy = self.direction
        if abs(dx) < 1e-12:
            return "vertical line"
        if abs(dy) < 1e-12:
            return "horizontal line"
        return "line"

    def nearest(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(2,))
        point, along = np.asarray(self.point), np.asarray(self.direction)
        return point + ((positions - point) @ along)[..., None] * along

    def shape(self, view: Box) -> TargetShape:
        segment = clip_line(self.point, self.direction, view)
        if segment is None:
            # The line misses the view: drawn as nothing but a label at its point.
            point = np.asarray(self.point, dtype=float)
            return TargetShape(np.empty((0, 2)), point)
        # The label sits where the line passes closest to the view's centre: in view, and away
        # from the edges and the base a plant may have at a corner.
        centre = np.array([sum(view.xlim) / 2.0, sum(view.ylim) / 2.0])
        return TargetShape(segment, self.nearest(centre))


@dataclass(frozen=True)
class SpacePointTarget(Target):
    """The skill drives an arm's tool to ``point`` in space (3,), e.g. a part on a table."""

    point: tuple[float, float, float]
    noun = "point"
    dimension = 0

    def __post_init__(self):
        point = as_float_array("point", self.point, ndim=1, shape=(3,))
        object.__setattr__(self, "point", tuple(float(v) for v in point))

    def nearest(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(3,))
        return np.broadcast_to(np.asarray(self.point), positions.shape).copy()

    def distance(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(3,))
        return np.linalg.norm(self.nearest(positions) - positions, axis=-1)

    def shape(self, view=None) -> TargetShape:
        """The point itself (1, 3); a view projects it (``SpaceDrawing``), so ``view`` is not needed."""
        point = np.asarray(self.point, dtype=float)
        return TargetShape(point[None, :], point)


@dataclass(frozen=True)
class ConveyorTarget(Target):
    """The skill follows a part riding a conveyor: at phase s (m) the part is at ``origin + s * direction``.

    The target moves with the state's conveyor phase, so where it is depends on the state
    (``at(phases)``); ``nearest`` gives the closest point of the belt's line, and ``shape`` the
    stretch of belt the taught phases and a reproduction cover.
    """

    origin: tuple[float, float, float]
    direction: tuple[float, float, float]
    phase_range: tuple[float, float]
    noun = "part on the conveyor"
    dimension = 0

    def __post_init__(self):
        origin = as_float_array("origin", self.origin, ndim=1, shape=(3,))
        direction = as_float_array("direction", self.direction, ndim=1, shape=(3,))
        norm = float(np.linalg.norm(direction))
        if norm == 0:
            raise ValueError("direction: expected a non-zero vector, got (0, 0, 0)")
        phases = as_float_array("phase_range", self.phase_range, ndim=1, shape=(2,))
        object.__setattr__(self, "origin", tuple(float(v) for v in origin))
        object.__setattr__(self, "direction", tuple(float(v) / norm for v in direction))
        object.__setattr__(self, "phase_range", (float(phases[0]), float(phases[1])))

    def at(self, phases) -> np.ndarray:
        """Where the part is at conveyor phases (...) m -> (..., 3) m."""
        phases = as_float_array("phases", phases)
        return np.asarray(self.origin) + phases[..., None] * np.asarray(self.direction)

    def nearest(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(3,))
        origin, along = np.asarray(self.origin), np.asarray(self.direction)
        return origin + ((positions - origin) @ along)[..., None] * along

    def distance(self, positions) -> np.ndarray:
        positions = as_float_array("positions", positions, shape=(3,))
        return np.linalg.norm(self.nearest(positions) - positions, axis=-1)

    def shape(self, view=None) -> TargetShape:
        """The belt's stretch (2, 3) from the first taught phase to 0.5 m past the last, labelled at its start."""
        low, high = self.phase_range
        ends = self.at(np.array([low, high + 0.5]))
        return TargetShape(ends, ends[0])
