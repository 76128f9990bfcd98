"""The reproduction player: the learnt skill rolled out from the skill's start, as an animation."""

from __future__ import annotations

import numpy as np
from ipywidgets import HTML, Button, HBox, Layout, VBox

from mt_widgets.core.validation import as_bool

from .animation import DEFAULT_FPS, frame_times, play_frames, sample_at, set_style_now
from .arm_view import ArmView
from .looks import plain, shared_layout
from .redraw import drawing_batch


def _path_painter(view: ArmView, positions: np.ndarray, color: str, alpha: float, width: float, dash=()):
    # float32 keeps the binary buffer small (8 bytes a point); paths come at frame rate.
    pixels = view.transform.to_pixel(positions).astype(np.float32)

    def paint(canvas):
        canvas.global_alpha = alpha
        canvas.stroke_style = color
        canvas.line_width = width
        canvas.set_line_dash(list(dash))
        canvas.stroke_lines(pixels)
        canvas.set_line_dash([])
        canvas.global_alpha = 1.0

    return paint


def _with_alpha(color: str, alpha: float) -> str:
    """'#RRGGBB' and an opacity in [0, 1] -> '#RRGGBBAA' (shorter on the wire than rgba())."""
    if not (isinstance(color, str) and len(color) == 7 and color.startswith("#")):
        raise ValueError(f"color: expected '#RRGGBB', got {color!r}")
    if not 0 <= alpha <= 1:
        raise ValueError(f"alpha: expected an opacity in [0, 1], got {alpha!r}")
    return f"{color}{round(alpha * 255):02X}"


class ReproductionPlayer(VBox):
    """Plays a ``Trajectory`` on its own arm view, with a replay button and the teaching error.

    The rollout itself comes from ``skill.reproduce`` (core); this widget only draws it.

    Args:
        skill: The skill whose robot and target are drawn.
        theme: A ``Theme`` or theme name.
        fps: Playback frames per second.
        width, height, css_width, action_length, target_label: As for ``ArmView``.
        show_outcome: write the teaching error and where the robot ended under the animation.
            A blinded study shows the reproduction only, as the paper's participants saw it.
    """

    def __init__(self, skill, theme=None, fps: float = DEFAULT_FPS, width=None, height=None, css_width=None,
                 action_length=None, target_label: str | None = "goal", show_outcome: bool = True):
        self.skill = skill
        self.target_label = target_label
        self.show_outcome = as_bool("show_outcome", show_outcome)
        self.fps = float(fps)
        self.view = ArmView(skill, width=width, height=height, theme=theme, action_length=action_length,
                            css_width=css_width, target_label=target_label)
        self.theme = self.view.theme
        # Its own width, never shrunk by the line beside it (a long error line cut it to "Rep...").
        self.replay_button = plain(Button, description="Replay", icon="repeat", disabled=True,
                                   tooltip="Play the reproduction again",
                                   layout=shared_layout(width="auto", min_width="96px", flex="0 0 auto"))
        self.replay_button.on_click(lambda _: self.replay())
        # Its own layout (hidden and shown), the shared style (looks.py).
        self.status = plain(HTML, layout=Layout(),
                            value="<i>The robot reproduces what it learnt here after the last demonstration.</i>")
        if not self.show_outcome:
            self.status.layout.display = "none"
        self.error_label = plain(HTML, value="")
        self.trajectory = None
        self.ghost = None
        self.theta_error = None
        self.policy_risk = None
        self._frames = None
        self.view.show_state(skill.start, show_velocity=False)
        self.view.legend.remove("velocity")  # frames draw the robot, not its velocity
        super().__init__([self.view.canvas, self.view.legend, plain(HBox, [self.replay_button, self.error_label],
                                                                        layout=shared_layout(align_items="center",
                                                                                             grid_gap="8px")),
                          self.status],
                         layout=Layout(align_items="flex-start"))

    def play(self, trajectory, theta_error: float | None = None, policy_risk: float | None = None,
             ghost=None) -> None:
        """Animate ``trajectory`` (a core ``Trajectory``) and show the episode's error and divergence.

        Args:
            trajectory: The learnt skill's rollout (``times``, ``states``, ``positions``,
                ``diverged``, ``diverged_at``).
            theta_error: Theta's error E = ||Theta_hat - Theta|| where the learner has a Theta; shown
                under the view in preference to the policy risk.
            policy_risk: the learnt policy's risk, shown where there is no ``theta_error``.
            ghost: Optionally the target skill's own rollout, drawn faintly for comparison.
        """
        if len(trajectory.times) < 1:
            raise ValueError("trajectory: expected at least one sample, got none")
        self.trajectory, self.ghost = trajectory, ghost
        self.theta_error, self.policy_risk = theta_error, policy_risk
        times = frame_times(float(trajectory.times[0]), float(trajectory.times[-1]), self.fps)
        states = sample_at(trajectory.times, trajectory.states, times)
        frames = self.view.painter.frame_points(self.view.transform, states)
        ghost_pixels = ghost_positions = None
        if ghost is not None:
            ghost_times = np.clip(times, ghost.times[0], ghost.times[-1])
            ghost_positions = sample_at(ghost.times, ghost.positions, ghost_times)
            ghost_pixels = np.rint(self.view.transform.to_pixel(ghost_positions)).astype(int).tolist()
        # Paths at half the frame rate: as smooth to the eye, half the bytes.
        learnt_positions = sample_at(trajectory.times, trajectory.positions, times[::2])
        if ghost_positions is not None:
            ghost_positions = ghost_positions[::2]
        self._frames = (frames, ghost_pixels, states[-1], learnt_positions, ghost_positions)
        self.view.legend.remove("ghost", "diverged")
        self.view.legend.add("learnt", *(("ghost",) if ghost is not None else ()),
                             *(("diverged",) if trajectory.diverged else ()))
        self._update_labels()
        self.replay()

    def replay(self) -> None:
        """Send the last animation again (one message)."""
        if self._frames is None:
            raise RuntimeError("replay: nothing to replay yet; call play(trajectory) first")
        frames, ghost_pixels, last_state, learnt_positions, ghost_positions = self._frames
        view, theme, painter = self.view, self.theme, self.view.painter
        ghost_path = (_path_painter(view, ghost_positions, theme.ghost, theme.ghost_alpha, 3.0, (6.0, 4.0))
                      if ghost_positions is not None else None)
        learnt_path = _path_painter(view, learnt_positions, theme.trail, 0.8, 2.0)

        def ghost_layer_after(canvas):
            if ghost_path is not None:
                ghost_path(canvas)
            learnt_path(canvas)

        def setup(canvas):
            painter.begin_frames(canvas, theme)

        ghost_fill = _with_alpha(theme.ghost, 0.45)
        robot_fill = painter.marker_fill(theme)

        def draw_frame(canvas, index):
            if ghost_pixels is not None:
                # Two fill-style changes per frame (about 45 bytes; the opacity rides in the
                # colour, not in global_alpha, to save two more) buy the ghost marker.
                x, y = ghost_pixels[index]
                set_style_now(canvas, "fill_style", ghost_fill)
                canvas.fill_circle(x, y, 7)
                set_style_now(canvas, "fill_style", robot_fill)
            painter.draw_frame(canvas, frames[index])

        diverged = bool(self.trajectory.diverged)
        final_position = np.asarray(self.trajectory.positions[-1], dtype=float)

        def final(canvas):
            painter.draw_state(canvas, view.transform, theme, last_state, show_velocity=False)
            if diverged:
                x, y = view.transform.to_pixel(final_position)
                canvas.stroke_style = theme.diverged
                canvas.line_width = 4.0
                canvas.stroke_line(x - 12, y - 12, x + 12, y + 12)
                canvas.stroke_line(x - 12, y + 12, x + 12, y - 12)

        ghost_canvas = view.layer("ghost")

        def path_after_motion():
            # Sent with the last frame, so the learnt path appears when the motion ends.
            ghost_canvas.clear()
            ghost_layer_after(ghost_canvas)

        with drawing_batch():
            view.show(ghost_path, "ghost")
            play_frames(view, "robot", len(frames), setup, draw_frame, final, self.fps, then=path_after_motion)
        view.remember(ghost_layer_after, "ghost")
        self.replay_button.disabled = False

    def _update_labels(self) -> None:
        if not self.show_outcome:
            return
        trajectory, units = self.trajectory, self.skill.units
        end = trajectory.positions[-1]
        # Fixed decimals: the optimal demonstration gives an error like 3.3e-15, which a
        # novice reads as a large number; 0.000 says what it is.
        if self.theta_error is not None:
            self.error_label.value = (f"<b>Teaching error</b> (&Theta;'s error) E = ||vec(&Theta;&#770;) &minus; "
                                      f"vec(&Theta;)|| = <b>{self.theta_error:.3f}</b> <small>(0 = the robot learnt "
                                      f"the skill exactly)</small>")
        elif self.policy_risk is not None:
            self.error_label.value = (f"<b>Teaching error</b> (policy risk) = <b>{self.policy_risk:.3f} "
                                      f"{self.skill.action_units}</b> <small>(the learnt actions' distance to the "
                                      f"skill's; 0 = the robot learnt the skill exactly)</small>")
        if trajectory.diverged:
            when = "" if trajectory.diverged_at is None else f" at t = {trajectory.diverged_at:.2f} s"
            self.status.value = (
                f"<div style='color:white;background:{self.theme.diverged};padding:4px 8px;border-radius:4px'>"
                f"<b>The learnt skill diverged{when}</b>: the robot left its safe range, so the replay stops "
                f"there ({self._named('diverged')}cross). The demonstrations did not teach a stable skill.</div>")
        else:
            distance = self.skill.target.distance(end) if self.skill.target is not None else None
            goal = "" if self.skill.target is None else self.theme.target_words(self.skill.target, self.target_label)
            extra = "" if distance is None else f", {float(distance):.3g} {units} from {goal}"
            self.status.value = (f"After {trajectory.times[-1]:.1f} s the robot's hand is at "
                                 f"({end[0]:.2f}, {end[1]:.2f}) {units}{extra}. "
                                 f"Its path is the {self._named('trail')}line"
                                 + (f"; the faint dashed {self._named('ghost')}line is the skill's own motion."
                                    if self.ghost is not None else "."))

    def _named(self, role: str) -> str:
        """The theme's name of a mark's colour and a space ("pink "), or nothing if it has none."""
        name = self.theme.color_name(role)
        return f"{name} " if name else ""
