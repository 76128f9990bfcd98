"""How a robot looks on screen, from what its plant says (``mt_widgets.core.drawing``).

One painter draws every plant: the plant's ``PlantDrawing`` says how its links and its
end-effector look (an arm's rigid links and hand, the uArm's reach line and state dot, or just
a dot for a plant that only reports an end-effector), and ``PoseSketch`` gives the points of a
state. Every view (teaching canvas, reproduction player) uses the same painter, so a robot looks
the same everywhere, and no view asks which robot it draws.
"""

from __future__ import annotations

import numpy as np

from .arrows import draw_arrow
from .coords import ViewTransform
from .theme import Theme

#: Pixels: link width of a rigid arm, joint pin size, end-effector marker radius.
LINK_WIDTH = 9.0
JOINT_SIZE = 6
MARKER_RADIUS = 8.0


def _pin(canvas, x, y) -> None:
    # A joint is a small hole punched through the link to the background (the layer below
    # shows through): the same mark in a still picture and in every animation frame, and in a
    # frame it costs one short command and no colour change, which keeps a 10 s reproduction
    # at 60 frames per second inside one small message.
    half = JOINT_SIZE // 2
    canvas.clear_rect(x - half, y - half, JOINT_SIZE, JOINT_SIZE)


class RobotPainter:
    """Draws a skill's plant in a state, and plays it frame by frame.

    Args:
        skill: The skill whose plant is drawn (``skill.drawing()`` and ``skill.sketch(states)``).
        velocity_length: World units of velocity arrow per unit of velocity (default: the
            plant's ``velocity_length``).
    """

    def __init__(self, skill, velocity_length: float | None = None):
        self.skill = skill
        self.drawing = skill.drawing()
        self.velocity_length = float(self.drawing.velocity_length if velocity_length is None else velocity_length)

    def end_effector(self, state) -> tuple[np.ndarray, np.ndarray]:
        """(position (2,), velocity (2,)) of one state, in skill units."""
        sketch = self.skill.sketch(np.asarray(state, dtype=float))
        return sketch.end_effector, sketch.velocity

    def marker_fill(self, theme: Theme) -> str:
        """The end-effector marker's colour in ``theme``."""
        return theme.end_effector if self.drawing.marker == "hand" else theme.state_dot

    # -- one state ---------------------------------------------------------------------------------
    def draw_state(self, canvas, transform: ViewTransform, theme: Theme, state, show_velocity: bool = True):
        """Draw the robot in ``state`` with its end-effector marker (and velocity arrow)."""
        sketch = self.skill.sketch(np.asarray(state, dtype=float))
        chain = transform.to_pixel(sketch.chain)
        links = self.drawing.links
        canvas.set_line_dash([])
        if links == "rigid" and len(chain) >= 2:
            canvas.stroke_style = theme.arm
            canvas.line_width = LINK_WIDTH
            canvas.line_cap = "round"
            canvas.line_join = "round"
            canvas.begin_path()
            canvas.move_to(*(round(float(v), 1) for v in chain[0]))
            for point in chain[1:]:
                canvas.line_to(*(round(float(v), 1) for v in point))
            canvas.stroke()
            for point in np.rint(chain[1:-1]).astype(int).tolist():
                _pin(canvas, *point)
        elif links == "reach" and len(chain) >= 2:
            # A faint line from the base shows which way the arm reaches; the dot is the state.
            canvas.stroke_style = theme.axes
            canvas.line_width = 2.0
            canvas.set_line_dash([4.0, 4.0])
            canvas.stroke_line(float(chain[0][0]), float(chain[0][1]), float(chain[-1][0]), float(chain[-1][1]))
            canvas.set_line_dash([])
        tip = chain[-1]
        canvas.fill_style = self.marker_fill(theme)
        canvas.fill_circle(float(tip[0]), float(tip[1]), MARKER_RADIUS)
        if self.drawing.marker == "hand":
            canvas.stroke_style = theme.end_effector_outline
            canvas.line_width = 1.5
            canvas.stroke_circle(float(tip[0]), float(tip[1]), MARKER_RADIUS)
        velocity = sketch.velocity
        if show_velocity and np.linalg.norm(velocity) > 0:
            end = tip + np.array([velocity[0], -velocity[1]]) * transform.pixels_per_unit * self.velocity_length
            draw_arrow(canvas, tip, end, theme.velocity_arrow)

    def draw_base(self, canvas, transform: ViewTransform, theme: Theme) -> None:
        """Draw the plant's fixed base (if it has one): it never moves, so it is drawn with the
        background, and shows in every frame of an animation."""
        if self.drawing.base is None:
            return
        x, y = (float(v) for v in transform.to_pixel(self.drawing.base))
        canvas.fill_style = theme.arm
        if self.drawing.links == "rigid":
            canvas.fill_rect(x - 12, y - 4, 24, 16)
        else:
            canvas.fill_circle(x, y, 4.0)

    # -- animation ---------------------------------------------------------------------------------
    def begin_frames(self, canvas, theme: Theme) -> None:
        """Set the styles that stay fixed during an animation (sent once, not per frame).

        The fill is the end-effector marker's; a caller that fills other marks within a frame
        sets ``marker_fill(theme)`` back before ``draw_frame``.
        """
        canvas.set_line_dash([])
        if self.drawing.links == "rigid":
            canvas.stroke_style = theme.arm
            canvas.line_width = LINK_WIDTH
            canvas.line_cap = "round"
            canvas.line_join = "round"
        elif self.drawing.links == "reach":
            canvas.stroke_style = theme.axes
            canvas.line_width = 2.0
            canvas.line_cap = "butt"
            canvas.set_line_dash([4.0, 4.0])
        canvas.fill_style = self.marker_fill(theme)

    def frame_points(self, transform: ViewTransform, states: np.ndarray) -> np.ndarray:
        """Pixels (T, P, 2) of the chain (base, joints, end-effector) for each of T states."""
        return transform.to_pixel(self.skill.sketch(np.asarray(states, dtype=float)).chain)

    def draw_frame(self, canvas, pixels: np.ndarray) -> None:
        """Draw one animation frame from ``frame_points`` pixels (P, 2), in few commands.

        Every frame draws the whole moving chain: the links, each joint between base and
        end-effector (an arm's elbow) and the end-effector; the fixed base is on the background,
        so nothing of the robot vanishes while it moves.
        """
        # Integer pixels: a frame costs about a third fewer bytes than with decimals, and a
        # sub-pixel wobble is invisible at 60 frames per second.
        points = np.rint(pixels).astype(int).tolist()
        links = self.drawing.links
        if links != "none" and len(points) >= 2:
            # One stroke_line per link: with round caps, links meet at a joint as a round join
            # would, in fewer bytes than a path (begin, move, lines, stroke).
            for (x0, y0), (x1, y1) in zip(points[:-1], points[1:]):
                canvas.stroke_line(x0, y0, x1, y1)
            if links == "rigid":
                for point in points[1:-1]:
                    _pin(canvas, *point)
        x, y = points[-1]
        canvas.fill_circle(x, y, int(MARKER_RADIUS))


def painter_for(skill, velocity_length: float | None = None) -> RobotPainter:
    """The painter for a skill's plant (any plant: its drawing says how it looks)."""
    return RobotPainter(skill, velocity_length)
