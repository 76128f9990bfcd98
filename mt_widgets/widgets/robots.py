"""How each robot looks on screen: the simulated arm (side view) and the uArm (top view).

A painter draws one robot in one state on one layer; every view (teaching canvas,
reproduction player) uses the same painters, so the arm looks the same everywhere.
Painters read geometry from the skill's plant (``plant.arm.joint_positions``) and
positions from ``skill.end_effector``; they compute no dynamics.
"""

from __future__ import annotations

import numpy as np

from .arrows import draw_arrow
from .coords import ViewTransform
from .theme import Theme


class RobotPainter:
    """Base class: draws a robot state and reports where its end-effector is on screen.

    Args:
        skill: The skill whose plant is drawn (``skill.end_effector`` gives positions in
            ``skill.units`` and velocities in ``skill.units`` per second).
        velocity_length: World units of arrow per unit of velocity (e.g. 0.3 m per m/s).
    """

    def __init__(self, skill, velocity_length: float = 0.3):
        self.skill = skill
        self.velocity_length = float(velocity_length)

    def end_effector(self, state) -> tuple[np.ndarray, np.ndarray]:
        """(position (2,), velocity (2,)) of one state, in skill units."""
        positions, velocities = self.skill.end_effector(np.asarray(state, dtype=float)[None, :])
        return positions[0], velocities[0]

    def draw_state(self, canvas, transform: ViewTransform, theme: Theme, state, show_velocity: bool = True):
        """Draw the robot in ``state`` with its end-effector marker (and velocity arrow)."""
        raise NotImplementedError

    def begin_frames(self, canvas, theme: Theme) -> None:
        """Set the styles that stay fixed during an animation (sent once, not per frame)."""
        raise NotImplementedError

    def draw_frame(self, canvas, pixels: np.ndarray) -> None:
        """Draw one animation frame from precomputed pixel points, as few commands as possible."""
        raise NotImplementedError

    def frame_points(self, transform: ViewTransform, states: np.ndarray) -> np.ndarray:
        """Pixels (T, P, 2) of what ``draw_frame`` needs for each of T states."""
        raise NotImplementedError


class SimArmPainter(RobotPainter):
    """The planar two-link arm seen from the side: links, joints, yellow end-effector marker."""

    link_width = 9.0

    def _joints(self, states) -> np.ndarray:
        states = np.asarray(states, dtype=float)
        return self.skill.plant.arm.joint_positions(states[..., :2])

    def draw_state(self, canvas, transform, theme, state, show_velocity=True):
        joints_px = transform.to_pixel(self._joints(state))
        position, velocity = self.end_effector(state)
        canvas.stroke_style = theme.arm
        canvas.line_width = self.link_width
        canvas.line_cap = "round"
        canvas.line_join = "round"
        canvas.set_line_dash([])
        canvas.begin_path()
        canvas.move_to(*(round(float(v), 1) for v in joints_px[0]))
        for point in joints_px[1:]:
            canvas.line_to(*(round(float(v), 1) for v in point))
        canvas.stroke()
        canvas.fill_style = theme.arm
        canvas.fill_rect(joints_px[0][0] - 12, joints_px[0][1] - 4, 24, 16)
        canvas.fill_style = theme.joint
        for point in joints_px[:2]:
            canvas.fill_circle(float(point[0]), float(point[1]), 3.0)
        self._marker(canvas, theme, joints_px[2])
        if show_velocity and np.linalg.norm(velocity) > 0:
            start = transform.to_pixel(position)
            end = start + np.array([velocity[0], -velocity[1]]) * transform.pixels_per_unit * self.velocity_length
            draw_arrow(canvas, start, end, theme.velocity_arrow)

    @staticmethod
    def _marker(canvas, theme, pixel, radius: float = 8.0):
        canvas.fill_style = theme.end_effector
        canvas.fill_circle(float(pixel[0]), float(pixel[1]), radius)
        canvas.stroke_style = theme.end_effector_outline
        canvas.line_width = 1.5
        canvas.stroke_circle(float(pixel[0]), float(pixel[1]), radius)

    def begin_frames(self, canvas, theme):
        canvas.stroke_style = theme.arm
        canvas.line_width = self.link_width
        canvas.line_cap = "round"
        canvas.line_join = "round"
        canvas.set_line_dash([])
        canvas.fill_style = theme.end_effector

    def frame_points(self, transform, states):
        return transform.to_pixel(self._joints(states))

    def draw_frame(self, canvas, pixels):
        # Integer pixels: a frame costs about a third fewer bytes than with decimals, and a
        # sub-pixel wobble is invisible at 60 frames per second.
        (x0, y0), (x1, y1), (x2, y2) = np.rint(pixels).astype(int).tolist()
        canvas.begin_path()
        canvas.move_to(x0, y0)
        canvas.line_to(x1, y1)
        canvas.line_to(x2, y2)
        canvas.stroke()
        canvas.fill_circle(x2, y2, 8)


class UArmPainter(RobotPainter):
    """The uArm seen from above, as on the paper's screen: a black dot at the end-effector."""

    def draw_state(self, canvas, transform, theme, state, show_velocity=True):
        position, _ = self.end_effector(state)
        base = transform.to_pixel([0.0, 0.0])
        pixel = transform.to_pixel(position)
        # A faint line from the base shows which way the arm reaches; the dot is the state.
        canvas.stroke_style = theme.axes
        canvas.line_width = 2.0
        canvas.set_line_dash([4.0, 4.0])
        canvas.stroke_line(float(base[0]), float(base[1]), float(pixel[0]), float(pixel[1]))
        canvas.set_line_dash([])
        canvas.fill_style = theme.uarm_state
        canvas.fill_circle(float(pixel[0]), float(pixel[1]), 8.0)

    def begin_frames(self, canvas, theme):
        canvas.fill_style = theme.uarm_state

    def frame_points(self, transform, states):
        positions, _ = self.skill.end_effector(np.asarray(states, dtype=float))
        return transform.to_pixel(positions)[:, None, :]

    def draw_frame(self, canvas, pixels):
        x, y = np.rint(pixels[0]).astype(int).tolist()
        canvas.fill_circle(x, y, 8)


def painter_for(skill, velocity_length: float | None = None) -> RobotPainter:
    """The painter for a skill's robot (``skill.robot`` is "sim" or "uarm")."""
    robot = getattr(skill, "robot", None)
    if robot == "sim":
        return SimArmPainter(skill, 0.3 if velocity_length is None else velocity_length)
    if robot == "uarm":
        return UArmPainter(skill, 1.0 if velocity_length is None else velocity_length)
    raise ValueError(f"skill.robot: expected 'sim' or 'uarm', got {robot!r}")
