"""Synthetic teachers: documented models of how novices demonstrate, and how they learn.

The model follows what the paper observed of its participants:

1. **Novices point at the target, too hard.** Early on, "users often provide actions that
   point to the target, with a large magnitude". A novice's arrow at a state points from the
   end-effector to the nearest point of the target (the point, or the foot on the line), as
   if pulling the tip there, ``m_i`` times as hard as the skill itself does: its length is
   ``m_i * g * distance`` with ``g`` the skill's own position gain (the spectral norm of the
   position block of Theta: 1 N/m for the simulated skills) and ``m_i`` drawn per participant,
   log-normal around ``magnitude`` > 1. It ignores the velocity, which the true spring-damper
   policy damps.
2. **Their understanding is a blend.** A teacher's intended arrow is
   ``(1 - w) * naive + w * optimal``, with ``optimal`` the machine-teaching arrow U_bar at that
   state and ``w`` in [0, 1] how far they have understood the skill (0 for a novice).
3. **They are noisy.** The drawn arrow is the intended one rotated by a direction slip
   (``direction_noise`` rad, per demonstration) and scaled by a magnitude slip
   (log-normal, ``magnitude_noise``).
4. **Without guidance they explore direction, not magnitude.** "Most control group users
   only explore the direction of action and failed to adjust the magnitude": in every episode
   without guidance the teacher turns all arrows by a fresh exploration angle
   (``exploration`` rad), scaled by ``1 - w``; their magnitude habit ``m_i`` never changes.
5. **Guided teachers move toward the optimal arrows.** After each demonstration with
   guidance (seeing their arrow beside the optimal one) ``w <- w + a_i (1 - w)``, with a
   learning rate ``a_i`` drawn per participant (logit-normal around ``learning_rate``).
   Watching a reproduction teaches a little too: ``w <- w + reproduction_learning (1 - w)``
   after every episode.
6. **Retention and transfer.** Without the arrows in front of them teachers apply only a part
   of what they learnt: ``w`` is multiplied by ``retention`` in unguided episodes and by
   ``transfer`` on a skill they were never guided on.

An **optimal teacher** (``OPTIMAL_TEACHER``) starts with ``w = 1`` and no noise: it draws the
optimal arrows and teaches the skill exactly.

Everything random about a participant is drawn once from their seed when they are created
(``TeacherPopulation.draw``): their traits and a table of standard-normal draws indexed by
episode and demonstration. Whoever runs them (the batched in-silico engine or the session
engine, one demonstration at a time) therefore gets exactly the same arrows.

``PAPER_FIT`` holds parameters fitted (``fit_to_paper``) so that an in-silico run of the
paper's simulation protocol lands near the paper's reported changes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

import numpy as np

#: Standard-normal draws kept per demonstration: direction slip, magnitude slip, the time to
#: the first input and the drawing time.
_PER_DEMONSTRATION = 4


@dataclass(frozen=True)
class TeacherParameters:
    """The parameters of the teacher model (see the module docstring for the model).

    Attributes:
        magnitude: median naive gain, as a multiple of the skill's own position gain (> 1:
            too large).
        magnitude_spread: SD of log(m_i) across participants.
        direction_noise: SD of the per-demonstration direction slip, rad.
        magnitude_noise: SD of the per-demonstration log-magnitude slip.
        exploration: SD of the per-episode exploration angle without guidance, rad.
        learning_rate: median learning rate a_i per guided demonstration, in (0, 1).
        learning_spread: SD of logit(a_i) across participants.
        reproduction_learning: what one reproduction teaches, in [0, 1).
        retention: share of the understanding applied without guidance, in [0, 1].
        transfer: share of the understanding applied to a skill never guided on, in [0, 1].
        initial_understanding: w at the start (0 for novices, 1 for the optimal teacher).
        first_input_s: median time from a state appearing to the first input, s.
        drawing_s: median time spent drawing an arrow, s.
        timing_spread: SD of the log of both times.
    """

    magnitude: float = 2.0
    magnitude_spread: float = 0.3
    direction_noise: float = 0.3
    magnitude_noise: float = 0.2
    exploration: float = 0.3
    learning_rate: float = 0.1
    learning_spread: float = 0.8
    reproduction_learning: float = 0.0
    retention: float = 0.8
    transfer: float = 0.8
    initial_understanding: float = 0.0
    first_input_s: float = 2.5
    drawing_s: float = 1.2
    timing_spread: float = 0.4

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) or not np.isfinite(value):
                raise ValueError(f"{f.name}: expected a finite number, got {value!r}")
            if value < 0:
                raise ValueError(f"{f.name}: expected a number >= 0, got {value}")
        for name in ("retention", "transfer", "initial_understanding"):
            if getattr(self, name) > 1:
                raise ValueError(f"{name}: expected a share in [0, 1], got {getattr(self, name)}")
        for name in ("learning_rate", "reproduction_learning"):
            if getattr(self, name) >= 1:
                raise ValueError(f"{name}: expected a rate in [0, 1), got {getattr(self, name)}")
        for name in ("magnitude", "first_input_s", "drawing_s"):
            if getattr(self, name) <= 0:
                raise ValueError(f"{name}: expected a positive number, got {getattr(self, name)}")

    def as_dict(self) -> dict:
        return asdict(self)


#: Parameters fitted to the paper's simulation experiment: ``fit_to_paper(n_per_group=500,
#: seed=0)`` on the shipped "paper-sim" protocol's query states, with the drawing slips held at
#: 0.05 rad and 0.05 (final loss 1.78, in squared units of the paper's SDs over 18 terms).
#: Novices draw about twice the skill's own gain, guided teachers close about 2.4% of their
#: gap to the optimal arrows per demonstration, and keep 94% of it without guidance.
#: ``compare_with_paper`` says how near an in-silico run lands, row by row.
PAPER_FIT = TeacherParameters(
    magnitude=1.9458, magnitude_spread=0.31726, direction_noise=0.05, magnitude_noise=0.05, exploration=0.50517,
    learning_rate=0.024286, learning_spread=0.52392, reproduction_learning=1.7199e-05, retention=0.94206,
    transfer=1.0,
)

#: A teacher who already knows the skill and draws without slips: the machine-teaching optimum.
OPTIMAL_TEACHER = TeacherParameters(magnitude=1.0, magnitude_spread=0.0, direction_noise=0.0, magnitude_noise=0.0,
                                    exploration=0.0, learning_rate=0.0, learning_spread=0.0, retention=1.0,
                                    transfer=1.0, initial_understanding=1.0, timing_spread=0.0)


def _logit(p: float) -> float:
    p = min(max(p, 1e-9), 1 - 1e-9)
    return float(np.log(p / (1 - p)))


def position_gain(theta) -> float:
    """g: the spectral norm of the position block (first two columns) of Theta (R, S)."""
    return float(np.linalg.norm(np.asarray(theta, dtype=float)[:, :2], 2))


def naive_offsets(positions: np.ndarray, target) -> np.ndarray:
    """Vectors from end-effector positions (..., 2) to the nearest point of ``target``.

    Args:
        positions: (..., 2) in the skill's units.
        target: a ``PointTarget`` (towards the point) or ``LineTarget`` (perpendicular onto the
            line).

    Returns:
        (..., 2) offsets in the positions' units (zero on the target).
    """
    positions = np.asarray(positions, dtype=float)
    point = np.asarray(target.point, dtype=float)
    if hasattr(target, "direction"):
        along = np.asarray(target.direction, dtype=float)
        offset = positions - point
        nearest = point + (offset @ along)[..., None] * along
    else:
        nearest = np.broadcast_to(point, positions.shape)
    return nearest - positions


def _rotate(vectors: np.ndarray, angles: np.ndarray) -> np.ndarray:
    c, s = np.cos(angles), np.sin(angles)
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


class TeacherPopulation:
    """B synthetic teachers stepped together (B = 1 for a single teacher in a session).

    Build with ``TeacherPopulation.draw``. The state that changes as they teach is the
    understanding ``w`` (B,) and the set of skills each has been guided on.

    Attributes:
        parameters: the ``TeacherParameters``.
        traits: (B, 2) standard normals behind each teacher's magnitude and learning rate.
        magnitude: (B,) each teacher's naive arrow length m_i (multiple of the optimal).
        learning_rate: (B,) each teacher's a_i.
        understanding: (B,) current w.
        demonstration_noise: (B, episodes, max_demonstrations, 4) standard normals.
        episode_noise: (B, episodes) standard normals (exploration angle).
    """

    def __init__(self, parameters: TeacherParameters, traits, demonstration_noise, episode_noise):
        self.parameters = parameters
        self.traits = np.asarray(traits, dtype=float)
        self.demonstration_noise = np.asarray(demonstration_noise, dtype=float)
        self.episode_noise = np.asarray(episode_noise, dtype=float)
        p = parameters
        self.magnitude = p.magnitude * np.exp(p.magnitude_spread * self.traits[:, 0])
        if p.learning_rate == 0:
            self.learning_rate = np.zeros(len(self.traits))
        else:
            self.learning_rate = 1 / (1 + np.exp(-(_logit(p.learning_rate) + p.learning_spread * self.traits[:, 1])))
        self.understanding = np.full(len(self.traits), float(p.initial_understanding))
        self.guided_skills: dict[str, np.ndarray] = {}

    def with_parameters(self, parameters: TeacherParameters) -> "TeacherPopulation":
        """The same people (the same draws) with other parameters, back at the start."""
        return TeacherPopulation(parameters, self.traits, self.demonstration_noise, self.episode_noise)

    def __len__(self) -> int:
        return len(self.magnitude)

    @classmethod
    def draw(cls, parameters: TeacherParameters | None, seeds, n_episodes: int, max_demonstrations: int):
        """Draws teachers, one per seed.

        Args:
            parameters: the model's parameters (default ``PAPER_FIT``).
            seeds: a sequence of ints or ``numpy.random.SeedSequence``; teacher i depends only
                on seeds[i], so a teacher is the same whether drawn alone or in a crowd.
            n_episodes: episodes in the protocol.
            max_demonstrations: the most demonstrations in any episode.
        """
        parameters = PAPER_FIT if parameters is None else parameters
        if not isinstance(parameters, TeacherParameters):
            raise ValueError(f"parameters: expected TeacherParameters, got {type(parameters).__name__}")
        seeds = list(seeds)
        if not seeds:
            raise ValueError("seeds: expected at least one seed, got none")
        traits = np.empty((len(seeds), 2))
        demonstration = np.empty((len(seeds), n_episodes, max_demonstrations, _PER_DEMONSTRATION))
        episode = np.empty((len(seeds), n_episodes))
        for i, seed in enumerate(seeds):
            rng = np.random.default_rng(seed)
            traits[i] = rng.standard_normal(2)
            demonstration[i] = rng.standard_normal((n_episodes, max_demonstrations, _PER_DEMONSTRATION))
            episode[i] = rng.standard_normal(n_episodes)
        return cls(parameters, traits, demonstration, episode)

    # -- one demonstration ------------------------------------------------------------------------
    def effective_understanding(self, skill_key: str, guided) -> np.ndarray:
        """(B,) the w a teacher applies now: all of it with guidance, less without, less on a new skill."""
        p = self.parameters
        guided = np.broadcast_to(np.asarray(guided, dtype=bool), self.understanding.shape)
        trained = self.guided_skills.get(skill_key, np.zeros(len(self), dtype=bool))
        factor = np.where(guided, 1.0, p.retention) * np.where(trained | guided, 1.0, p.transfer)
        if p.initial_understanding == 1.0:
            factor = np.ones_like(factor)   # an expert has nothing to forget
        return self.understanding * factor

    def act(self, episode: int, demonstration: int, offsets, optimal, gain: float, skill_key: str, guided):
        """The arrows the teachers draw at one query state.

        Args:
            episode: 0-based episode index in the protocol.
            demonstration: 0-based demonstration index in the episode.
            offsets: (B, 2) from the end-effector to the target (``naive_offsets``).
            optimal: (B, 2) the optimal arrows U_bar at this state.
            gain: the skill's position gain g (``position_gain``).
            skill_key: the skill taught (for transfer).
            guided: bool or (B,) whether each teacher sees guidance in this episode.

        Returns:
            (B, 2) actions, in the skill's action units.
        """
        p = self.parameters
        w = self.effective_understanding(skill_key, guided)[:, None]
        noise = self.demonstration_noise[:, episode, demonstration]
        naive = (self.magnitude * gain)[:, None] * offsets
        intended = (1 - w) * naive + w * optimal
        guided = np.broadcast_to(np.asarray(guided, dtype=bool), self.understanding.shape)
        explore = np.where(guided, 0.0, p.exploration * self.episode_noise[:, episode]) * (1 - w[:, 0])
        angle = p.direction_noise * noise[:, 0] + explore
        return _rotate(intended, angle) * np.exp(p.magnitude_noise * noise[:, 1])[:, None]

    def timings(self, episode: int, demonstration: int, guided) -> tuple[np.ndarray, np.ndarray]:
        """(time to first input (B,), drawing duration (B,)) in seconds; guided teachers deliberate longer."""
        p = self.parameters
        noise = self.demonstration_noise[:, episode, demonstration]
        slower = 1 + 0.5 * np.asarray(guided, dtype=float) * self.understanding
        first = p.first_input_s * np.exp(p.timing_spread * noise[:, 2]) * slower
        drawing = p.drawing_s * np.exp(p.timing_spread * noise[:, 3]) * slower
        return first, drawing

    # -- learning ---------------------------------------------------------------------------------
    def see_guidance(self, skill_key: str, guided) -> None:
        """After a demonstration: teachers who saw the optimal arrow move toward it."""
        guided = np.broadcast_to(np.asarray(guided, dtype=bool), self.understanding.shape)
        rate = np.where(guided, self.learning_rate, 0.0)
        self.understanding = self.understanding + rate * (1 - self.understanding)
        self.guided_skills[skill_key] = self.guided_skills.get(skill_key, np.zeros(len(self), dtype=bool)) | guided

    def see_reproduction(self) -> None:
        """After an episode: watching the robot reproduce the learnt skill teaches a little."""
        self.understanding = self.understanding + self.parameters.reproduction_learning * (1 - self.understanding)


def with_parameters(base: TeacherParameters, **changes) -> TeacherParameters:
    """``base`` with some fields changed (validated)."""
    return replace(base, **changes)


# -- fitting to the paper -------------------------------------------------------------------------

#: The fields ``fit_to_paper`` can adjust, with the transform that keeps each in its range.
TRANSFORMS = {
    "magnitude": "log", "magnitude_spread": "log", "direction_noise": "log", "magnitude_noise": "log",
    "exploration": "log", "learning_rate": "logit", "learning_spread": "log", "reproduction_learning": "logit",
    "retention": "logit", "transfer": "logit",
}

#: The fields fitted by default. The drawing slips (``direction_noise``, ``magnitude_noise``)
#: are held at the start's values: fitted freely they shrink to nothing (the paper's small SDs
#: leave no room for them), yet a hand never draws the same arrow twice, so they stay at a
#: modest assumed size (about 6 degrees and 10 %).
FITTED_FIELDS = ("magnitude", "magnitude_spread", "exploration", "learning_rate", "learning_spread",
                 "reproduction_learning", "retention", "transfer")


def _to_free(parameters: TeacherParameters, names) -> np.ndarray:
    values = []
    for name in names:
        value = getattr(parameters, name)
        values.append(np.log(max(value, 1e-6)) if TRANSFORMS[name] == "log" else _logit(value))
    return np.array(values)


def _from_free(free: np.ndarray, base: TeacherParameters, names) -> TeacherParameters:
    changes = {}
    for value, name in zip(free, names):
        changes[name] = float(np.exp(value)) if TRANSFORMS[name] == "log" else float(1 / (1 + np.exp(-value)))
    # Rates must stay below 1 and shares at most 1: the logistic keeps them there except at
    # the edges of floating point.
    for name in ("learning_rate", "reproduction_learning"):
        if name in changes:
            changes[name] = min(changes[name], 0.999)
    return replace(base, **changes)


def paper_targets(reference: dict | None = None) -> dict:
    """What the fit aims at: the paper's change means and SDs per group and the target group's
    baseline error implied by its percentage reductions (change / percent)."""
    from .in_silico import paper_results
    reference = paper_results() if reference is None else reference
    simulation = reference["simulation"]
    changes = simulation["changes"]
    percent = simulation["percent_reduction_target"]
    baselines = {
        "P1_to_P3E8": -changes["P1_to_P3E8"]["target"]["mean"] / (percent["during_P3"] / 100),
        "P1_to_P4": -changes["P1_to_P4"]["target"]["mean"] / (percent["P4_vs_P1"] / 100),
        "P2_to_P5": -changes["P2_to_P5"]["target"]["mean"] / (percent["P5_vs_P2"] / 100),
    }
    return {"changes": changes, "baselines": baselines}


def fit_loss(deltas: dict, targets: dict) -> float:
    """Squared gaps of the simulated change means and SDs from the paper's, in units of the
    paper's SDs, plus the gaps of the target group's baseline error (in units of its SD)."""
    loss = 0.0
    for name, groups in targets["changes"].items():
        for group, values in groups.items():
            delta = deltas[name][group].ravel()
            loss += ((delta.mean() - values["mean"]) / values["sd"]) ** 2
            loss += ((delta.std(ddof=1) - values["sd"]) / values["sd"]) ** 2
        before = deltas[name]["before"][:, : deltas[name]["target"].shape[1]].ravel()
        loss += ((before.mean() - targets["baselines"][name]) / groups["target"]["sd"]) ** 2
    return float(loss)


def fit_to_paper(n_per_group: int = 1000, seed: int = 0, start: TeacherParameters | None = None, protocol=None,
                 max_evaluations: int = 1500, reference: dict | None = None, fields=FITTED_FIELDS):
    """Fits the teacher model so an in-silico run of the protocol lands near the paper's changes.

    The loss (``fit_loss``) compares, for each of the paper's three changes and both groups,
    the mean and SD of the simulated changes with the paper's, and the target group's baseline
    error with the one the paper's percentages imply. The same simulated people (common random
    numbers) are used at every evaluation, on the protocol's own query states, so the loss is a
    smooth function of the parameters and Nelder-Mead can minimise it.

    Args:
        n_per_group: simulated participants per group (large: the population's moments).
        seed: seed of the simulated people.
        start: the starting parameters (default ``PAPER_FIT``).
        protocol: the protocol (default the paper's simulation protocol).
        max_evaluations: the optimiser's budget.
        reference: the paper's results (default the shipped ones).
        fields: the parameters to fit (the others stay at ``start``'s values).

    Returns:
        (fitted ``TeacherParameters``, final loss).
    """
    from scipy.optimize import minimize

    from .in_silico import episode_plan, query_states_for, resolve_protocol, simulate_changes, teacher_seed
    protocol = resolve_protocol(protocol)
    start = PAPER_FIT if start is None else start
    targets = paper_targets(reference)
    plan = episode_plan(protocol)
    states = [query_states_for(protocol, step)[None] for step in plan]
    n = 2 * n_per_group
    people = TeacherPopulation.draw(start, [teacher_seed(seed, p) for p in range(n)], len(plan),
                                    max(step["demonstrations"] for step in plan))

    unknown = [name for name in fields if name not in TRANSFORMS]
    if unknown:
        raise ValueError(f"fields: expected names from {sorted(TRANSFORMS)}, got also {unknown}")

    def loss(free):
        parameters = _from_free(free, start, fields)
        deltas = simulate_changes(protocol, people.with_parameters(parameters), 1, n_per_group, states)
        return fit_loss(deltas, targets)

    result = minimize(loss, _to_free(start, fields), method="Nelder-Mead",
                      options={"maxfev": max_evaluations, "xatol": 1e-3, "fatol": 1e-4, "adaptive": True})
    return _from_free(result.x, start, fields), float(result.fun)
