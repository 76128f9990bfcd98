"""Replaying a participant log against the timeline: where the participant is, from the log alone.

Each step of a timeline (``mt_widgets.study.timeline``) is completed by exactly one logged
event, so the position in the timeline is a pure function of the log. The events are checked
against the timeline in order: a duplicated or missing event is detected (a ``LogError``
naming the event), never silently accepted. The event types are in ``mt_widgets.study.schema``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .jsonl import LogError
from .timeline import ENDING_EVENTS, Slot, StepKind


def completed_slot(event: dict, steps) -> Slot | None:
    """The timeline slot an event completes, or None (events that complete no step).

    Args:
        event: a (migrated) log event.
        steps: the session's ``StudyStep``s (a step event names its step by id).
    """
    kind = event["type"]
    if kind == "screen_done":
        return Slot(StepKind(event["screen"]), event.get("phase_index"), event.get("episode"))
    if kind == "consent_given":
        return _step_slot(event["step"], steps) if event.get("step") else Slot(StepKind.CONSENT)
    if kind == "step_done":
        return _step_slot(event["step"], steps)
    if kind == "practice_finished":
        return Slot(StepKind.PRACTICE)
    if kind == "demonstration":
        return Slot(StepKind.DEMONSTRATION, event["phase_index"], event["episode"], event["index"])
    if kind == "episode_finished":
        return Slot(StepKind.EPISODE_END, event["phase_index"], event["episode"])
    return None


def _step_slot(step_id: str, steps) -> Slot:
    ids = [step.id for step in steps]
    if step_id not in ids:
        raise LogError(f"step {step_id!r} in the log is not a step of this protocol ({ids})")
    return Slot(StepKind.STEP, index=ids.index(step_id))


def describe(slot: Slot | None, plan) -> str:
    """A slot in words ("demonstration (P3, episode 2, demonstration 4)") for messages and logs."""
    if slot is None:
        return "the end of the protocol"
    if slot.kind == StepKind.STEP:
        step = plan.steps[slot.index]
        return f"{step.kind} step {step.id!r}"
    where = []
    if slot.phase_index is not None:
        where.append(plan.phases[slot.phase_index].id)
    if slot.episode is not None:
        where.append(f"episode {slot.episode}")
    if slot.index is not None:
        where.append(f"demonstration {slot.index + 1}")
    return str(slot.kind) + (f" ({', '.join(where)})" if where else "")


@dataclass
class Replayed:
    """What a log says of a session.

    Attributes:
        position: index of the first slot without its event.
        episodes: {(phase_index, episode): the episode_started event}.
        demonstrations: {(phase_index, episode): the logged demonstration events, in order} (the
            session records them into each episode's ``TeachingEpisode``, the one place they live).
        finished: {(phase_index, episode): the episode_finished event}.
        ended: why the session ended early ("declined", "ineligible", "withdrawn"), or None.
    """

    position: int = 0
    episodes: dict = field(default_factory=dict)
    demonstrations: dict = field(default_factory=dict)
    finished: dict = field(default_factory=dict)
    ended: str | None = None


def replay(events: list[dict], slots: list[Slot], plan) -> Replayed:
    """Checks ``events`` against ``slots`` in order and returns where they leave the session.

    Raises:
        LogError: an event that completes another step than the next one of the timeline.
    """
    state = Replayed()
    for event in events:
        if event["type"] in ENDING_EVENTS:
            state.ended = ENDING_EVENTS[event["type"]]
            continue
        if event["type"] == "episode_started":
            state.episodes[(event["phase_index"], event["episode"])] = event
            continue
        slot = completed_slot(event, plan.steps)
        if slot is None:
            continue
        expected = slots[state.position] if state.position < len(slots) else None
        if slot != expected:
            raise LogError(f"event seq {event['seq']} ({event['type']}) completes {describe(slot, plan)}, "
                           f"but the protocol expects {describe(expected, plan)} next; the log does not match "
                           f"this protocol or holds a duplicate")
        if slot.kind == StepKind.DEMONSTRATION:
            state.demonstrations.setdefault((slot.phase_index, slot.episode), []).append(event)
        if slot.kind == StepKind.EPISODE_END:
            state.finished[(slot.phase_index, slot.episode)] = event
        state.position += 1
    return state
