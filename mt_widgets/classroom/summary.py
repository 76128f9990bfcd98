"""What the instructor's view shows, worked out from the students' events (no I/O, no widgets).

``summarise`` turns a ``ClassProgress`` into: where each student is (the lesson or exercise of
their latest event), each student's teaching errors (Theta's error) over their episodes (the class's own
version of the paper's Fig. 3a), per exercise the share of its checks each student has
passed, and who is stuck: no progress (a new lesson, a check passed for the first time, a
finished episode) for ``stuck_after_s`` seconds, with the words of the check they last failed.
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field

from .reader import ClassProgress

#: Seconds without progress after which a student counts as stuck (the view lets you change it).
STUCK_AFTER_S = 600.0


def parse_time(text: str) -> _dt.datetime:
    """An event's ISO 8601 UTC time ('2025-01-31T14:03:07.123Z') as an aware datetime."""
    return _dt.datetime.fromisoformat(text.replace("Z", "+00:00"))



def _number(value) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def episode_errors(event: dict) -> tuple[float | None, float | None]:
    """(theta_error, policy_risk) of a recorded episode event, None where it has none.

    Files written before the two had their own names hold one ``error``: every lesson that recorded
    episodes then (a5_teach_in_widget, tutorials 07, 08, 09 and 13) taught the ridge learner, whose
    ``error`` was Theta's error, so it reads as the theta_error.
    """
    if "theta_error" in event or "policy_risk" in event:
        return _number(event.get("theta_error")), _number(event.get("policy_risk"))
    return _number(event.get("error")), None

@dataclass
class StudentSummary:
    """One student's row in the instructor's view.

    Attributes:
        student: pseudonym.
        place: lesson or exercise of the latest event ("" if none).
        last_seen: time of the latest event.
        idle_s: seconds since the latest progress (a new lesson, a first pass, an episode).
        stuck: ``idle_s >= stuck_after_s``.
        theta_errors: Theta's error ||Theta_hat - Theta|| of the finished episodes that have a Theta,
            in order (the class's own Fig. 3a).
        episode_lessons: the lesson of each of those episodes.
        policy_risks: the policy risk of the finished episodes recorded with one, in order.
        checks: exercise -> {check: passed on its latest run}.
        last_failure: the words of the latest failed check run, if the student has not passed it since.
        torn_lines: lines skipped in the student's file.
    """

    student: str
    place: str = ""
    last_seen: _dt.datetime | None = None
    idle_s: float = 0.0
    stuck: bool = False
    theta_errors: list[float] = field(default_factory=list)
    episode_lessons: list[str] = field(default_factory=list)
    policy_risks: list[float] = field(default_factory=list)
    checks: dict[str, dict[str, bool]] = field(default_factory=dict)
    last_failure: str | None = None
    torn_lines: int = 0

    def passed_share(self, exercise: str) -> float:
        """Share of the exercise's checks (run so far) whose latest run passed."""
        checks = self.checks.get(exercise, {})
        return sum(checks.values()) / len(checks) if checks else 0.0


@dataclass
class ClassSummary:
    """The class at one moment."""

    students: list[StudentSummary]
    places: list[str]
    exercises: list[str]
    problems: list[str]
    now: _dt.datetime
    stuck_after_s: float

    @property
    def stuck(self) -> list[StudentSummary]:
        return [s for s in self.students if s.stuck]

    def at_place(self) -> dict[str, list[str]]:
        """place -> the students whose latest event is there, in course order."""
        return {place: [s.student for s in self.students if s.place == place] for place in self.places}

    def exercise_shares(self, exercise: str) -> list[float]:
        """Each student's passed share in ``exercise``, for the students who started it."""
        return [s.passed_share(exercise) for s in self.students if exercise in s.checks]


def summarise(progress: ClassProgress, now: _dt.datetime | None = None,
              stuck_after_s: float = STUCK_AFTER_S) -> ClassSummary:
    """Summarises a class folder as read by ``read_class``.

    Args:
        progress: the class's events.
        now: the moment to measure idleness against (default: now, UTC).
        stuck_after_s: seconds without progress after which a student is stuck.
    """
    if isinstance(stuck_after_s, bool) or not isinstance(stuck_after_s, (int, float)) or not stuck_after_s > 0:
        raise ValueError(f"stuck_after_s: expected a positive number of seconds, got {stuck_after_s!r}")
    now = now or _dt.datetime.now(_dt.timezone.utc)
    rows: list[StudentSummary] = []
    places: set[str] = set()
    exercises: set[str] = set()
    for student, data in sorted(progress.students.items()):
        row = StudentSummary(student, torn_lines=len(data.torn_lines))
        # Two kernels of one student interleave lines; time order is what happened.
        events = sorted((e for e in data.events if isinstance(e.get("time"), str)), key=lambda e: e["time"])
        last_progress = None
        for event in events:
            try:
                moment = parse_time(event["time"])
            except ValueError:
                continue
            kind = event.get("kind")
            place = event.get("lesson") or event.get("exercise")
            if isinstance(place, str) and place:
                row.place = place
                places.add(place)
            row.last_seen = moment
            progressed = False
            if kind == "lesson":
                progressed = True
            elif kind == "check" and isinstance(event.get("exercise"), str):
                exercise, check = event["exercise"], str(event.get("check"))
                exercises.add(exercise)
                checks = row.checks.setdefault(exercise, {})
                passed = event.get("passed") is True
                progressed = passed and not checks.get(check, False)
                checks[check] = passed or checks.get(check, False)
                if passed:
                    if row.last_failure and row.last_failure.startswith(f"{exercise}/{check}:"):
                        row.last_failure = None
                else:
                    row.last_failure = f"{exercise}/{check}: {event.get('message') or 'failed'}"
            elif kind == "episode":
                theta_error, policy_risk = episode_errors(event)
                if theta_error is not None:
                    row.theta_errors.append(theta_error)
                    row.episode_lessons.append(str(event.get("lesson", "")))
                if policy_risk is not None:
                    row.policy_risks.append(policy_risk)
                progressed = theta_error is not None or policy_risk is not None
            if progressed:
                last_progress = moment
        reference = last_progress or row.last_seen
        row.idle_s = max(0.0, (now - reference).total_seconds()) if reference else 0.0
        row.stuck = reference is not None and row.idle_s >= stuck_after_s
        rows.append(row)
    return ClassSummary(rows, sorted(places), sorted(exercises), list(progress.problems), now, float(stuck_after_s))
