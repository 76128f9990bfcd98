"""What the study's files hold, the schema version each carries, and the migrations that read old ones.

Research data must be readable years later, so every file of a study folder says which schema
wrote it, and readers check it: a file of a newer schema than this code knows is refused (it
may mean something this code would misread); an older one is read through an explicit
migration below, never by filling gaps with silent defaults.

Versions (``LOG_FORMAT``, the same number for every file of a study folder):

- 1: mt-widgets up to commit eeb8693 (December 2026). ``study.json`` said ``"format": 1``; participant
  logs, enrolment and outcome records carried no version.
- 2: every file carries it: ``study.json`` ``"format": 2``; a participant log's
  ``session_started`` event ``"format": 2`` (and each ``session_resumed`` the format of the
  events it starts); every enrolment and outcome record ``"format": 2``.

Migration 1 -> 2 (``migrate_events``, ``migrate_record``, ``migrate_study_meta``):

- ``session_started`` gains ``session``: the protocol's first session (format 1 knew one session).
- ``episode_started`` without ``guidance_modality`` (logs older than that field, which showed
  guidance as arrows with words, the only way then) gains ``"arrows+words"``: stated here,
  once, rather than as a default wherever the field is read.
- ``format`` becomes 2 on every migrated record (``migrated_from`` = 1 says it was migrated).

A format-1 log may be continued by this code (a study running across an upgrade): its
``session_resumed`` event then says ``"format": 2``, and only the events before it are
migrated. ``tests/data/study-v1`` is a folder written by format-1 code; a test reads it.

Participant log events (one JSON object a line; ``mt_widgets.study.log`` writes them) all have
``seq`` (0-based, consecutive), ``type``, ``time`` (ISO 8601 UTC), ``participant`` and
``study``; by type:

- ``session_started``: format, session (the protocol session's id), software_version,
  protocol_hash, protocol_name, group, enrolment (the enrolment record), lam, numpy_version,
  python_version; window (``WindowCheck.as_dict()``) and arrived_at when the arrival was
  checked against a session window; repaired_torn_line when a kill had torn the session's very
  first event before it (the start is then made again, and says so).
- ``session_resumed``: format, software_version, protocol_hash, at (the step resumed at),
  repaired_torn_line (bytes of a torn last line ended by this resume; 0 if none).
- ``screen_done``: screen (welcome, instructions, phase_intro, reproduction), phase_index,
  phase, episode (where they apply).
- ``consent_given``: step (the consent step's id, absent for the default consent);
  ``consent_declined``: step.
- ``step_done``: step (id), kind, and by kind: answers {item: value} (eligibility, and a
  step with an item that screens, add eligible (bool)); watched_to_end (bool) and plays (int) for a video.
- ``screened_out``: step, answers (the step's answers, one of them not eligible).
- ``withdrawn``: reason, data ("exclude" or "delete", the protocol's policy), at (the step).
- ``practice_started``: skill, duration_s; ``practice_finished``: duration_s (as measured
  by the caller, seconds).
- ``episode_started``: phase, phase_index, episode (1-based), skill, guidance (bool),
  n_demonstrations, query_states (N x state_dim), features (N x S), theta (R x S), lam,
  optimal (N x R), exact (bool), guidance_modality, seed {study_seed, spawn_key}; for a
  protocol's learner without a Theta on the features also learner (its name) and
  learner_parameters.
- ``demonstration``: phase, phase_index, episode, index (0-based), state, action, optimal,
  guidance_shown (bool), time_to_first_input_s, drawing_duration_s, response_time_s (from
  the state's appearance to the submission, measured by the engine), input (method, redraws,
  ... as given by the caller), modality ("hand" for an input method "hand", else "drawn").
- ``episode_finished``: phase, phase_index, episode, skill, guidance, actions (N x R),
  optimal, theta_hat (R x S), theta_error (||Theta_hat - Theta||), policy_risk (the learnt policy's
  RMS distance from the target's actions over the skill's evaluation states,
  ``mt_widgets.core.learner_teaching``), rho1, rho2, bound, residual, contributions (N,), exact,
  reproduction {diverged, diverged_at, final_position, duration_s}, started_at, duration_s (wall
  clock from episode_started, interruptions included). For a learner without a Theta on the
  features: theta_hat, theta_error, bound and residual are null, and learner and learnt_actions
  (N x R, the fitted policy at the query states) are added (``mt_widgets.study.study_learners``).
  Logs written before theta_error and policy_risk had their own names hold one teaching_error
  instead (Theta's error with a theta_hat, else the policy risk); they still read
  (``mt_widgets.study.tidy.episode_errors``).
- ``session_finished``.
"""

from __future__ import annotations

from .jsonl import LogError

#: The schema version this code writes (see the module docstring).
LOG_FORMAT = 2
#: Versions this code reads (older ones through the migrations below).
READABLE_FORMATS = (1, 2)
#: What a format-1 log showed as guidance: arrows with words, the only modality before the
#: protocol could choose one.
FORMAT_1_GUIDANCE_MODALITY = "arrows+words"


def check_format(found, where: str) -> int:
    """The format of a file or record, checked: an int this code reads.

    Raises:
        LogError: a format newer than ``LOG_FORMAT`` (written by newer software) or not a known one.
    """
    if isinstance(found, bool) or not isinstance(found, int) or found not in READABLE_FORMATS:
        newer = isinstance(found, int) and not isinstance(found, bool) and found > LOG_FORMAT
        raise LogError(f"{where}: written with schema format {found!r}; this version of mt-widgets reads formats "
                       f"{list(READABLE_FORMATS)}" + ("; update mt-widgets to read it" if newer else ""))
    return found


def migrate_events(events: list[dict], first_session: str, where: str) -> list[dict]:
    """A participant log's events in the current format (see the module docstring).

    Args:
        events: as read from the file, in order.
        first_session: the id of the protocol's first session (what a format-1 log ran).
        where: the file, for messages.
    """
    if not events:
        return events
    current = check_format(events[0].get("format", 1), f"{where}, seq 0") if events[0]["type"] == \
        "session_started" else 1
    out = []
    for event in events:
        if event["type"] in ("session_started", "session_resumed") and "format" in event:
            current = check_format(event["format"], f"{where}, seq {event['seq']}")
        if current == 1:
            event = _event_1_to_2(event, first_session)
        out.append(event)
    return out


def _event_1_to_2(event: dict, first_session: str) -> dict:
    event = dict(event)
    if event["type"] == "session_started":
        event["session"] = first_session
        event["format"] = 2
        event["migrated_from"] = 1
    elif event["type"] == "episode_started" and "guidance_modality" not in event:
        event["guidance_modality"] = FORMAT_1_GUIDANCE_MODALITY
    return event


def migrate_record(record: dict, where: str) -> dict:
    """An enrolment or outcome record in the current format (format 1 records had no version)."""
    found = check_format(record.get("format", 1), where)
    if found == 1:
        record = {**record, "format": 2, "migrated_from": 1}
    return record


def migrate_study_meta(meta: dict, where: str) -> dict:
    """``study.json`` in the current format (format 1 differs only in its number)."""
    if "format" not in meta:
        raise LogError(f"{where}: no schema format; this is not a study file mt-widgets wrote")
    found = check_format(meta["format"], where)
    if found == 1:
        meta = {**meta, "format": 2, "migrated_from": 1}
    return meta
