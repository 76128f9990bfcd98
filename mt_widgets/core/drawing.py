"""What a view needs to draw a plant and a target: pure data in world units, no widget library.

A plant in the plane says ``PlantDrawing``; a plant in space (the UR5) says ``SpaceDrawing``:
three views (top, side, perspective), each a ``ViewProjection`` from world points to its plane,
and the same ``PoseSketch`` with 3-D points.

A view (a canvas, a matplotlib figure, the uArm's screen) never asks which robot it draws.
It asks the plant for

- ``plant.drawing()``: a ``PlantDrawing``, what stays fixed (the view extent, units, the base,
  the workspace outline, how links and the end-effector look, arrow scales), and
- ``plant.sketch(states)``: a ``PoseSketch``, what changes with the state (the kinematic chain
  from the base to the end-effector, and the end-effector's velocity),

and it asks the skill's target for ``target.shape(view)``: a ``TargetShape``. Any plant that
only reports an end-effector position gets a generic drawing: a dot at the end-effector, its
velocity, and a view that frames where its query states lie.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .validation import as_float_array, as_positive
from .workspace import Box, Cuboid

#: How links are drawn: "rigid" (thick links with joints: an arm seen from the side), "reach" (a
#: faint dashed line from the base to the end-effector: which way a desktop arm seen from above
#: reaches), or "none" (only the end-effector: a point mass, a mobile robot).
LINK_KINDS = ("rigid", "reach", "none")

#: How the end-effector is marked: "hand" (a coloured, outlined disc at the tip of an arm) or
#: "dot" (a dark dot: the state itself, as on the paper's uArm screen).
MARKER_KINDS = ("hand", "dot")


@dataclass(frozen=True)
class PlantDrawing:
    """What stays fixed when a plant is drawn.

    Attributes:
        view: the world rectangle to show (``xlim``, ``ylim`` in ``units``).
        units: length unit of positions ("m", "cm").
        action_units: unit of an action component ("N", "cm").
        links: one of ``LINK_KINDS``.
        marker: one of ``MARKER_KINDS``.
        base: (2,) the fixed base in world units, or None (nothing is fixed).
        outline: closed polylines (K, 2) in world units around where the plant can be
            (e.g. the uArm's reachable sector); empty for none.
        action_length: world units of arrow per action unit, or None to let the skill choose
            one from its typical action (``Skill.drawing``).
        velocity_length: world units of arrow per unit of velocity (units per second).
        has_velocity: whether a state has a velocity worth drawing (a kinematic plant such as
            the uArm's is at rest at every state).
    """

    view: Box
    units: str
    action_units: str
    links: str = "none"
    marker: str = "dot"
    base: tuple[float, float] | None = None
    outline: tuple[np.ndarray, ...] = field(default_factory=tuple)
    action_length: float | None = None
    velocity_length: float = 0.3
    has_velocity: bool = True

    def __post_init__(self):
        if not isinstance(self.view, Box):
            raise TypeError(f"view: expected a Box, got {type(self.view).__name__}")
        if self.links not in LINK_KINDS:
            raise ValueError(f"links: expected one of {LINK_KINDS}, got {self.links!r}")
        if self.marker not in MARKER_KINDS:
            raise ValueError(f"marker: expected one of {MARKER_KINDS}, got {self.marker!r}")
        if self.base is not None:
            base = as_float_array("base", self.base, ndim=1, shape=(2,))
            object.__setattr__(self, "base", (float(base[0]), float(base[1])))
        outline = tuple(as_float_array("outline", line, ndim=2, shape=(None, 2)) for line in self.outline)
        object.__setattr__(self, "outline", outline)
        if self.action_length is not None:
            object.__setattr__(self, "action_length", as_positive("action_length", self.action_length))
        object.__setattr__(self, "velocity_length", as_positive("velocity_length", self.velocity_length))
        if not isinstance(self.has_velocity, bool):
            raise TypeError(f"has_velocity: expected True or False, got {self.has_velocity!r}")


@dataclass(frozen=True)
class PoseSketch:
    """What to draw of a plant in some states (any leading axes ``...``).

    Attributes:
        chain: (..., P, 2) points from the base through the joints to the end-effector, in world
            units; P = 1 when only the end-effector is known. (..., P, 3) for a plant in space.
        velocity: (..., 2) the end-effector's velocity in units per second ((..., 3) in space).
    """

    chain: np.ndarray
    velocity: np.ndarray

    @property
    def end_effector(self) -> np.ndarray:
        """(..., 2) the last point of the chain."""
        return self.chain[..., -1, :]

    @property
    def joints(self) -> np.ndarray:
        """(..., P - 2, 2) the joints between the base and the end-effector (none for P <= 2)."""
        return self.chain[..., 1:-1, :]


@dataclass(frozen=True)
class TargetShape:
    """How a target looks, in world units.

    Attributes:
        points: (K, 2); K = 1 is a point (drawn as a dot), K >= 2 a polyline (drawn as a line).
        label_at: (2,) where a label beside the target goes.
    """

    points: np.ndarray
    label_at: np.ndarray

    @property
    def is_point(self) -> bool:
        return len(self.points) == 1


def framing_box(points, pad: float = 0.15) -> Box:
    """A square-ish ``Box`` around world points (N, 2), padded by ``pad`` of its span on each side.

    Used for the generic drawing: a plant that says nothing about its view is framed around
    where its query states put the end-effector.
    """
    points = as_float_array("points", points, ndim=2, shape=(None, 2))
    if len(points) == 0:
        raise ValueError("points: expected at least one point, got none")
    low, high = points.min(axis=0), points.max(axis=0)
    span = float(max(np.max(high - low), 1e-6))
    centre = (low + high) / 2.0
    half = span * (0.5 + pad)
    return Box((float(centre[0] - half), float(centre[0] + half)), (float(centre[1] - half), float(centre[1] + half)))


def clip_line(point, direction, box: Box) -> np.ndarray | None:
    """The segment (2, 2) of the infinite line through ``point`` along ``direction`` inside ``box``.

    Returns None when the line misses the box (Liang-Barsky clipping).
    """
    p = as_float_array("point", point, ndim=1, shape=(2,))
    d = as_float_array("direction", direction, ndim=1, shape=(2,))
    t_low, t_high = -np.inf, np.inf
    for axis, (low, high) in enumerate((box.xlim, box.ylim)):
        if abs(d[axis]) < 1e-15:
            if not low <= p[axis] <= high:
                return None
            continue
        a, b = (low - p[axis]) / d[axis], (high - p[axis]) / d[axis]
        t_low, t_high = max(t_low, min(a, b)), min(t_high, max(a, b))
    if t_low > t_high:
        return None
    return np.array([p + t_low * d, p + t_high * d])


# -- plants in space -----------------------------------------------------------------------------------

#: The views of a plant in space: two orthographic ones a person draws in (``top``: looking down
#: -z, horizontal components; ``side``: looking along +y, x and height), and a ``perspective``
#: one to orbit.
SPACE_VIEWS = ("top", "side", "perspective")


@dataclass(frozen=True)
class ViewProjection:
    """How one view maps world points (..., 3) to its plane (..., 2), in world units.

    Attributes:
        name: one of ``SPACE_VIEWS``.
        azimuth_deg, elevation_deg: the perspective camera's direction (degrees); the
            orthographic views ignore them.
        distance: the perspective camera's distance from the bounds' centre, in world units.
        centre: (3,) the point the perspective camera looks at.
    """

    name: str
    azimuth_deg: float = 35.0
    elevation_deg: float = 25.0
    distance: float = 3.0
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        if self.name not in SPACE_VIEWS:
            raise ValueError(f"name: expected one of {SPACE_VIEWS}, got {self.name!r}")
        object.__setattr__(self, "distance", as_positive("distance", self.distance))
        centre = as_float_array("centre", self.centre, ndim=1, shape=(3,))
        object.__setattr__(self, "centre", tuple(float(v) for v in centre))

    def camera(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The perspective camera's right, up and forward unit vectors (3,) in the world."""
        azimuth, elevation = np.deg2rad(self.azimuth_deg), np.deg2rad(self.elevation_deg)
        forward = -np.array([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                             np.sin(elevation)])
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        return right, np.cross(right, forward), forward

    def project(self, points) -> np.ndarray:
        """World points (..., 3) -> view coordinates (..., 2).

        top: (x, y); side: (x, z); perspective: a pinhole camera on the sphere of ``distance``
        around ``centre``, coordinates scaled so a point at the centre keeps its world size.
        """
        points = as_float_array("points", points, shape=(3,))
        if self.name == "top":
            return points[..., [0, 1]].copy()
        if self.name == "side":
            return points[..., [0, 2]].copy()
        right, up, forward = self.camera()
        relative = points - (np.asarray(self.centre) - self.distance * forward)
        depth = relative @ forward
        if np.any(depth <= 0):
            raise ValueError(f"points: expected points in front of the camera ({self.distance} from the centre), "
                             f"got one {float(-depth.min()):.3g} behind it")
        scale = self.distance / depth
        return np.stack([(relative @ right) * scale, (relative @ up) * scale], axis=-1)


@dataclass(frozen=True)
class SpaceDrawing:
    """What stays fixed when a plant in space (an industrial arm) is drawn.

    A view draws the same three things in each of ``views``: the fixed scene (``surfaces``,
    ``base``), the plant's chain from ``plant.sketch(states)`` (a ``PoseSketch`` whose points
    are (..., P, 3)), and arrows (actions, velocities) from the tool point, each projected with
    its ``ViewProjection``. Nothing in it names the robot.

    Attributes:
        bounds: the world box every view frames (a ``Cuboid`` in ``units``).
        units, action_units: as ``PlantDrawing``.
        views: the ``ViewProjection`` of each of ``SPACE_VIEWS``, in that order.
        base: (3,) the fixed base in world units.
        surfaces: closed polygons (K, 3) in world units drawn as the scene (a table top).
        link_radius: how thick links are, in world units (their collision capsules).
        action_length: world units of arrow per action unit, or None to let the skill choose.
        velocity_length: world units of arrow per unit of velocity.
        has_velocity: whether a state has a velocity worth drawing.
    """

    bounds: Cuboid
    units: str
    action_units: str
    views: tuple[ViewProjection, ...]
    base: tuple[float, float, float] = (0.0, 0.0, 0.0)
    surfaces: tuple[np.ndarray, ...] = field(default_factory=tuple)
    link_radius: float = 0.05
    action_length: float | None = None
    velocity_length: float = 0.3
    has_velocity: bool = True

    def __post_init__(self):
        if not isinstance(self.bounds, Cuboid):
            raise TypeError(f"bounds: expected a Cuboid, got {type(self.bounds).__name__}")
        names = tuple(getattr(view, "name", None) for view in self.views)
        if names != SPACE_VIEWS or not all(isinstance(view, ViewProjection) for view in self.views):
            raise ValueError(f"views: expected a ViewProjection for each of {SPACE_VIEWS} in that order, got {names}")
        base = as_float_array("base", self.base, ndim=1, shape=(3,))
        object.__setattr__(self, "base", tuple(float(v) for v in base))
        surfaces = tuple(as_float_array("surfaces", surface, ndim=2, shape=(None, 3)) for surface in self.surfaces)
        object.__setattr__(self, "surfaces", surfaces)
        object.__setattr__(self, "link_radius", as_positive("link_radius", self.link_radius))
        if self.action_length is not None:
            object.__setattr__(self, "action_length", as_positive("action_length", self.action_length))
        object.__setattr__(self, "velocity_length", as_positive("velocity_length", self.velocity_length))
        if not isinstance(self.has_velocity, bool):
            raise TypeError(f"has_velocity: expected True or False, got {self.has_velocity!r}")

    @property
    def view(self) -> Box:
        """The top view's extent (x, y): what a planar consumer of ``Skill.workspace`` gets."""
        return Box(self.bounds.xlim, self.bounds.ylim)

    def projection(self, name: str) -> ViewProjection:
        """The ``ViewProjection`` called ``name`` (one of ``SPACE_VIEWS``)."""
        for view in self.views:
            if view.name == name:
                return view
        raise ValueError(f"name: expected one of {SPACE_VIEWS}, got {name!r}")

    def extent(self, name: str) -> Box:
        """The rectangle of view ``name`` that frames ``bounds`` (its eight corners projected)."""
        low, high = self.bounds.low, self.bounds.high
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                            for z in (low[2], high[2])])
        flat = self.projection(name).project(corners)
        low, high = flat.min(axis=0), flat.max(axis=0)
        return Box((float(low[0]), float(high[0])), (float(low[1]), float(high[1])))
