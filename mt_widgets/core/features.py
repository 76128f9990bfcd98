"""Feature maps phi(x): what the learnt linear policy u = Theta phi(x) can depend on."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .validation import as_float_array


class FeatureMap:
    """Maps states (..., state_dim) to features (..., S).

    Attributes:
        names: a short name per feature, for tables and axis labels.
    """

    names: tuple[str, ...] = ()

    def __init__(self, plant):
        self.plant = plant

    @property
    def dim(self) -> int:
        return len(self.names)

    def __call__(self, states) -> np.ndarray:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(self.names)})"


class EndEffectorFeatures(FeatureMap):
    """phi(x) = (r1, r2, r1dot, r2dot, 1): end-effector position, velocity and a bias.

    The paper's features for the simulated arm. ``ArmPlant``'s rollout recognises this map and
    the chain engine evaluates it inline.
    """

    names = ("r1", "r2", "r1dot", "r2dot", "1")

    def __call__(self, states):
        positions, velocities = self.plant.end_effector(self.plant.check_states("states", states))
        return np.concatenate([positions, velocities, np.ones(positions.shape[:-1] + (1,))], axis=-1)


class PositionFeatures(FeatureMap):
    """phi(x) = (r1, r2, 1): end-effector position and a bias (the paper's uArm features)."""

    names = ("r1", "r2", "1")

    def __call__(self, states):
        positions, _ = self.plant.end_effector(self.plant.check_states("states", states))
        return np.concatenate([positions, np.ones(positions.shape[:-1] + (1,))], axis=-1)


class ToolFeatures(FeatureMap):
    """phi(x) = (r1, r2, r3, 1): an arm's tool point in space and a bias (the UR5's reach and place skills).

    The compiled UR5 rollout recognises this map and evaluates it inline.
    """

    names = ("r1", "r2", "r3", "1")

    def __call__(self, states):
        positions, _ = self.plant.end_effector(self.plant.check_states("states", states))
        return np.concatenate([positions, np.ones(positions.shape[:-1] + (1,))], axis=-1)


class ConveyorFeatures(FeatureMap):
    """phi(x) = (r1, r2, r3, s, 1): the tool point, the conveyor's phase s (m travelled) and a bias.

    A part riding a conveyor is at ``origin + s * direction``, so a policy that follows it is
    linear in these features (the UR5's conveyor skill). The compiled UR5 rollout recognises
    this map and evaluates it inline.
    """

    names = ("r1", "r2", "r3", "s", "1")

    def __call__(self, states):
        states = self.plant.check_states("states", states)
        positions, _ = self.plant.end_effector(states)
        phase = self.plant.conveyor_phase(states)
        return np.concatenate([positions, phase[..., None], np.ones(positions.shape[:-1] + (1,))], axis=-1)


class FunctionFeatures(FeatureMap):
    """A user's own feature map from a vectorised function.

    Args:
        plant: the plant whose states the function takes.
        function: states (N, state_dim) -> features (N, S).
        names: one name per feature.

    Example:
        >>> polar = FunctionFeatures(plant, lambda x: np.stack([np.hypot(x[:, 0], x[:, 1]), np.ones(len(x))], 1),
        ...                          names=("radius", "1"))
    """

    def __init__(self, plant, function: Callable[[np.ndarray], np.ndarray], names: Sequence[str]):
        super().__init__(plant)
        if not callable(function):
            raise ValueError(f"function: expected a callable states -> features, got {function!r}")
        self.function = function
        self.names = tuple(str(n) for n in names)
        if not self.names:
            raise ValueError("names: expected at least one feature name, got none")

    def __call__(self, states):
        states = self.plant.check_states("states", states)
        flat = states.reshape(-1, states.shape[-1])
        features = as_float_array("features returned by function", self.function(flat), ndim=2,
                                  shape=(len(flat), self.dim), finite=False)
        return features.reshape(states.shape[:-1] + (self.dim,))
