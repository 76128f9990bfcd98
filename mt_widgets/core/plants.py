"""The small interface every plant shares, and generic rollouts for plants users write.

A plant is what a skill runs on: the simulated arm, the uArm's kinematic model, or a user's
own system. Teaching widgets and the study runner only talk to this interface, so they
never ask which robot they drive.

Two kinds are provided for user plants:
- ``ContinuousPlant``: a state derivative integrated with RK4, the control input computed
  once per control step and held over it (as a real controller running at a fixed rate does).
- ``KinematicPlant``: a discrete map ``x <- step(x, u)``.
"""

from __future__ import annotations

import numpy as np

from .drawing import PlantDrawing, PoseSketch, framing_box
from .trajectory import TrajectoryBatch
from .validation import as_count, as_float_array, as_positive
from .workspace import Box


class Plant:
    """Base class. Subclasses set the attributes below and implement the methods.

    Attributes:
        robot: a short name ("sim", "uarm", or a user's own).
        state_names: names of the state's components.
        action_dim: R, the number of action components.
        units: length unit of end-effector positions ("m", "cm").
        action_units: unit of an action component ("N", "cm").
        view: a ``Box`` that frames the plant's workspace for drawing, or None to frame where
            the query states put the end-effector.
        default_duration: seconds a reproduction lasts by default.

    Drawing: views ask ``drawing()`` (what stays fixed) and ``sketch(states)`` (what moves);
    the defaults draw a dot at the end-effector with its velocity, so a plant that only
    implements ``end_effector`` is drawn too. A plant with links overrides both.
    """

    robot: str = "custom"
    state_names: tuple[str, ...] = ()
    action_dim: int = 2
    units: str = "m"
    action_units: str = "N"
    default_duration: float = 10.0
    view: Box | None = None

    @property
    def state_dim(self) -> int:
        return len(self.state_names)

    # -- how it is drawn ---------------------------------------------------------------------------
    def drawing(self) -> PlantDrawing:
        """What stays fixed when this plant is drawn (the generic drawing: an end-effector dot)."""
        view = self.view
        if view is None:
            # Framed around the end-effector positions of states drawn as query states are, so
            # the states a teacher sees and the paths near them are in view.
            rng = np.random.default_rng(0)
            states = self.sample_states(rng, 256)
            states = states[self.is_valid_state(states)]
            view = framing_box(self.end_effector(states)[0])
        return PlantDrawing(view=view, units=self.units, action_units=self.action_units)

    def sketch(self, states) -> PoseSketch:
        """What to draw at states (..., state_dim): by default the end-effector and its velocity."""
        positions, velocities = self.end_effector(states)
        positions = np.asarray(positions, dtype=float)
        return PoseSketch(positions[..., None, :], np.asarray(velocities, dtype=float))

    def check_states(self, name: str, states) -> np.ndarray:
        """Validates a single state (state_dim,) or a batch (..., state_dim)."""
        return as_float_array(name, states, shape=(self.state_dim,))

    def end_effector(self, states) -> tuple[np.ndarray, np.ndarray]:
        """(positions (..., 2), velocities (..., 2)) of the end-effector for states (..., state_dim)."""
        raise NotImplementedError

    def sample_states(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n candidate query states (n, state_dim), drawn from the region teaching happens in."""
        raise NotImplementedError

    def is_valid_state(self, states) -> np.ndarray:
        """A bool per state: may it be shown as a query state / used as a start?"""
        states = self.check_states("states", states)
        return np.all(np.isfinite(states), axis=-1)

    def rollout(self, thetas, feature_map, start, duration: float, record_every: int | None = None) -> TrajectoryBatch:
        """Rolls out the linear policies ``u = theta @ feature_map(x)`` from ``start``.

        Args:
            thetas: (B, R, S) policy parameters.
            feature_map: a ``FeatureMap`` for this plant.
            start: (state_dim,) initial state.
            duration: seconds.
            record_every: control steps between recorded samples (plant default if None).
        """
        raise NotImplementedError


class ContinuousPlant(Plant):
    """A plant with continuous dynamics ``xdot = derivative(x, held_input)``.

    Subclasses implement ``derivative`` and ``end_effector``, and may override ``hold`` to turn
    the policy's action into the input held over a control step (the arm turns an
    end-effector force into joint torques there). Rollouts use RK4 at ``control_rate`` Hz.

    Attributes:
        control_rate: controller frequency in Hz (the paper's arm: 1 kHz).
        max_state_norm: a state with a larger norm counts as divergence.
    """

    control_rate: float = 1000.0
    max_state_norm: float = 1e6

    def hold(self, states: np.ndarray, actions: np.ndarray) -> np.ndarray:
        return actions

    def derivative(self, states: np.ndarray, held_input: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def has_diverged(self, states: np.ndarray) -> np.ndarray:
        return ~np.all(np.isfinite(states), axis=-1) | (np.linalg.norm(states, axis=-1) > self.max_state_norm)

    def rollout(self, thetas, feature_map, start, duration, record_every=None):
        thetas, start, n_steps = _check_rollout(self, thetas, feature_map, start, duration, self.control_rate)
        dt = 1.0 / self.control_rate
        record_every = as_count("record_every", record_every if record_every is not None else 1)
        batch = thetas.shape[0]
        n_samples = n_steps // record_every + 1
        states = np.empty((batch, n_samples, self.state_dim))
        actions = np.zeros((batch, n_samples, self.action_dim))
        lengths = np.full(batch, n_samples)
        diverged_at = np.full(batch, np.nan)
        x = np.repeat(start[None, :], batch, axis=0)
        alive = np.ones(batch, dtype=bool)
        sample = 0
        with np.errstate(all="ignore"):  # divergence is detected below, not reported as a warning
            for k in range(n_steps + 1):
                u = np.einsum("brs,bs->br", thetas, feature_map(x))
                if k % record_every == 0:
                    states[:, sample] = x
                    actions[:, sample] = np.where(alive[:, None], u, 0.0)
                    sample += 1
                if k == n_steps:
                    break
                held = self.hold(x, u)
                k1 = self.derivative(x, held)
                k2 = self.derivative(x + 0.5 * dt * k1, held)
                k3 = self.derivative(x + 0.5 * dt * k2, held)
                k4 = self.derivative(x + dt * k3, held)
                stepped = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
                newly = alive & self.has_diverged(stepped)
                if newly.any():
                    diverged_at[newly] = (k + 1) * dt
                    lengths[newly] = sample
                    alive &= ~newly
                x = np.where(alive[:, None], stepped, x)
        for b in np.flatnonzero(lengths < n_samples):
            states[b, lengths[b]:] = states[b, lengths[b] - 1]
            actions[b, lengths[b]:] = 0.0
        return _batch(self, np.arange(n_samples) * record_every * dt, states, actions, diverged_at, lengths)


class KinematicPlant(Plant):
    """A plant moved by a discrete map ``x <- step(x, u)`` every ``step_period`` seconds."""

    step_period: float = 0.5

    def step(self, states: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns (next states, the actions actually applied after the plant's limits)."""
        raise NotImplementedError

    def rollout(self, thetas, feature_map, start, duration, record_every=None):
        thetas, start, n_steps = _check_rollout(self, thetas, feature_map, start, duration, 1.0 / self.step_period)
        batch = thetas.shape[0]
        states = np.empty((batch, n_steps + 1, self.state_dim))
        actions = np.zeros((batch, n_steps + 1, self.action_dim))
        x = np.repeat(start[None, :], batch, axis=0)
        for k in range(n_steps + 1):
            states[:, k] = x
            if k == n_steps:
                break
            x, applied = self.step(x, np.einsum("brs,bs->br", thetas, feature_map(x)))
            actions[:, k] = applied
        lengths = np.full(batch, n_steps + 1)
        return _batch(self, np.arange(n_steps + 1) * self.step_period, states, actions, np.full(batch, np.nan), lengths)


def _check_rollout(plant, thetas, feature_map, start, duration, rate):
    thetas = as_float_array("theta", thetas, ndim=3, shape=(plant.action_dim, feature_map.dim))
    start = plant.check_states("start", start)
    if start.ndim != 1:
        raise ValueError(f"start: expected one state of shape ({plant.state_dim},), got {start.shape}")
    duration = as_positive("duration", duration)
    n_steps = max(1, int(round(duration * rate)))
    return thetas, start, n_steps


def _batch(plant, times, states, actions, diverged_at, lengths) -> TrajectoryBatch:
    positions, velocities = plant.end_effector(states)
    return TrajectoryBatch(times, states, positions, velocities, actions, ~np.isnan(diverged_at), diverged_at,
                           lengths, plant.units)
