"""A protocol as the in-silico engine runs it: its episodes in order, their query states, and
which of the paper's experiments (and so which fitted teachers) it replicates.

Everything here reads the protocol the study runner loads (``mt_widgets.study.protocol``), and
the episodes and their query states come from the one place the session engine takes them
from (``mt_widgets.study.timeline``), so a synthetic study and a real one meet the same
episodes, in the same sessions, with the same query states.
"""

from __future__ import annotations

import numpy as np

from mt_widgets.core import UArmPlant
from mt_widgets.study.protocol import Protocol, load_protocol
from mt_widgets.study.timeline import episode_query_states, planned_episodes

from .teachers import PAPER_FIT, PAPER_FIT_UARM, TeacherParameters


def resolve_protocol(protocol):
    """A ``Protocol`` from a protocol object, a shipped name ("paper-sim") or a file path."""
    if protocol is None:
        protocol = "paper-sim"
    if isinstance(protocol, Protocol):
        return protocol
    return load_protocol(protocol)


def episode_plan(protocol) -> list[dict]:
    """The protocol's episodes in order, every session's (``mt_widgets.study.timeline.planned_episodes``):
    session, phase, phase_index, episode (1-based), skill, demonstrations, guidance, states_index,
    episode_index (0-based), and reproduced (whether the participant watches this episode's
    reproduction: every episode's, or each phase's last, as the protocol says)."""
    plan = []
    last = {}
    for step in planned_episodes(protocol):
        last[(step.session, step.phase)] = step.episode
    for step in planned_episodes(protocol):
        plan.append({"session": step.session, "phase": step.phase, "phase_index": step.phase_index,
                     "episode": step.episode, "skill": step.skill, "demonstrations": step.demonstrations,
                     "guidance": step.guidance, "states_index": step.states_index,
                     "episode_index": step.episode_index,
                     "reproduced": protocol.reproduce_after == "episode"
                     or step.episode == last[(step.session, step.phase)]})
    return plan


def query_states_for(protocol, step: dict, participant: int | None = None, study_seed: int | None = None) -> np.ndarray:
    """The query states of one episode, from the protocol's seed schedule.

    Args:
        protocol: the ``Protocol``.
        step: an ``episode_plan`` entry.
        participant: the enrolment number, used when the protocol draws states per participant.
        study_seed: overrides the protocol's seed (each simulated study of a power analysis
            has its own).

    Returns:
        (demonstrations, state_dim) states.
    """
    states, _ = episode_query_states(protocol, step["states_index"], step["episode"], step["demonstrations"],
                                     step["skill"], participant=participant, study_seed=study_seed)
    return states


def session_delays(protocol, delays=None) -> dict:
    """Seconds between the end of each session and the start of the next, by the later session's id.

    Args:
        protocol: the ``Protocol``.
        delays: {session id: seconds} for some sessions (a design explored in silico); the others
            get the earliest time their window allows (the design's planned delay).
    """
    delays = {} if delays is None else dict(delays)
    later = {s.id: s for s in protocol.sessions[1:]}
    unknown = sorted(set(delays) - set(later))
    if unknown:
        raise ValueError(f"delays: expected ids of later sessions {sorted(later)}, got {unknown}")
    return {sid: float(delays.get(sid, session.window.earliest_s)) for sid, session in later.items()}


def imagined_line_target(protocol, phase_index: int, session: str | None = None):
    """The point a novice takes for a line skill's target in phase ``phase_index`` (model item 1b).

    It is the point target they last practised or taught on the same robot before this phase
    (the practice skill counts first): in the paper's protocols skill 1's point, taught in P1 just
    before the line appears in P2 (their practice skill is a neutral point elsewhere, which P1
    comes after).

    Args:
        protocol: the ``Protocol``.
        phase_index: the 0-based index of the phase in its session's phases.
        session: the protocol session's id (None: the first); phases of earlier sessions count
            as taught before.

    Returns:
        (2,) the point in the skill's units, or None (a point skill, or no point taught before).
    """
    phase = protocol.session(session).phases[phase_index]
    skill = protocol.skill(phase.skill)
    if skill.target is None or skill.target.dimension == 0:
        return None
    before = [protocol.practice.skill] if protocol.practice.duration_s > 0 else []
    everything = protocol.all_phases
    before += [p.skill for p in everything[:everything.index(phase)]]
    anchor = None
    for key in before:
        other = protocol.skill(key)
        if type(other.plant) is type(skill.plant) and other.target is not None and other.target.dimension == 0:
            # A point target's nearest point to anywhere is the point itself.
            anchor = np.asarray(other.target.nearest(np.zeros(2)), dtype=float)
    return anchor


def default_parameters(protocol) -> TeacherParameters:
    """The fitted teacher parameters for a protocol: ``PAPER_FIT_UARM`` for a uArm protocol, else ``PAPER_FIT``."""
    return paper_fit(resolve_protocol(protocol))


def teacher_seed(seed: int, participant: int) -> np.random.SeedSequence:
    """The seed of synthetic participant ``participant`` of a run seeded ``seed``."""
    return np.random.SeedSequence(seed, spawn_key=(1, participant))



def runs_on_uarm(protocol) -> bool:
    """Whether a ``Protocol`` teaches skills of the uArm (its phases' skills run on the uArm plant)."""
    return any(isinstance(protocol.skill(phase.skill).plant, UArmPlant) for phase in protocol.phases)


def paper_fit(protocol=None) -> TeacherParameters:
    """The parameters fitted to the paper's experiment that ``protocol`` replicates.

    Args:
        protocol: a ``Protocol``, a shipped name ("paper-sim", "paper-uarm") or a path
            (default "paper-sim").

    Returns:
        ``PAPER_FIT_UARM`` for a protocol on the uArm, else ``PAPER_FIT``.
    """
    return PAPER_FIT_UARM if runs_on_uarm(resolve_protocol(protocol)) else PAPER_FIT


def participant_id(index: int) -> str:
    """The code of synthetic participant ``index`` in logs ("S001")."""
    return f"S{index + 1:03d}"


def experiment_of(protocol) -> str:
    """The paper's experiment a protocol replicates: "physical" on the uArm, else "simulation"."""
    return "physical" if runs_on_uarm(resolve_protocol(protocol)) else "simulation"
