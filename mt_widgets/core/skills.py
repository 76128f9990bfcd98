"""Skills: what a teacher teaches. A skill is a target policy Theta on a plant's features.

``SKILLS`` holds the paper's four, read-only; the shipped arms' skills (the UR5's three, ``ur5-``
keys, the Panda's three, ``panda-``, the SO-101's two, ``so101-``) are promised to it by
``mt_widgets.arms``, which reads their URDFs (core reads no file), and each arm is built when one
of its skills is first asked for. A user
defines their own with ``Skill(...)``: a plant, a feature map, Theta (R x S), and the start state
its reproduction runs from; then passes it to a widget or a session directly, or adds it to a
``SkillRegistry`` they own.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, replace

import numpy as np

from .arm_plant import ArmPlant
from .chain_plant import ChainPlant
from .drawing import PlantDrawing, PoseSketch, TargetShape
from .features import (
    ConveyorFeatures,
    EndEffectorFeatures,
    FeatureMap,
    FunctionFeatures,
    PositionFeatures,
    ToolFeatures,
)
from .query_states import sample_query_states
from .targets import ConveyorTarget, LineTarget, PointTarget, SpacePointTarget, Target
from .uarm_plant import UArmPlant
from .validation import UnknownKeyError, as_bool, as_count, as_float_array, as_positive


@dataclass(frozen=True, eq=False)
class Skill:
    """A motor skill to teach.

    Args:
        key: a short identifier ("sim-point").
        title: a human title ("Reach the point (0.8, 1.2) m").
        plant: the plant it runs on.
        feature_map: phi for that plant.
        theta: (R, S) the target policy u = theta @ phi(x).
        start: the state every reproduction starts from.
        target: a ``Target`` (``PointTarget``, ``LineTarget`` or a user's own), or None.
        description: one or two sentences for a student.
        max_condition: the query-state sampler's condition-number threshold for this skill.
        policy: the target policy as a function states (N, state_dim) -> actions (N, R), for a
            skill whose target is not linear in its features (a curved path, a path around an
            obstacle; ``nonlinear_skills``). Then ``theta`` is the best linear policy on the
            features (what the paper's ridge learner can at best learn) and ``target_actions``
            are the policy's. None (the paper's skills): the target is ``theta @ phi(x)``.
    """

    key: str
    title: str
    plant: object
    feature_map: FeatureMap
    theta: np.ndarray
    start: np.ndarray
    target: Target | None = None
    description: str = ""
    max_condition: float = 20.0
    policy: Callable[[np.ndarray], np.ndarray] | None = None

    def __post_init__(self):
        theta = as_float_array("theta", self.theta, ndim=2, shape=(self.plant.action_dim, self.feature_map.dim))
        theta = theta.copy()
        theta.setflags(write=False)
        object.__setattr__(self, "theta", theta)
        start = self.plant.check_states("start", self.start).copy()
        if start.ndim != 1:
            raise ValueError(f"start: expected one state of shape ({self.plant.state_dim},), got {start.shape}")
        start.setflags(write=False)
        object.__setattr__(self, "start", start)
        as_positive("max_condition", self.max_condition)
        if self.target is not None and not isinstance(self.target, Target):
            raise TypeError(f"target: expected a Target (PointTarget, LineTarget or a subclass) or None, "
                            f"got {type(self.target).__name__}")
        if self.policy is not None and not callable(self.policy):
            raise TypeError(f"policy: expected a function states -> actions or None, got {type(self.policy).__name__}")
        if not isinstance(self.key, str) or not self.key:
            raise ValueError(f"key: expected a non-empty text, got {self.key!r}")

    def __repr__(self) -> str:
        return f"Skill({self.key!r}: {self.title})"

    # -- what a view needs to know -------------------------------------------------------------
    @property
    def robot(self) -> str:
        return self.plant.robot

    @property
    def units(self) -> str:
        return self.plant.units

    @property
    def action_units(self) -> str:
        return self.plant.action_units

    @property
    def state_dim(self) -> int:
        return self.plant.state_dim

    @property
    def n_features(self) -> int:
        return self.feature_map.dim

    @property
    def workspace(self):
        """The view extent (a ``Box`` with ``xlim``, ``ylim`` in ``units``)."""
        return self.drawing().view

    @property
    def default_duration(self) -> float:
        return self.plant.default_duration

    def end_effector(self, states):
        """(positions (..., 2), velocities (..., 2)) in ``units``."""
        return self.plant.end_effector(states)

    def drawing(self) -> PlantDrawing:
        """The plant's ``PlantDrawing``, with an arrow scale chosen for this skill if the plant gave none.

        The scale makes the skill's median action (theta @ phi at states drawn as query states
        are) a fifth of the view's width, so a typical arrow is clearly visible.
        """
        cached = self.__dict__.get("_drawing")
        if cached is not None:
            return cached
        drawing = self.plant.drawing()
        if drawing.action_length is None:
            drawing = replace(drawing, action_length=self._typical_action_length(drawing))
        # Cached: a generic plant's drawing samples states, and views ask for it often.
        object.__setattr__(self, "_drawing", drawing)
        return drawing

    def _typical_action_length(self, drawing: PlantDrawing) -> float:
        rng = np.random.default_rng(0)
        states = self.plant.sample_states(rng, 256)
        states = states[self.plant.is_valid_state(states)]
        typical = float(np.median(np.linalg.norm(self.target_actions(states), axis=-1))) if len(states) else 0.0
        span = drawing.view.xlim[1] - drawing.view.xlim[0]
        return 0.2 * span / typical if typical > 0 else 0.1 * span

    def sketch(self, states) -> PoseSketch:
        """What to draw of the plant at states (..., state_dim): its chain and velocity."""
        return self.plant.sketch(states)

    def target_shape(self) -> TargetShape | None:
        """The target's shape inside the plant's view, or None for a skill without a target."""
        return None if self.target is None else self.target.shape(self.drawing().view)

    # -- the science -----------------------------------------------------------------------------
    def features(self, states) -> np.ndarray:
        """phi for states (N, state_dim) -> (N, S)."""
        states = as_float_array("states", states, ndim=2, shape=(None, self.state_dim))
        return self.feature_map(states)

    def target_actions(self, states) -> np.ndarray:
        """The skill's own actions at states (N, state_dim) -> (N, R): theta @ phi(x), or the
        target policy's for a skill given one."""
        if self.policy is None:
            return self.features(states) @ self.theta.T
        states = as_float_array("states", states, ndim=2, shape=(None, self.state_dim))
        return as_float_array("actions returned by policy", self.policy(states), ndim=2,
                              shape=(len(states), self.plant.action_dim))

    @property
    def linear(self) -> bool:
        """Whether the target is linear in the features (``theta`` is the whole skill)."""
        return self.policy is None

    def query_states(self, seed=None, n: int | None = None) -> np.ndarray:
        """n (default S, the fewest given states that meet the rank condition) well-conditioned query states, seeded."""
        n = self.n_features if n is None else as_count("n", n)
        return sample_query_states(self.plant, self.feature_map, n, seed=seed, max_condition=self.max_condition)

    def reproduce(self, theta, duration: float | None = None, record_every: int | None = None):
        """Rolls out the policy ``theta`` from the skill's start.

        Args:
            theta: (R, S), or (B, R, S) for B rollouts stepped together.
            duration: seconds (default: the plant's, 10 s).
            record_every: control steps between recorded samples (default every step).

        Returns:
            A ``Trajectory`` for one theta, a ``TrajectoryBatch`` for a batch. A policy that
            drives the plant out of bounds comes back with ``diverged`` set, never as NaN.
        """
        theta = as_float_array("theta", theta, ndim=(2, 3), shape=(self.plant.action_dim, self.n_features))
        duration = self.default_duration if duration is None else duration
        batch = self.plant.rollout(theta.reshape((-1,) + self.theta.shape), self.feature_map, self.start,
                                   duration, record_every)
        return batch[0] if theta.ndim == 2 else batch

    def reproduce_policy(self, policy, duration: float | None = None, record_every: int | None = None):
        """Rolls out any policy, a function states (B, state_dim) -> actions (B, R), from the skill's start
        (a nonlinear target, or what a nonlinear learner learnt); a ``Trajectory``."""
        if not callable(policy):
            raise TypeError(f"policy: expected a function states -> actions, got {type(policy).__name__}")
        names = tuple(f"u{i + 1}" for i in range(self.plant.action_dim))
        # The policy as a feature map with Theta = I: the plant's generic rollout runs it unchanged.
        as_features = FunctionFeatures(self.plant, policy, names)
        duration = self.default_duration if duration is None else duration
        return self.plant.rollout(np.eye(len(names))[None], as_features, self.start, duration, record_every)[0]


def _paper_skills() -> dict[str, Skill]:
    sim = ArmPlant()
    uarm = UArmPlant()
    sim_features = EndEffectorFeatures(sim)
    uarm_features = PositionFeatures(uarm)
    # Reproductions start at rest at q = (0.3, 0.5): the end-effector at about (1.65, 1.01) m,
    # away from both targets, so a student sees the whole approach.
    sim_start = np.array([0.3, 0.5, 0.0, 0.0])
    # The uArm point skill starts at (18, -10) cm, the line skill at (26, -4) cm: inside the
    # workspace, off their targets, and placed so the true skill's path stays inside the
    # workspace all the way (the line skill moves along (-1, 2) onto r1 = 2 r2 at (19.2, 9.6)).
    uarm_point_start = np.array([18.0, -10.0])
    uarm_line_start = np.array([26.0, -4.0])
    # Thresholds: about the median condition number of random sets of S states for each plant
    # (sim 5 x 5: about 16; uArm 3 x 3 in cm: about 200, the bias column being small next to
    # positions of 14-30 cm), so accepted sets are ordinary rather than contrived while the worst
    # half, which would amplify a teacher's small slips the most, is never shown.
    skills = [
        Skill("sim-point", "Reach the point (0.8, 1.2) m", sim, sim_features,
              [[-1, 0, -1, 0, 0.8], [0, -1, 0, -1, 1.2]], sim_start, PointTarget((0.8, 1.2)),
              "A spring-damper pulling the arm's tip to the point (0.8, 1.2) m: force = -(r - r*) - rdot.",
              max_condition=20.0),
        Skill("sim-line", "Reach the line r1 = 0.8 m", sim, sim_features,
              [[-1, 0, -1, 0, 0.8], [0, 0, 0, -1, 0]], sim_start, LineTarget((0.8, 0.0), (0.0, 1.0)),
              "Pull the tip onto the vertical line r1 = 0.8 m, damping its motion along the line.",
              max_condition=20.0),
        Skill("uarm-point", "Reach the point (23, 11) cm", uarm, uarm_features,
              [[-0.2, 0, 4.6], [0, -0.2, 2.2]], uarm_point_start, PointTarget((23.0, 11.0)),
              "Each step, move a fifth of the way to the point (23, 11) cm.", max_condition=200.0),
        Skill("uarm-line", "Reach the line r1 = 2 r2", uarm, uarm_features,
              [[-0.04, 0.08, 0], [0.08, -0.16, 0]], uarm_line_start, LineTarget((0.0, 0.0), (2.0, 1.0)),
              "Each step, move towards the line r1 = 2 r2 along the direction (-1, 2).", max_condition=200.0),
    ]
    return {skill.key: skill for skill in skills}


def production_line_skills(prefix: str, arm: str, table: ChainPlant, part, fixture, above_part, max_condition: float,
                            line: ChainPlant | None = None,
                            conveyor_condition: float | None = None) -> dict[str, Skill]:
    """An arm's production-line skills, defined as the UR5's are: the action is the tool's velocity (m/s).

    ``<prefix>-reach``: v = 0.8 (part - r) from the home pose; ``<prefix>-place``: from the state
    ``above_part`` (as if just picked) across to the fixture and down onto it, the vertical gain
    half the horizontal one; with a plant ``line`` carrying a conveyor, ``<prefix>-conveyor``:
    v = 1.5 (o + s d - r) + speed d from the home pose.

    Args:
        prefix: the keys' prefix ("panda"); arm: the arm's name in the titles ("Panda").
        table: the arm's plant without a conveyor; line: with one, or None.
        part, fixture: (3,) m; above_part: the place skill's start state.
        max_condition, conveyor_condition: the query-state thresholds (about the median condition
            number of S random candidates, as for the paper's skills).
    """
    titles = dict((key, title) for title, key in production_line_titles(prefix, arm, line is not None))
    home = np.concatenate([table.home] + ([] if table.kinematic else [np.zeros(table.n_joints)]))
    part, fixture = np.asarray(part, dtype=float), np.asarray(fixture, dtype=float)
    reach = np.hstack([-0.8 * np.eye(3), 0.8 * part[:, None]]) + 0.0
    gains = np.diag([1.0, 1.0, 0.5])
    place = np.hstack([-gains, (gains @ fixture)[:, None]]) + 0.0
    at = ", ".join(f"{v:.2f}" for v in part)
    to = ", ".join(f"{v:.2f}" for v in fixture)
    skills = [
        Skill(f"{prefix}-reach", titles[f"{prefix}-reach"], table, ToolFeatures(table), reach, home,
              SpacePointTarget(tuple(part)),
              description=f"Move the {arm}'s tool to the part waiting on the table at ({at}) m: "
                          "velocity = 0.8 (part - tool).", max_condition=max_condition),
        Skill(f"{prefix}-place", titles[f"{prefix}-place"], table, ToolFeatures(table), place,
              np.asarray(above_part, dtype=float), SpacePointTarget(tuple(fixture)),
              description=f"Carry the part across to the fixture at ({to}) m, lowering it more slowly than it moves "
                          "across.", max_condition=max_condition),
    ]
    if line is not None:
        belt = line.conveyor
        direction, origin = np.array(belt.direction), np.array(belt.origin)
        follow = np.hstack([-1.5 * np.eye(3), 1.5 * direction[:, None],
                            (1.5 * origin + belt.speed * direction)[:, None]]) + 0.0
        skills.append(Skill(f"{prefix}-conveyor", titles[f"{prefix}-conveyor"], line,
                            ConveyorFeatures(line), follow, np.concatenate([home, [belt.phase_range[0]]]),
                            ConveyorTarget(belt.origin, belt.direction, belt.phase_range),
                            description=f"Catch up with the part riding the conveyor ({100 * belt.speed:.0f} cm/s) "
                                        "and move with it.", max_condition=conveyor_condition))
    return {skill.key: skill for skill in skills}


def production_line_titles(prefix: str, arm: str, conveyor: bool) -> tuple[tuple[str, str], ...]:
    """(title, key) of each skill ``production_line_skills(prefix, arm, ...)`` defines, without building one.

    ``conveyor``: whether the arm has a conveyor line (then ``<prefix>-conveyor`` too).
    """
    titles = ((f"{arm}: reach the part on the table", f"{prefix}-reach"),
              (f"{arm}: place the part at the fixture", f"{prefix}-place"))
    return titles + (((f"{arm}: follow the part on the conveyor", f"{prefix}-conveyor"),) if conveyor else ())


class _Promise:
    """Skills under known keys, built by ``build()`` the first time one of them is asked for."""

    def __init__(self, keys: tuple[str, ...], build: Callable[[], Iterable[Skill]]):
        self.keys, self.build = keys, build


class SkillRegistry(Mapping):
    """Skills by key, owned by whoever needs them: a course, a lab's study, a notebook.

    ``registry[key]`` gives a skill; a missing key raises a ``KeyError`` that names the known
    ones. ``add`` puts a skill in (a key is taken once unless ``replace=True``); ``defer`` promises
    skills under new keys, built when one of them is first asked for (listing the keys or asking
    ``key in registry`` builds nothing). A registry made with ``read_only=True`` (``SKILLS``) refuses
    changes: make your own, e.g. ``SkillRegistry(SKILLS.values())``, and add to that. It still takes
    promises of new keys, which never replace or remove a skill: that is how ``mt_widgets.arms``
    gives ``SKILLS`` the shipped arms' skills without core reading their URDFs.

    Args:
        skills: ``Skill`` objects to start with.
        read_only: refuse ``add``, item assignment and deletion.
    """

    def __init__(self, skills: Iterable[Skill] = (), *, read_only: bool = False):
        read_only = as_bool("read_only", read_only)
        self._skills: dict[str, Skill | _Promise] = {}
        # Two threads asking for a promised skill at once (a study server's pages) get one build.
        self._building = threading.Lock()
        for skill in skills:
            self._put(skill, replace=False)
        self.read_only = read_only

    def _put(self, skill, replace: bool) -> Skill:
        if not isinstance(skill, Skill):
            raise TypeError(f"skill: expected a Skill, got {type(skill).__name__}")
        replace = as_bool("replace", replace)
        if skill.key in self._skills and self._skills[skill.key] is not skill and not replace:
            raise ValueError(f"skill: the key {skill.key!r} is already taken by {self._skills[skill.key]!r}; "
                             f"pass replace=True to replace it")
        self._skills[skill.key] = skill
        return skill

    def _refuse_if_read_only(self) -> None:
        if self.read_only:
            raise TypeError("this skill registry is read-only (SKILLS holds the suite's own skills): make your own, "
                            "e.g. registry = SkillRegistry(SKILLS.values()); registry.add(skill), "
                            "or pass the skill itself")

    def add(self, skill: Skill, replace: bool = False) -> Skill:
        """Register ``skill`` under ``skill.key`` and return it."""
        self._refuse_if_read_only()
        return self._put(skill, replace)

    def __setitem__(self, key, skill) -> None:
        self._refuse_if_read_only()
        if not isinstance(skill, Skill) or skill.key != key:
            raise ValueError(f"key: expected the skill's own key {getattr(skill, 'key', None)!r}, got {key!r}")
        self._put(skill, replace=True)

    def __delitem__(self, key) -> None:
        self._refuse_if_read_only()
        self[key]  # the KeyError naming the known skills
        del self._skills[key]

    def defer(self, keys, build: Callable[[], Iterable[Skill]]) -> None:
        """Promise skills under ``keys`` (new ones), built by ``build()`` when one of them is first asked for.

        ``build`` returns the skills, exactly one under each promised key (checked when it runs).
        """
        if isinstance(keys, str) or not isinstance(keys, Iterable):
            raise TypeError(f"keys: expected skill keys (str), got {keys!r}")
        keys = tuple(keys)
        if not keys or not all(isinstance(key, str) and key for key in keys) or len(set(keys)) != len(keys):
            raise ValueError(f"keys: expected distinct non-empty skill keys, got {keys!r}")
        if not callable(build):
            raise TypeError(f"build: expected a function returning the skills, got {type(build).__name__}")
        taken = [key for key in keys if key in self._skills]
        if taken:
            raise ValueError(f"keys: expected keys not yet taken, got {taken} (already {self._skills[taken[0]]!r})")
        promise = _Promise(keys, build)
        for key in keys:
            self._skills[key] = promise

    def _keep(self, promise: _Promise) -> None:
        with self._building:
            waiting = [key for key in promise.keys if self._skills.get(key) is promise]
            if not waiting:
                return  # built meanwhile by another thread
            built = {}
            for skill in promise.build():
                if not isinstance(skill, Skill):
                    raise TypeError(f"build: expected Skills, got {type(skill).__name__}")
                built[skill.key] = skill
            if sorted(built) != sorted(promise.keys):
                raise ValueError(f"build: expected skills under the promised keys {list(promise.keys)}, "
                                 f"got {list(built)}")
            for key in waiting:  # a key replaced since (``add(..., replace=True)``) keeps its replacement
                self._skills[key] = built[key]

    def __getitem__(self, key) -> Skill:
        try:
            found = self._skills[key]
        except (KeyError, TypeError):
            raise UnknownKeyError(f"skill: expected one of the known skills ({', '.join(sorted(self._skills))}), "
                                  f"got {key!r}") from None
        if isinstance(found, _Promise):
            self._keep(found)
            found = self._skills[key]
        return found

    def __contains__(self, key) -> bool:
        try:
            return key in self._skills  # a promised key counts, unbuilt
        except TypeError:
            return False

    def __iter__(self) -> Iterator[str]:
        return iter(self._skills)

    def __len__(self) -> int:
        return len(self._skills)

    def __repr__(self) -> str:
        kind = "read-only " if self.read_only else ""
        return f"<{kind}SkillRegistry: {', '.join(self._skills)}>"


#: The paper's four skills, by key: "sim-point", "sim-line", "uarm-point", "uarm-line" (read-only). Once
#: ``mt_widgets`` is imported (any ``from mt_widgets.core import SKILLS`` imports it first), also the
#: shipped arms' ``mt_widgets.arms`` promises: the UR5's production line (issue 31): "ur5-reach",
#: "ur5-place", "ur5-conveyor"; the Panda's "panda-reach", "panda-place", "panda-conveyor"; the
#: SO-101's "so101-reach", "so101-place".
SKILLS: SkillRegistry = SkillRegistry(_paper_skills().values(), read_only=True)

#: The paper's own four keys, in the paper's order (the protocols, the demo and the planar views use these).
PAPER_SKILL_KEYS = ("sim-point", "sim-line", "uarm-point", "uarm-line")

