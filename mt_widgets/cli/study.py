"""A study folder from the command line: its status, its BIDS export, a participant's withdrawal."""

from __future__ import annotations

from pathlib import Path

from mt_widgets.study.bids import export_bids
from mt_widgets.study.study_folder import StudyFolder


def status_text(folder) -> str:
    """The experimenter's view: per group counts, then one line per participant (with groups)."""
    study = StudyFolder(folder)
    lines = [f"{study.folder}: protocol {study.protocol.name!r}, {len(study.enrolments())} enrolled",
             study.status_report(), ""]
    for row in study.status():
        events = "damaged log" if row["events"] < 0 else f"{row['events']} events"
        lines.append(f"{row['participant']:<12} {row['group']:<9} {row['state']:<12} {events}")
    return "\n".join(lines)


def export(folder, out) -> Path:
    """The study's BIDS-style behavioural dataset, written to ``out`` (``mt_widgets.study.bids``)."""
    return export_bids(StudyFolder(folder).folder, Path(out).expanduser())


def withdraw(folder, participant: str, reason: str = "") -> dict:
    """Records that ``participant`` withdrew (told the experimenter rather than the page), with the
    protocol's data policy: "exclude" keeps the log out of the analysis and the export, "delete"
    deletes the participant's logs, as the page's own withdrawal does (``Session.withdraw``)."""
    study = StudyFolder(folder)
    policy = study.protocol.withdrawal
    record = study.record_outcome(participant, "withdrawn", reason=reason, data=policy, at="experimenter")
    if policy == "delete":
        for plan in study.protocol.sessions:
            study.log_path(participant, plan.id).unlink(missing_ok=True)
    return record
