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
1b. **They treat "reach the line" like "reach a point on it".** On a line skill the arrow does
   not point only at the foot of the perpendicular: novices aim partway along the line, at
   where they take the line's target to be, the point target they practised and taught just
   before (skill 1's point, projected onto the line: (0.8, 1.2) m lies on the simulated line
   r1 = 0.8; (23, 11) cm is 0.4 cm off the uArm's line r1 = 2 r2). Their arrow aims at
   ``(1 - line_as_point) * foot + line_as_point * anchor`` with the same magnitude habit
   ``m_i * g``, so it keeps the damping-free pull of a point skill along a line the true skill
   leaves free (the simulated line skill only damps motion along it; the uArm's moves
   perpendicular to it). ``line_as_point`` = 0 is the perpendicular pull; 1 is "the line is
   the point". Why: the paper sees users "provide actions that point to the target, with a
   large magnitude" in the first phases, and its baselines for the line skill are no smaller
   than for the point skill (simulation 2.94 vs 2.93, physical 8.17 vs 6.00, from its changes
   and percentage reductions); a perpendicular pull alone gives line errors well below both
   (about 2.2 in simulation, 1.4 on the uArm, where the perpendicular pull is Theta itself
   scaled by m_i).
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
3-4 in space. With 3-D actions (the ``ur5-`` skills: a tool velocity in space) a turn needs an
   axis as well as an angle. The direction slip turns the arrow by its angle about an axis
   perpendicular to it (so it leaves the arrow off by exactly that angle, as in the plane), the
   axis's bearing around the arrow drawn per demonstration; the exploration turns all the
   episode's arrows alike about one axis drawn per episode. These axes are drawn after every
   other draw of a teacher, so planar teachers are the same people as before they existed.
   A novice's naive arrow on a moving target (a part on a conveyor) points at where the part
   is in the query state, not at the belt.
5. **Guided teachers move toward the optimal arrows.** After each demonstration with
   guidance (seeing their arrow beside the optimal one) ``w <- w + a_i (1 - w)``, with a
   learning rate ``a_i`` drawn per participant (logit-normal around ``learning_rate``).
   Watching a reproduction teaches a little too: ``w <- w + reproduction_learning (1 - w)``
   after every episode.
6. **Retention and transfer.** Without the arrows in front of them teachers apply only a part
   of what they learnt: ``w`` is multiplied by ``retention`` in unguided episodes and by
   ``transfer`` on a skill they were never guided on.

7. **They forget between sessions** (``Forgetting``, off unless given). Between the end of one
   protocol session and the start of the next, a delay of ``t`` days later, what a teacher
   understood decays toward the novice they were: ``w <- w * 2 ** (-t / half_life_days)``, an
   exponential forgetting curve (Ebbinghaus' shape; Murre and Dros, 2015, PLoS ONE 10(7):
   e0120644, replicate it). Their magnitude habit, learning rate and which skills they were
   guided on stay. The half-life is a design assumption for piloting and powering a follow-up
   study, **not fitted to any data**: the paper has one session, so nothing here says how
   fast its participants forget. ``paper-sim-followup``'s power is reported for a stated
   half-life (``mt_widgets/study/protocols/paper_sim_followup.toml``).

An **optimal teacher** (``OPTIMAL_TEACHER``) starts with ``w = 1`` and no noise: it draws the
optimal arrows and teaches the skill exactly.

Everything random about a participant is drawn once from their seed when they are created
(``TeacherPopulation.draw``): their traits and a table of standard-normal draws indexed by
episode and demonstration. Whoever runs them (the batched in-silico engine or the session
engine, one demonstration at a time) therefore gets exactly the same arrows.

``PAPER_FIT`` holds parameters fitted (``fit_to_paper``) so that an in-silico run of the
paper's simulation protocol lands near the paper's reported changes; ``PAPER_FIT_UARM`` the
same model's parameters fitted to the physical (uArm) experiment. ``paper_fit(protocol)``
(``mt_widgets.in_silico.plan``) picks the one for a protocol; ``mt_widgets.in_silico.fitting``
fits them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace

import numpy as np

from mt_widgets.core.targets import ConveyorTarget
from mt_widgets.core.validation import as_positive

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
        line_as_point: on a line skill, how far along the line toward the point they take for
            its target (the practised point projected onto the line) a novice aims, in [0, 1]:
            0 pulls perpendicular onto the line, 1 at that point.
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
    line_as_point: float = 0.0
    first_input_s: float = 2.5
    drawing_s: float = 1.2
    timing_spread: float = 0.4

    def __post_init__(self):
        for f in fields(self):
            as_positive(f.name, getattr(self, f.name), allow_zero=True)
        for name in ("retention", "transfer", "initial_understanding", "line_as_point"):
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
#: 0.05 rad and 0.05 (final loss 0.31, in squared units of the paper's SDs over 18 terms; 1.78
#: before the line-as-point habit, whose line baseline stayed near 2.2). What they say:
#: novices draw about twice the skill's own gain (``magnitude`` 2.02, spread 0.20 in log), and
#: on the line skill aim 63 % of the way from the foot of the perpendicular toward skill 1's
#: point (``line_as_point``); without guidance they turn all their arrows by about 0.49 rad
#: (28 degrees) SD per episode; guided, they close about 4 % of their gap to the optimal arrows
#: per demonstration (median; logit spread 1.43 across people), apply 75 % of it without the
#: arrows in front of them (``retention``) and 94 % of it on the line skill they were never
#: guided on (``transfer``). Watching reproductions taught nothing the fit could see
#: (``reproduction_learning`` fitted below 1e-28, written 0). ``compare_with_paper`` says how
#: near an in-silico run lands, row by row.
PAPER_FIT = TeacherParameters(
    magnitude=2.0227, magnitude_spread=0.20487, direction_noise=0.05, magnitude_noise=0.05, exploration=0.48804,
    learning_rate=0.040668, learning_spread=1.4264, reproduction_learning=0.0, retention=0.74928,
    transfer=0.93982, line_as_point=0.6273,
)

#: Parameters fitted to the paper's physical experiment (uArm Swift Pro, actions in cm):
#: ``fit_to_paper(n_per_group=500, seed=0, protocol="paper-uarm")`` from ``PAPER_FIT`` with
#: ``line_as_point`` started at 0.8, fitting every field of ``FITTED_FIELDS`` but
#: ``magnitude_spread``, held at the simulation's 0.20: fitted freely it collapses to zero
#: (every novice with the same habit) for a loss barely lower (1.34 against 1.56), the
#: exploration taking over all the between-person spread. Final loss 1.56 (18 terms), most of it
#: from the control group's rows, which move in the paper (-1.54 better by P3E8, +2.21 worse by
#: P5, SD 5.54) where teachers who only turn their arrows cannot move on average. What they say:
#: the same doubled magnitude habit (2.17), a stronger line-as-point habit (79 % of the way to
#: the foot of (23, 11) cm on the line: the paper's line baseline, 8.17, is well above its point
#: baseline, 6.00), exploration 0.53 rad, faster learning from guidance (8.9 % of the gap per
#: demonstration, the same for everyone: ``learning_spread`` fitted to < 1e-8, written 0; the
#: uArm episodes have 3 demonstrations, not 5), retention 90 % and transfer 97 %;
#: ``reproduction_learning`` again fitted to nothing (written 0).
PAPER_FIT_UARM = TeacherParameters(
    magnitude=2.1713, magnitude_spread=0.20487, direction_noise=0.05, magnitude_noise=0.05, exploration=0.53222,
    learning_rate=0.088566, learning_spread=0.0, reproduction_learning=0.0, retention=0.90155,
    transfer=0.9691, line_as_point=0.78953,
)

#: A teacher who already knows the skill and draws without slips: the machine-teaching optimum.
OPTIMAL_TEACHER = TeacherParameters(magnitude=1.0, magnitude_spread=0.0, direction_noise=0.0, magnitude_noise=0.0,
                                    exploration=0.0, learning_rate=0.0, learning_spread=0.0, retention=1.0,
                                    transfer=1.0, initial_understanding=1.0, timing_spread=0.0)


def logit(p: float) -> float:
    """log(p / (1 - p)), with p kept inside (0, 1)."""
    p = min(max(p, 1e-9), 1 - 1e-9)
    return float(np.log(p / (1 - p)))


def position_gain(theta) -> float:
    """g: the spectral norm of the position block of Theta (R, S): its first R columns (the features
    start with the end-effector's position, one coordinate per action component: 2 in the plane, 3 in space)."""
    theta = np.asarray(theta, dtype=float)
    return float(np.linalg.norm(theta[:, :theta.shape[0]], 2))


def naive_offsets(positions: np.ndarray, target) -> np.ndarray:
    """Vectors from end-effector positions (..., 2) to the nearest point of ``target``.

    Args:
        positions: (..., 2) in the skill's units.
        target: a ``Target`` (towards a point, perpendicular onto a line, or onto the nearest
            point of a user's own target).

    Returns:
        (..., 2) offsets in the positions' units (zero on the target).
    """
    positions = np.asarray(positions, dtype=float)
    return target.nearest(positions) - positions


def target_offsets(skill, states) -> np.ndarray:
    """What a novice pulls the tool toward at each query state: the vectors (N, R) from its end-effector
    to the nearest point of the skill's target, or, for a part moving on a conveyor, to the part where
    the state says it is."""
    positions, _ = skill.end_effector(states)
    if isinstance(skill.target, ConveyorTarget):
        return skill.target.at(skill.plant.conveyor_phase(states)) - positions
    return naive_offsets(positions, skill.target)


def line_foot(point, target) -> np.ndarray:
    """The foot of ``point`` (2,) on a target of extent (a line): its nearest point of the target."""
    return np.asarray(point, dtype=float) + naive_offsets(np.asarray(point, dtype=float), target)


def along_line_offsets(positions: np.ndarray, target, anchor) -> np.ndarray:
    """Vectors from the foot of each position on the line to the foot of ``anchor`` (model item 1b).

    Args:
        positions: (..., 2) end-effector positions in the skill's units.
        target: the skill's target; only a target of extent (``dimension`` >= 1, a line) has
            somewhere to move along.
        anchor: (2,) the point the teacher takes for the line's target, or None.

    Returns:
        (..., 2) offsets along the line; zeros for a point target or without an anchor.
    """
    positions = np.asarray(positions, dtype=float)
    if anchor is None or target.dimension == 0:
        return np.zeros_like(positions)
    anchor = np.asarray(anchor, dtype=float)
    if anchor.shape != (2,) or not np.all(np.isfinite(anchor)):
        raise ValueError(f"anchor: expected a finite point (2,), got {anchor!r}")
    return line_foot(anchor, target) - (positions + naive_offsets(positions, target))


def _rotate(vectors: np.ndarray, angles: np.ndarray) -> np.ndarray:
    c, s = np.cos(angles), np.sin(angles)
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def _turn_about(vectors: np.ndarray, axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Rodrigues' rotation of vectors (B, 3) about unit axes (B, 3) by angles (B,) rad."""
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    along = np.sum(axes * vectors, axis=-1, keepdims=True)
    return vectors * c + np.cross(axes, vectors) * s + axes * along * (1 - c)


def _unit(vectors: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return vectors / np.where(norm > 0, norm, 1.0)


def _turn_in_space(vectors: np.ndarray, slip: np.ndarray, slip_axes: np.ndarray, explore: np.ndarray,
                   explore_axes: np.ndarray) -> np.ndarray:
    """Arrows (B, 3) turned by the episode's exploration about its axis, then by the slip (rad) about the
    drawn axis made perpendicular to each arrow (model items 3-4 in space)."""
    turned = _turn_about(vectors, _unit(explore_axes), explore)
    direction = _unit(turned)
    across = slip_axes - np.sum(slip_axes * direction, axis=-1, keepdims=True) * direction
    return _turn_about(turned, _unit(across), slip)


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
        turn_axes: (B, episodes, max_demonstrations + 1, 3) standard normals: per demonstration the
            axis of the direction slip, last the episode's exploration axis (3-D actions only).
    """

    def __init__(self, parameters: TeacherParameters, traits, demonstration_noise, episode_noise, turn_axes):
        self.parameters = parameters
        self.traits = np.asarray(traits, dtype=float)
        self.demonstration_noise = np.asarray(demonstration_noise, dtype=float)
        self.episode_noise = np.asarray(episode_noise, dtype=float)
        self.turn_axes = np.asarray(turn_axes, dtype=float)
        p = parameters
        self.magnitude = p.magnitude * np.exp(p.magnitude_spread * self.traits[:, 0])
        if p.learning_rate == 0:
            self.learning_rate = np.zeros(len(self.traits))
        else:
            self.learning_rate = 1 / (1 + np.exp(-(logit(p.learning_rate) + p.learning_spread * self.traits[:, 1])))
        self.understanding = np.full(len(self.traits), float(p.initial_understanding))
        self.guided_skills: dict[str, np.ndarray] = {}

    def with_parameters(self, parameters: TeacherParameters) -> TeacherPopulation:
        """The same people (the same draws) with other parameters, back at the start."""
        return TeacherPopulation(parameters, self.traits, self.demonstration_noise, self.episode_noise, self.turn_axes)

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
        axes = np.empty((len(seeds), n_episodes, max_demonstrations + 1, 3))
        for i, seed in enumerate(seeds):
            rng = np.random.default_rng(seed)
            traits[i] = rng.standard_normal(2)
            demonstration[i] = rng.standard_normal((n_episodes, max_demonstrations, _PER_DEMONSTRATION))
            episode[i] = rng.standard_normal(n_episodes)
            # Last, so the draws above (all a planar teacher uses) do not depend on them.
            axes[i] = rng.standard_normal((n_episodes, max_demonstrations + 1, 3))
        return cls(parameters, traits, demonstration, episode, axes)

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

    def act(self, episode: int, demonstration: int, offsets, optimal, gain: float, skill_key: str, guided,
            along=None):
        """The arrows the teachers draw at one query state.

        Args:
            episode: 0-based episode index in the protocol.
            demonstration: 0-based demonstration index in the episode.
            offsets: (B, R) from the end-effector to the target (``target_offsets``); R = 2 in the
                plane, 3 in space.
            optimal: (B, R) the optimal arrows U_bar at this state.
            gain: the skill's position gain g (``position_gain``).
            skill_key: the skill taught (for transfer).
            guided: bool or (B,) whether each teacher sees guidance in this episode.
            along: (B, 2) from the foot on a target line to the point taken for the line's
                target (``along_line_offsets``), or None (a point skill).

        Returns:
            (B, R) actions, in the skill's action units.
        """
        p = self.parameters
        w = self.effective_understanding(skill_key, guided)[:, None]
        noise = self.demonstration_noise[:, episode, demonstration]
        aim = np.asarray(offsets, dtype=float)
        if along is not None:
            aim = aim + p.line_as_point * np.asarray(along, dtype=float)
        naive = (self.magnitude * gain)[:, None] * aim
        intended = (1 - w) * naive + w * optimal
        guided = np.broadcast_to(np.asarray(guided, dtype=bool), self.understanding.shape)
        explore = np.where(guided, 0.0, p.exploration * self.episode_noise[:, episode]) * (1 - w[:, 0])
        slip = p.direction_noise * noise[:, 0]
        if intended.shape[-1] == 2:
            drawn = _rotate(intended, slip + explore)
        elif intended.shape[-1] == 3:
            axes = self.turn_axes[:, episode]
            drawn = _turn_in_space(intended, slip, axes[:, demonstration], explore, axes[:, -1])
        else:
            raise ValueError(f"offsets: expected arrows of 2 (plane) or 3 (space) components, got {intended.shape[-1]}")
        return drawn * np.exp(p.magnitude_noise * noise[:, 1])[:, None]

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

    def forget(self, forgetting: Forgetting | None, delay_s: float) -> None:
        """Between sessions ``delay_s`` apart: understanding decays (``Forgetting``); None keeps it."""
        if forgetting is not None:
            self.understanding = self.understanding * forgetting.retained(delay_s)


@dataclass(frozen=True)
class Forgetting:
    """Forgetting between protocol sessions (model item 7 of the module docstring).

    Attributes:
        half_life_days: days after which half of what a teacher understood is gone (> 0;
            ``math.inf``: no forgetting). A design assumption, not fitted to data.
    """

    half_life_days: float

    def __post_init__(self):
        value = self.half_life_days
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ValueError(f"half_life_days: expected a number of days > 0 (math.inf: no forgetting), got {value!r}")

    def retained(self, delay_s: float) -> float:
        """The fraction of understanding kept after ``delay_s`` seconds."""
        delay_s = as_positive("delay_s", delay_s, allow_zero=True)
        return float(2.0 ** (-(delay_s / 86400.0) / self.half_life_days))


def with_parameters(base: TeacherParameters, **changes) -> TeacherParameters:
    """``base`` with some fields changed (validated)."""
    return replace(base, **changes)

