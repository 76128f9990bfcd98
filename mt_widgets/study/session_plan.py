"""A protocol's sessions: one sitting or several (a main session, then follow-ups a set time later).

A protocol without ``[[sessions]]`` has one session, ``main``, made of its top-level phases
and steps. Each ``[[sessions]]`` table adds a later session, in order, with its own phases,
steps and texts, and a window after the end of the previous session::

    [[sessions]]
    id = "followup"                     # a plain name; BIDS writes it as ses-<id without - and _>
    welcome = "..."                     # the session's own texts (reproduction defaults to the
    instructions = "..."                # protocol's)
    thank_you = "..."

    [sessions.window]                   # measured from the end of the previous session
    earliest = "7d"                     # durations: a number and s, min, h, d or w ("36h", "1w")
    latest = "14d"                      # optional: no upper bound when absent
    too_early = "refuse"                # "refuse": the participant is told to come back later;
    too_late = "flag"                   # "flag": the session runs, flagged in the log
    too_early_text = "..."              # optional: the words shown ({opens} is replaced by the
    too_late_text = "..."               # date the window opens, {closed} by when it closed)

    [[sessions.phases]]                 # as [[phases]]; ids unique in the whole protocol, and
    id = "F1"                           # states_from may name a phase of an earlier session
    ...
    [[sessions.before]]                 # as [[before]] / [[after]]; ids unique in the protocol
    [[sessions.after]]

The first session's id is ``main`` unless the top level says ``session = "..."``. Practice
and the default consent belong to the first session. A returning participant keeps their
group and sees only the session they are in (``mt_widgets.study.session.Session.arrive``).

Query states: a later session's phases draw their seeds at positions after every earlier
session's phases (``Phase.states_index``), so no follow-up phase repeats a main-session
phase's states unless its ``states_from`` says so; the main session's seeds are those of a
one-session protocol.
"""

from __future__ import annotations

import datetime as _dt
import re
from dataclasses import dataclass

#: What a protocol can say happens outside a session's window.
WINDOW_ACTIONS = ("refuse", "flag")
_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0, "w": 604800.0}
_DURATION = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*(s|min|h|d|w)\s*$")

DEFAULT_TOO_EARLY = ("Thank you for coming back. This session opens on {opens}; please come back then with "
                     "the same link or code. Nothing was recorded today.")
DEFAULT_TOO_LATE = ("Thank you for coming back. The time for this session ended on {closed}, so it cannot "
                    "be run any more. Nothing was recorded today; please let the experimenter know.")
DEFAULT_LATE_FLAGGED = "This session is later than planned; it runs, and the log says so."


def parse_duration(text) -> float:
    """Seconds of a duration written as a number and a unit: "90s", "30min", "36h", "7d", "1w".

    Raises:
        TypeError: not text.
        ValueError: not a number followed by one of s, min, h, d, w.
    """
    if not isinstance(text, str):
        raise TypeError(f"duration: expected text such as '7d', got {type(text).__name__} {text!r}")
    match = _DURATION.match(text)
    if not match:
        raise ValueError(f"duration: expected a number and a unit (s, min, h, d, w), e.g. '7d', got {text!r}")
    return float(match.group(1)) * _UNITS[match.group(2)]


def bids_label(session_id: str) -> str:
    """The BIDS ``ses-`` label of a session: its id without '-' and '_' (BIDS labels are alphanumeric)."""
    return re.sub(r"[^A-Za-z0-9]", "", session_id)


def as_utc(now) -> _dt.datetime:
    """``now`` as an aware UTC datetime (None: the current time).

    Raises:
        TypeError: not a datetime.
        ValueError: a naive datetime (its time zone would be a guess).
    """
    if now is None:
        return _dt.datetime.now(_dt.timezone.utc)
    if not isinstance(now, _dt.datetime):
        raise TypeError(f"now: expected a datetime with a time zone, got {type(now).__name__}")
    if now.tzinfo is None or now.utcoffset() is None:
        raise ValueError(f"now: expected a datetime with a time zone (e.g. datetime.now(timezone.utc)), got the "
                         f"naive {now.isoformat()}")
    return now.astimezone(_dt.timezone.utc)


def _when(moment: _dt.datetime) -> str:
    return moment.strftime("%A %d %B %Y, %H:%M UTC")


@dataclass(frozen=True)
class WindowCheck:
    """Where an arrival falls in a session's window.

    Attributes:
        status: "open" (inside), "early" or "late".
        action: "start" (inside), or the protocol's "refuse" / "flag" for early or late.
        opens_at, closes_at: the window (closes_at None when it has no end).
        delay_s: seconds since the previous session ended.
        message: the words for the participant (empty when inside the window).
    """

    status: str
    action: str
    opens_at: _dt.datetime
    closes_at: _dt.datetime | None
    delay_s: float
    message: str

    def as_dict(self) -> dict:
        return {"status": self.status, "action": self.action, "opens_at": _iso(self.opens_at),
                "closes_at": None if self.closes_at is None else _iso(self.closes_at), "delay_s": self.delay_s,
                "message": self.message}


def _iso(moment: _dt.datetime) -> str:
    return moment.isoformat(timespec="milliseconds").replace("+00:00", "Z")


@dataclass(frozen=True)
class Window:
    """When a session may run, after the end of the previous one (see the module docstring).

    Attributes:
        earliest_s, latest_s: seconds after the previous session's end (latest_s None: no end).
        too_early, too_late: "refuse" or "flag".
        too_early_text, too_late_text: the words shown when refused ({opens} / {closed} replaced).
    """

    earliest_s: float
    latest_s: float | None
    too_early: str = "refuse"
    too_late: str = "flag"
    too_early_text: str = DEFAULT_TOO_EARLY
    too_late_text: str = DEFAULT_TOO_LATE

    def check(self, previous_end, now=None) -> WindowCheck:
        """Where ``now`` falls after a previous session that ended at ``previous_end``.

        Args:
            previous_end: an aware datetime.
            now: an aware datetime (None: the current time).
        """
        previous_end, now = as_utc(previous_end), as_utc(now)
        opens = previous_end + _dt.timedelta(seconds=self.earliest_s)
        closes = None if self.latest_s is None else previous_end + _dt.timedelta(seconds=self.latest_s)
        delay = (now - previous_end).total_seconds()
        fill = {"opens": _when(opens), "closed": _when(closes) if closes else ""}
        if now < opens:
            text = self.too_early_text.format(**fill) if self.too_early == "refuse" else ""
            return WindowCheck("early", self.too_early, opens, closes, delay, text)
        if closes is not None and now > closes:
            text = self.too_late_text.format(**fill) if self.too_late == "refuse" else DEFAULT_LATE_FLAGGED
            return WindowCheck("late", self.too_late, opens, closes, delay, text)
        return WindowCheck("open", "start", opens, closes, delay, "")

    def describe(self) -> str:
        """The window in words, e.g. "7 d to 14 d after the previous session"."""
        def words(seconds):
            for unit in ("w", "d", "h", "min", "s"):
                if seconds >= _UNITS[unit] and (seconds / _UNITS[unit]).is_integer():
                    return f"{seconds / _UNITS[unit]:g} {unit}"
            return f"{seconds:g} s"
        end = "with no end" if self.latest_s is None else f"to {words(self.latest_s)}"
        return f"{words(self.earliest_s)} {end} after the previous session"


@dataclass(frozen=True)
class ProtocolSession:
    """One session of a protocol: its phases and steps, texts, and window.

    Attributes:
        id: a plain name ("main", "followup-1w").
        index: 0-based position among the protocol's sessions.
        phases: its ``Phase``s (``Phase.index`` counts within the session).
        before, after: its ``StudyStep``s around the task.
        texts: welcome, instructions, reproduction, thank_you (and the early-ending texts).
        window: when it may run after the previous session (None for the first).
        practice: whether the protocol's practice runs in this session (the first only).
        default_consent: whether the default consent screen follows the welcome when the
            steps run hold no consent step of their own (the first session only).
    """

    id: str
    index: int
    phases: tuple
    before: tuple = ()
    after: tuple = ()
    texts: dict | None = None
    window: Window | None = None
    practice: bool = True
    default_consent: bool = True

    @property
    def steps(self) -> tuple:
        return self.before + self.after

    @property
    def bids_label(self) -> str:
        return bids_label(self.id)

    @property
    def n_episodes(self) -> int:
        return sum(phase.episodes for phase in self.phases)

    def phase(self, phase_id: str):
        for phase in self.phases:
            if phase.id == phase_id:
                return phase
        raise KeyError(f"phase_id: expected one of {[p.id for p in self.phases]}, got {phase_id!r}")


def parse_window(check, table: dict, path: tuple) -> Window:
    """Validates a ``[sessions.window]`` table (``check``: the protocol's checker)."""
    check.unknown(table, path, ("earliest", "latest", "too_early", "too_late", "too_early_text", "too_late_text"))
    values = {}
    for key in ("earliest", "latest"):
        if key not in table and key == "latest":
            values[key] = None
            continue
        text = check.get(table, path + (key,), "text")
        try:
            values[key] = parse_duration(text)
        except ValueError as error:
            check.fail(path + (key,), str(error).split(": ", 1)[1])
    if values["latest"] is not None and values["latest"] < values["earliest"]:
        check.fail(path + ("latest",), f"expected latest >= earliest ({table['earliest']}), got {table['latest']}")
    actions = {key: check.get(table, path + (key,), "text", default=default, choices=WINDOW_ACTIONS)
               for key, default in (("too_early", "refuse"), ("too_late", "flag"))}
    texts = {}
    for key, default in (("too_early_text", DEFAULT_TOO_EARLY), ("too_late_text", DEFAULT_TOO_LATE)):
        text = check.get(table, path + (key,), "text", nonempty=True, default=default)
        try:
            text.format(opens="", closed="")
        except (KeyError, IndexError, ValueError):
            check.fail(path + (key,), "expected text whose only {placeholders} are {opens} and {closed} (write "
                                      "{{ and }} for braces)")
        texts[key] = text
    return Window(values["earliest"], values["latest"], actions["too_early"], actions["too_late"],
                  texts["too_early_text"], texts["too_late_text"])
