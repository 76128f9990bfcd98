"""The uArm Swift Pro as the paper uses it: a kinematic plant in the horizontal plane, in cm."""

from __future__ import annotations

import numpy as np

from .drawing import PlantDrawing, PoseSketch
from .plants import KinematicPlant
from .validation import as_positive
from .workspace import AnnulusSector

#: The teaching workspace in centimetres: 14-30 cm from the base axis, within +-60 degrees of
#: straight ahead. Kept well inside what the arm reaches at the teaching height (about
#: 10.5-36 cm at z = 5 cm, per the firmware's kinematics in docs/uarm-protocol.md), so that no
#: reproduction or query state asks the real arm for a place it cannot reach.
UARM_WORKSPACE_CM = AnnulusSector(r_min=14.0, r_max=30.0, max_yaw_deg=60.0)


class UArmPlant(KinematicPlant):
    """State r = (r1, r2) in cm; action = desired change of position in cm; ``r <- r + u``.

    Each step the action is limited to ``max_step_cm`` (the arm's top speed times the step
    period: 10 cm/s x 0.5 s) and the result projected back into the workspace, so a learnt
    skill can push against the edge but never leave it.

    Args:
        workspace: an ``AnnulusSector`` in cm.
        step_period: seconds per step of reproduction.
        max_speed_cm_s: the arm's top speed (the paper's 100 mm/s).
    """

    robot = "uarm"
    state_names = ("r1", "r2")
    units = "cm"
    action_units = "cm"
    default_duration = 10.0

    def __init__(self, workspace: AnnulusSector = UARM_WORKSPACE_CM, step_period: float = 0.5,
                 max_speed_cm_s: float = 10.0):
        if not isinstance(workspace, AnnulusSector):
            raise ValueError(f"workspace: expected an AnnulusSector, got {type(workspace).__name__}")
        self.workspace = workspace
        self.step_period = as_positive("step_period", step_period)
        self.max_speed_cm_s = as_positive("max_speed_cm_s", max_speed_cm_s)
        box = workspace.bounding_box
        self.view = type(box)((0.0, box.xlim[1] + 2.0), (box.ylim[0] - 2.0, box.ylim[1] + 2.0))

    def __repr__(self) -> str:
        return f"UArmPlant(workspace={self.workspace}, step_period={self.step_period})"

    @property
    def max_step_cm(self) -> float:
        return self.max_speed_cm_s * self.step_period

    def end_effector(self, states):
        states = self.check_states("states", states)
        return states.copy(), np.zeros_like(states)

    def drawing(self):
        # Seen from above, as on the paper's screen: a dot for the state, a faint line from the
        # base showing which way the arm reaches, the reachable sector outlined. Arrows of 2 cm
        # per cm of action: the 1-4 cm moves of a step read as 2-8 cm on screen.
        return PlantDrawing(view=self.view, units=self.units, action_units=self.action_units, links="reach",
                            marker="dot", base=(0.0, 0.0), outline=(self.workspace.outline(),),
                            action_length=2.0, velocity_length=1.0, has_velocity=False)

    def sketch(self, states):
        positions, velocities = self.end_effector(states)
        chain = np.stack([np.zeros_like(positions), positions], axis=-2)
        return PoseSketch(chain, velocities)

    def sample_states(self, rng, n):
        return self.workspace.sample(rng, n)

    def is_valid_state(self, states):
        states = self.check_states("states", states)
        return self.workspace.contains(states)

    def step(self, states, actions):
        length = np.linalg.norm(actions, axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = np.where(length > self.max_step_cm, self.max_step_cm / length, 1.0)
        proposed = states + actions * scale
        next_states = self.workspace.project(proposed)
        return next_states, next_states - states
