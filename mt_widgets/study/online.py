"""Online participants: who a URL says the participant is, and where they go when they leave.

A protocol may have an ``[online]`` table for studies run on a participant pool such as
Prolific, where a participant arrives by a URL that carries their ID and must end on a
completion URL with a code (one code per way of ending, so the pool knows who completed,
who was screened out, who declined and who withdrew)::

    [online]
    # Which URL parameters identify the participant: "prolific" (PROLIFIC_PID is the ID;
    # STUDY_ID and SESSION_ID are recorded with the enrolment) or "participant" (the
    # generic ?participant=<ID>).
    identify = "prolific"

    [online.completion.completed]
    url = "https://app.prolific.com/submissions/complete?cc={code}"
    code = "C1MPL3T3"

    [online.completion.screened_out]
    url = "https://app.prolific.com/submissions/complete?cc={code}"
    code = "SCR33N3D"

    [online.completion.declined]
    url = "https://app.prolific.com/submissions/complete?cc={code}"
    code = "D3CL1N3D"

    [online.completion.withdrawn]
    url = "https://app.prolific.com/submissions/complete?cc={code}"
    code = "W1THDR4WN"

    # Optional: where a participant who cannot take part now goes to give their place back.
    # Prolific asks such a participant to "return" their submission (no payment, no penalty),
    # which they do on their Prolific submissions page, not on the study's page.
    return_url = "https://app.prolific.com/submissions"

Every outcome of ``OUTCOMES`` must be given: a participant who ends in a way the protocol
did not plan for would otherwise be stranded. ``{code}`` (optional) in a URL is replaced by
the outcome's code; a URL must be ``https://`` (or ``http://localhost`` for a pilot). An outcome
without ``url`` (a pilot's: no pool to go back to) ends on the page, which shows its code and
says the participant may close it; nothing redirects. The
``return_url`` is shown, never followed automatically, on the pages that turn a participant away
before their session starts (the study is busy, the link names no one, the session's window is
closed) and beside the completion code when a session ends early.

API (for the online participant page)::

    online = protocol.online                         # None without an [online] table
    arrival = online.participant_from_url({"PROLIFIC_PID": "5f...", "STUDY_ID": "...", ...})
    arrival.participant_id, arrival.parameters        # the ID (validated), what to record
    online.completion_url("completed")                # or a session's outcome: see outcome_of
    online.completion_url(outcome_of(session))

``participant_from_url`` refuses an ID that is missing, empty, over-long, path-like or holds
control characters (``mt_widgets.study.participants.validate_url_participant_id``) with a
message meant for the participant, before anything is written.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from urllib.parse import quote, urlsplit

from .participants import ParticipantIdError, validate_url_participant_id

#: The ways an online participant's session ends, each with its own completion URL and code.
OUTCOMES = ("completed", "screened_out", "declined", "withdrawn")
#: How a URL identifies a participant: the ID's parameter, and the parameters recorded beside it.
IDENTIFY = {
    "prolific": ("PROLIFIC_PID", ("STUDY_ID", "SESSION_ID")),
    "participant": ("participant", ()),
}
#: ``Session.ended`` (and completion) -> the online outcome.
_SESSION_OUTCOMES = {None: "completed", "completed": "completed", "ineligible": "screened_out",
                     "screened_out": "screened_out", "declined": "declined", "withdrawn": "withdrawn"}
_CODE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
#: The longest value of a recorded parameter (STUDY_ID, SESSION_ID): Prolific's are 24 characters.
MAX_PARAMETER_LENGTH = 128


@dataclass(frozen=True)
class Completion:
    """Where an outcome sends the participant: ``url`` with ``{code}`` replaced, and the code.
    ``url_template`` None: the outcome sends no one anywhere (a pilot's); the page shows the code."""

    outcome: str
    url_template: str | None
    code: str

    @property
    def url(self) -> str | None:
        if self.url_template is None:
            return None
        return self.url_template.replace("{code}", quote(self.code, safe=""))


@dataclass(frozen=True)
class UrlArrival:
    """A participant as a URL names them.

    Attributes:
        participant_id: the validated ID (from ``OnlineSettings.id_parameter``).
        parameters: the other identifying parameters, to record with the enrolment
            ({"STUDY_ID": ..., "SESSION_ID": ...} for Prolific; empty for "participant").
    """

    participant_id: str
    parameters: dict = field(default_factory=dict)


@dataclass(frozen=True)
class OnlineSettings:
    """The protocol's ``[online]`` table (see the module docstring).

    Attributes:
        identify: "prolific" or "participant".
        completions: {outcome: ``Completion``} for every outcome of ``OUTCOMES``.
        return_url: where a participant who cannot take part gives their place back (None: not given).
    """

    identify: str
    completions: Mapping[str, Completion]
    return_url: str | None = None

    @property
    def id_parameter(self) -> str:
        """The URL parameter that carries the participant's ID ("PROLIFIC_PID", "participant")."""
        return IDENTIFY[self.identify][0]

    @property
    def recorded_parameters(self) -> tuple[str, ...]:
        """URL parameters recorded with the enrolment (Prolific's STUDY_ID and SESSION_ID)."""
        return IDENTIFY[self.identify][1]

    def participant_from_url(self, query: Mapping) -> UrlArrival:
        """The participant a URL's query names.

        Args:
            query: the URL's parameters, {name: value} or {name: [values]} (as
                ``urllib.parse.parse_qs`` gives them).

        Raises:
            ParticipantIdError: the ID is missing, given twice, or not usable (empty,
                over-long, path-like, control characters), or a recorded parameter is too long
                or holds control characters; the message is for the participant.
            TypeError: ``query`` is not a mapping.
        """
        if not isinstance(query, Mapping):
            raise TypeError(f"query: expected a mapping of URL parameters, got {type(query).__name__}")
        values = {}
        for name in (self.id_parameter, *self.recorded_parameters):
            value = query.get(name)
            if isinstance(value, (list, tuple)):
                if len(value) > 1:
                    raise ParticipantIdError(f"{name}: the link gives it {len(value)} times; please use the link "
                                             f"exactly as the study gave it. Nothing was recorded.")
                value = value[0] if value else None
            values[name] = value
        participant_id = validate_url_participant_id(values[self.id_parameter], parameter=self.id_parameter)
        recorded = {}
        for name in self.recorded_parameters:
            value = values[name]
            if value is None:
                continue
            recorded[name] = _check_parameter(name, value)
        return UrlArrival(participant_id, recorded)

    def completion(self, outcome: str) -> Completion:
        """The ``Completion`` of ``outcome`` (one of ``OUTCOMES``, or a session's ``ended``)."""
        key = _SESSION_OUTCOMES.get(outcome) if isinstance(outcome, str) or outcome is None else None
        if key is None:
            raise ValueError(f"outcome: expected one of {list(OUTCOMES)} (or 'ineligible' for screened_out), "
                             f"got {outcome!r}")
        return self.completions[key]

    def completion_url(self, outcome: str) -> str | None:
        """The URL to send the participant to when their session ends with ``outcome`` (None: the
        protocol gives that ending no URL, and the page ends there with the code)."""
        return self.completion(outcome).url

    def as_dict(self) -> dict:
        table = {"identify": self.identify,
                 "completion": {k: {"code": c.code} | ({} if c.url_template is None else {"url": c.url_template})
                                for k, c in self.completions.items()}}
        if self.return_url is not None:
            table["return_url"] = self.return_url
        return table


def outcome_of(session) -> str:
    """The online outcome of a finished session: "completed", or how it ended early.

    Raises:
        ValueError: the session has not finished.
    """
    if not session.finished:
        raise ValueError("session: expected a finished session (completed or ended early), it is still running")
    return _SESSION_OUTCOMES[session.ended]


def _check_parameter(name: str, value) -> str:
    if not isinstance(value, str):
        raise ParticipantIdError(f"{name}: expected text, got {type(value).__name__}. Nothing was recorded.")
    if len(value) > MAX_PARAMETER_LENGTH or any(ord(ch) < 32 or ord(ch) == 127 for ch in value):
        raise ParticipantIdError(f"{name}: this link's {name} is not one the study gave out (too long or holding "
                                 f"control characters); please use the link exactly as the study gave it. Nothing "
                                 f"was recorded.")
    return value


def parse_online(check, raw: dict) -> OnlineSettings | None:
    """Validates a protocol's ``[online]`` table (``check``: the protocol's checker)."""
    if "online" not in raw:
        return None
    table = check.get(raw, ("online",), "table")
    check.unknown(table, ("online",), ("identify", "completion", "return_url"))
    identify = check.get(table, ("online", "identify"), "text", choices=tuple(IDENTIFY))
    completion = check.get(table, ("online", "completion"), "table")
    check.unknown(completion, ("online", "completion"), OUTCOMES)
    completions = {}
    for outcome in OUTCOMES:
        path = ("online", "completion", outcome)
        if outcome not in completion:
            check.fail(path, f"missing required table [online.completion.{outcome}] (its code, and the pool's "
                             f"url): every way a session can end ({', '.join(OUTCOMES)}) needs its completion code")
        entry = check.get(completion, path, "table")
        check.unknown(entry, path, ("url", "code"))
        url = _check_url(check, entry, path + ("url",)) if "url" in entry else None
        code = check.get(entry, path + ("code",), "text", nonempty=True)
        if not _CODE.match(code):
            check.fail(path + ("code",), f"expected a code of letters, digits, '-' or '_' (at most 64), got {code!r}")
        completions[outcome] = Completion(outcome, url, code)
    return_url = _check_url(check, table, ("online", "return_url")) if "return_url" in table else None
    return OnlineSettings(identify, completions, return_url)


def _check_url(check, table: dict, path: tuple) -> str:
    """A URL a participant is sent to: https (a pool's page), or http://localhost for a pilot."""
    url = check.get(table, path, "text", nonempty=True)
    parts = urlsplit(url)
    local = parts.scheme == "http" and parts.hostname in ("localhost", "127.0.0.1")
    if not (parts.scheme == "https" or local) or not parts.netloc or any(ch in url for ch in "\"'<> \t\n"):
        check.fail(path, f"expected an https:// URL (or http://localhost for a pilot), got {url!r}")
    return url
