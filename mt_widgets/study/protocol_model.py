"""The protocol as a model: its phases, practice, sessions, texts and plan, validated and frozen.

Built by ``mt_widgets.study.protocol_schema.parse_protocol`` (``load_protocol`` in
``mt_widgets.study.protocol``); read by the session engine, the in-silico engine and the
analysis. The file format is documented in ``mt_widgets.study.protocol``.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field

from mt_widgets.core import SKILLS, Skill

from .analysis_plan import AnalysisPlan
from .online import OnlineSettings
from .practice import PRACTICE_SKILLS
from .session_plan import ProtocolSession
from .steps import StudyStep

#: Texts a protocol may set for a session that ends early; these say it when it does not.
OPTIONAL_TEXTS = {
    "declined": "You chose not to take part. Thank you for your time; please let the experimenter know.",
    "ineligible": "Thank you for your interest. This study is looking for participants with a different "
                  "background, so it ends here. Please let the experimenter know.",
    "withdrawn": "You have withdrawn from the study. Nothing more is recorded. Thank you for your time; please "
                 "let the experimenter know.",
}


class ProtocolError(ValueError):
    """A protocol file that cannot be run, with where and why.

    Attributes:
        source: the file (or "<string>").
        line: 1-based line of the offending field or table, or None when unknown.
        field: the field's path, e.g. ``phases[2].episodes``.
    """

    def __init__(self, message: str, source: str = "<string>", line: int | None = None, field: str | None = None):
        self.source, self.line, self.field, self.reason = source, line, field, message
        where = source + (f", line {line}" if line else "")
        super().__init__(f"{where}: {field + ': ' if field else ''}{message}")


@dataclass(frozen=True)
class Phase:
    """One phase: ``episodes`` episodes of ``demonstrations`` demonstrations of one skill.

    Attributes:
        id: short name shown in logs and CSVs ("P3").
        index: 0-based position in the protocol.
        skill: the skill's name in the protocol (``Protocol.skills[skill]`` is the ``Skill``).
        episodes: number of episodes (>= 1).
        demonstrations: demonstrations per episode (>= 1).
        guidance: groups that see guidance after each demonstration.
        instructions: text shown before the phase, the same for every group.
        states_index: the seed position of this phase's query states: its position among every
            session's phases, or that of the phase ``states_from`` names.
        session: the id of the protocol session it belongs to ("main").
    """

    id: str
    index: int
    skill: str
    episodes: int
    demonstrations: int
    guidance: tuple[str, ...]
    instructions: str
    states_index: int
    session: str = "main"

    def guidance_for(self, group: str) -> bool:
        return group in self.guidance


@dataclass(frozen=True)
class Practice:
    """Free drawing before the study: ``duration_s`` seconds on ``skill`` (0: no practice).

    Attributes:
        skill: the practice skill's key; the shipped protocols use a neutral one that no phase
            uses (``mt_widgets.study.practice``).
        duration_s: seconds of practice.
        text: shown above the practice.
        reproduction: whether each practice round ends with the robot reproducing what it
            learnt (False: arrows are drawn and confirmed, nothing is learnt or played back).
    """

    skill: str
    duration_s: float
    text: str
    reproduction: bool = True


class ProtocolSkills(Mapping):
    """The skills a protocol names, by name: read-only, and picklable (unlike a ``MappingProxyType``),
    since in-silico studies send the protocol to worker processes."""

    def __init__(self, skills: Mapping[str, Skill]):
        self._skills = dict(skills)

    def __getitem__(self, name: str) -> Skill:
        return self._skills[name]

    def __iter__(self):
        return iter(self._skills)

    def __len__(self) -> int:
        return len(self._skills)

    def __repr__(self) -> str:
        return f"ProtocolSkills({sorted(self._skills)})"


@dataclass(frozen=True)
class Protocol:
    """A validated protocol. Build it with ``load_protocol`` or ``parse_protocol``.

    ``data`` is the normalised plain-data form (what ``study.json`` stores and what the hash
    covers); ``source_text`` the file as written.
    """

    name: str
    title: str
    groups: tuple[str, ...]
    lam: float
    seed: int
    query_states: str
    reproduction_duration_s: float | None
    block_size: int
    assignment_seed: int
    texts: dict[str, str]
    practice: Practice
    phases: tuple[Phase, ...]
    data: dict = field(repr=False, compare=False)
    source_text: str = field(default="", repr=False, compare=False)
    source: str = field(default="<string>", compare=False)
    #: The skills its phases name, by name (see ``resolve_protocol_skills``).
    skills: Mapping[str, Skill] = field(default_factory=lambda: ProtocolSkills({**SKILLS, **PRACTICE_SKILLS}),
                                        repr=False, compare=False)
    guidance_modality: str = "arrows+words"
    #: How demonstrations are given: "drawn" on the screen, or "hand" (moving the uArm by hand).
    demonstration_modality: str = "drawn"
    before: tuple[StudyStep, ...] = ()
    after: tuple[StudyStep, ...] = ()
    withdrawal: str = "exclude"
    analysis: AnalysisPlan = AnalysisPlan()
    #: The protocol's sessions in order (``ProtocolSession``); the first holds ``phases``,
    #: ``before`` and ``after``. One unless the protocol has ``[[sessions]]``.
    sessions: tuple = ()
    #: The ``[online]`` table (``mt_widgets.study.online.OnlineSettings``), or None.
    online: OnlineSettings | None = None
    #: When the robot reproduces what it learnt: "episode" (after every episode) or "phase"
    #: (after each phase's last episode).
    reproduce_after: str = "episode"
    #: The robot's learner (``learner = ...``; a name of ``mt_widgets.core.LEARNERS``): "ridge",
    #: the paper's, with ``lam``, unless the protocol says otherwise.
    learner: str = "ridge"
    #: (low, high) band of the learner's sensitivity ||A||_F every episode's query states are
    #: drawn within (``mt_widgets.study.timeline``), or None (plain seeded draws, as the paper).
    matched_difficulty: tuple | None = None

    def __post_init__(self):
        if not self.sessions:  # built by hand (tests, in-silico copies): one session of its phases
            object.__setattr__(self, "sessions", (ProtocolSession("main", 0, self.phases, self.before, self.after,
                                                                  self.texts, None),))

    def session(self, session_id: str | None = None) -> ProtocolSession:
        """The ``ProtocolSession`` with this id (None: the first)."""
        if session_id is None:
            return self.sessions[0]
        for session in self.sessions:
            if session.id == session_id:
                return session
        raise KeyError(f"session_id: expected one of {[s.id for s in self.sessions]}, got {session_id!r}")

    @property
    def all_phases(self) -> tuple[Phase, ...]:
        """Every session's phases, in order (``phases`` is the first session's)."""
        return tuple(phase for session in self.sessions for phase in session.phases)

    def any_phase(self, phase_id: str) -> Phase:
        """A phase of any session, by id."""
        for phase in self.all_phases:
            if phase.id == phase_id:
                return phase
        raise KeyError(f"phase_id: expected one of {[p.id for p in self.all_phases]}, got {phase_id!r}")

    @property
    def steps(self) -> tuple[StudyStep, ...]:
        """Every step around the task, those before it first."""
        return self.before + self.after

    def step(self, step_id: str) -> StudyStep:
        for step in (step for session in self.sessions for step in session.steps):
            if step.id == step_id:
                return step
        raise KeyError(f"step_id: expected one of {[s.id for ses in self.sessions for s in ses.steps]}, "
                       f"got {step_id!r}")

    def skill(self, key: str) -> Skill:
        """The ``Skill`` a phase or the practice names (``skills``: the paper's, the neutral
        practice skills and any the protocol brings)."""
        if key not in self.skills:
            raise KeyError(f"key: expected one of {sorted(self.skills)}, got {key!r}")
        return self.skills[key]

    @property
    def hash(self) -> str:
        """sha256 of the canonical JSON of ``data``: equal for protocols that run the same."""
        return protocol_hash(self.data)

    @property
    def n_episodes(self) -> int:
        return sum(phase.episodes for phase in self.phases)

    def phase(self, phase_id: str) -> Phase:
        for phase in self.phases:
            if phase.id == phase_id:
                return phase
        raise KeyError(f"phase_id: expected one of {[p.id for p in self.phases]}, got {phase_id!r}")


def protocol_hash(data: dict) -> str:
    canonical = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return "sha256:" + hashlib.sha256(canonical.encode()).hexdigest()
