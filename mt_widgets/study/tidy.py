"""Tidy export of a study folder: one row per episode, one row per demonstration.

Rows are rebuilt from the logs alone (``study.json`` and each ``<participant>.jsonl``), with
the standard library: analysis code may load the CSVs with pandas, the runner never needs it.

episodes.csv columns (``EPISODE_COLUMNS``): study, participant, group, session (the protocol
session's id, "main" for a one-session protocol), phase, phase_index
(0-based), episode (1-based within the phase), skill, guidance (0/1), n_demonstrations,
theta_error (||Theta_hat - Theta||; empty for a learner without a Theta), policy_risk (the learnt
policy's RMS distance from the target's actions over the skill's evaluation states; every learner;
empty for a log written before it was logged), rho1, rho2, theta_hat (JSON list of rows; empty for
a learner without a Theta), reproduction_diverged (0/1), started_at (ISO 8601 UTC), duration_s.
A log written when the two errors were one field, ``teaching_error``, still reads: it is the
theta_error where the episode has a theta_hat, else the policy_risk (``episode_errors``).

demonstrations.csv columns (``DEMONSTRATION_COLUMNS``): study, participant, group, session, phase,
phase_index, episode, index (0-based), skill, state (JSON list), action_1, action_2,
optimal_1, optimal_2, guidance_shown (0/1), time_to_first_input_s, drawing_duration_s
(empty when unknown), action_3, optimal_3 (a plant's third action component, the UR5's
tool velocity along z; empty for a planar plant's two components).

Only completed episodes are exported; demonstrations of an episode still in progress are
exported (they are data), marked by the absence of their episode's row. A participant who
withdrew is left out (their withdrawal is in the study folder's ``_outcomes.jsonl``, and in
their log when the protocol keeps it); so are those who declined consent or were screened out,
who have no task data.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

from .log import read_log
from .schema import migrate_study_meta
from .study_folder import OUTCOME_FILE, STUDY_FILE

EPISODE_COLUMNS = ("study", "participant", "group", "session", "phase", "phase_index", "episode", "skill", "guidance",
                   "n_demonstrations", "theta_error", "policy_risk", "rho1", "rho2", "theta_hat",
                   "reproduction_diverged", "started_at", "duration_s")
DEMONSTRATION_COLUMNS = ("study", "participant", "group", "session", "phase", "phase_index", "episode", "index",
                         "skill", "state", "action_1", "action_2", "optimal_1", "optimal_2", "guidance_shown",
                         "time_to_first_input_s", "drawing_duration_s", "action_3", "optimal_3")


def episode_errors(event: dict) -> tuple[float | None, float | None]:
    """(theta_error, policy_risk) of an ``episode_finished`` event. A log written when they were
    one field, ``teaching_error``, holds Theta's error where the event has a theta_hat (the paper's
    ridge) and the policy risk otherwise; its other error was not logged (None)."""
    if "policy_risk" in event:
        return event.get("theta_error"), event["policy_risk"]
    error = event["teaching_error"]
    return (error, None) if event.get("theta_hat") is not None else (None, error)


def participant_logs(study_folder) -> list[Path]:
    """The participant log files of a study folder, sorted by name."""
    folder = Path(study_folder)
    return sorted(p for p in folder.glob("*.jsonl") if not p.name.startswith("_"))


def excluded_participants(study_folder) -> set[str]:
    """Participants the analysis leaves out: those who withdrew, declined consent or were screened
    out (read from ``_outcomes.jsonl``; those who dropped out keep the data they gave)."""
    path = Path(study_folder) / OUTCOME_FILE
    if not path.exists():
        return set()
    records = [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]
    return {r["participant"] for r in records if r["outcome"] in ("withdrawn", "declined", "ineligible")}


def read_study(study_folder) -> tuple[list[dict], list[dict]]:
    """Reads every participant log of a study folder into plain rows.

    Args:
        study_folder: a folder with ``study.json`` and ``<participant>.jsonl`` files.

    Returns:
        (episodes, demonstrations): lists of dicts keyed by ``EPISODE_COLUMNS`` and
        ``DEMONSTRATION_COLUMNS``; numbers as Python numbers, JSON columns as JSON text,
        unknown timings as None. Sorted by participant, then by order in the protocol
        (sessions, then each session's order).

    Raises:
        FileNotFoundError: the folder has no ``study.json``.
    """
    folder = Path(study_folder)
    if not (folder / STUDY_FILE).is_file():
        raise FileNotFoundError(f"study_folder: expected a study folder with {STUDY_FILE}, got {folder}")
    meta = migrate_study_meta(json.loads((folder / STUDY_FILE).read_text(encoding="utf-8")), str(folder / STUDY_FILE))
    study = meta["study"]
    sessions = [entry["id"] for entry in meta["protocol"].get("sessions", [])]
    first_session = meta["protocol"].get("session", "main")  # the protocol's own default (protocol.py)
    order = {name: i for i, name in enumerate([first_session, *sessions])}
    episodes: list[dict] = []
    demonstrations: list[dict] = []
    excluded = excluded_participants(folder)
    for path in participant_logs(folder):
        events = read_log(path, first_session)
        if not events or events[0]["type"] != "session_started" or events[0]["participant"] in excluded:
            continue
        if any(event["type"] in ("withdrawn", "consent_declined", "screened_out") for event in events):
            continue
        participant, group, session = events[0]["participant"], events[0]["group"], events[0]["session"]
        started = {}
        for event in events:
            kind = event["type"]
            if kind == "episode_started":
                started[(event["phase_index"], event["episode"])] = event
            elif kind == "demonstration":
                episode = started[(event["phase_index"], event["episode"])]
                demonstrations.append({
                    "study": study, "participant": participant, "group": group, "session": session,
                    "phase": event["phase"], "phase_index": event["phase_index"], "episode": event["episode"],
                    "index": event["index"],
                    "skill": episode["skill"], "state": json.dumps(event["state"]),
                    "action_1": event["action"][0], "action_2": event["action"][1],
                    "optimal_1": event["optimal"][0], "optimal_2": event["optimal"][1],
                    "guidance_shown": int(bool(event["guidance_shown"])),
                    "time_to_first_input_s": event["time_to_first_input_s"],
                    "drawing_duration_s": event["drawing_duration_s"],
                    **_third_component(event)})
            elif kind == "episode_finished":
                episodes.append({
                    "study": study, "participant": participant, "group": group, "session": session,
                    "phase": event["phase"], "phase_index": event["phase_index"], "episode": event["episode"],
                    "skill": event["skill"],
                    "guidance": int(bool(event["guidance"])), "n_demonstrations": len(event["actions"]),
                    **dict(zip(("theta_error", "policy_risk"), episode_errors(event))),
                    "rho1": event["rho1"], "rho2": event["rho2"],
                    # Only a learner with a Theta logs Theta_hat (another's is null: study_learners).
                    "theta_hat": None if event["theta_hat"] is None else json.dumps(event["theta_hat"]),
                    "reproduction_diverged": int(bool(event["reproduction"]["diverged"])),
                    "started_at": event["started_at"], "duration_s": event["duration_s"]})
    # Files sort by name; sessions go in the protocol's order (a stable sort keeps each log's).
    def key(row):
        return row["participant"], order.get(row["session"], len(order))
    return sorted(episodes, key=key), sorted(demonstrations, key=key)


def _third_component(event: dict) -> dict:
    """action_3 and optimal_3 of a demonstration event: its third components, None for two."""
    return {f"{name}_3": event[name][2] if len(event[name]) > 2 else None for name in ("action", "optimal")}


def _write_csv(path: Path, columns, rows) -> None:
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(columns), lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({key: "" if row[key] is None else row[key] for key in columns})


def export_study(study_folder, out_folder=None) -> tuple[Path, Path]:
    """Writes ``episodes.csv`` and ``demonstrations.csv`` for a study folder.

    Args:
        study_folder: the study folder.
        out_folder: where to write (default: the study folder itself).

    Returns:
        (episodes_csv_path, demonstrations_csv_path).
    """
    episodes, demonstrations = read_study(study_folder)
    out = Path(study_folder if out_folder is None else out_folder)
    out.mkdir(parents=True, exist_ok=True)
    episodes_path, demonstrations_path = out / "episodes.csv", out / "demonstrations.csv"
    _write_csv(episodes_path, EPISODE_COLUMNS, episodes)
    _write_csv(demonstrations_path, DEMONSTRATION_COLUMNS, demonstrations)
    return episodes_path, demonstrations_path
