"""The study runner: protocols as data, participants, the session engine, the crash-safe log
and the tidy export. No widgets here (``mt_widgets.apps`` composes them with this package).

Depends on ``mt_widgets.core`` only. The simulation of teachers (``mt_widgets.in_silico``) and the
analysis (``mt_widgets.analysis``) are packages of their own above this one.

One concern per module::

    protocol.py        the file format; load_protocol, parse_protocol, the shipped protocols
    protocol_model.py  Protocol, Phase, Practice: the validated, frozen model
    protocol_schema.py validation of TOML/JSON into the model (ProtocolError with line and field)
    protocol_source.py line numbers of fields in the source text
    skill_modules.py   the skills a protocol names (a user's Python file, "module:name")
    session_plan.py    sessions and their windows ([[sessions]])
    online.py          online participants: URL parameters, completion URLs and codes ([online])
    steps.py           steps around the task ([[before]] / [[after]]): video, forms, questionnaires
    analysis_plan.py   the pre-registered analysis plan ([analysis])
    practice.py        the neutral practice skills
    participants.py    IDs (typed and from a URL), re-entry codes, block randomisation
    timeline.py        a session unrolled into steps (StepKind), each episode's query states
    replay.py          a log replayed against the timeline
    session.py         the engine: Session, where it stands (current_step) and the steps' driver calls
    session_arrival.py which log a Session runs: start, resume, arrive (windows), lesson
    session_episodes.py the episode steps: one TeachingEpisode per episode (the one store of its
                       demonstrations), submit_demonstration, finish_episode, the EpisodeResult
    study_learners.py  the robot learner a protocol names, and what the log records of it
    session_types.py   what the engine hands a view: Step, Feedback, EpisodeResult (core's),
                       SessionStateError
    schema.py          the files' schema version, the event types, migrations of older logs
    log.py             the append-only participant log (ParticipantLog, read_events, read_log)
    study_folder.py    the study folder: study.json, enrolments, outcomes, status
    jsonl.py           JSON lines, locks and fsync: the crash-safe primitives
    tidy.py, bids.py   exports: episodes/demonstrations CSVs, a BIDS dataset
    pseudonyms.py      the key from participant ID to the random code an export uses (0600)
    erasure.py         a participant's erasure request: removed everywhere, what is kept said
    __main__.py        python -m mt_widgets.study erase | export-bids | status
"""

from .analysis_plan import PAPER_CHANGES, AnalysisPlan, Change
from .bids import export_bids
from .erasure import ErasureReport, UnknownParticipantError, erase_participant
from .jsonl import NotSavedError
from .log import LogError, LogFolderError, MemoryLog, ParticipantLog, check_folder_writable, read_events, read_log
from .online import OnlineSettings, outcome_of
from .participants import ParticipantIdError, block_assignment, validate_participant_id, validate_url_participant_id
from .protocol import BUILTIN_PROTOCOLS, Phase, Practice, Protocol, ProtocolError, load_protocol, parse_protocol
from .session import EpisodeResult, Feedback, Session, SessionStateError, Step, WindowError, timeline
from .session_plan import ProtocolSession, Window
from .study_folder import StudyFolder
from .tidy import DEMONSTRATION_COLUMNS, EPISODE_COLUMNS, export_study, read_study

__all__ = [
    "AnalysisPlan", "BUILTIN_PROTOCOLS", "Change", "DEMONSTRATION_COLUMNS", "EPISODE_COLUMNS", "EpisodeResult",
    "Feedback", "LogError", "LogFolderError", "MemoryLog", "PAPER_CHANGES", "ParticipantIdError", "ParticipantLog",
    "Phase", "Practice", "Protocol", "ProtocolError", "Session", "SessionStateError", "Step", "StudyFolder",
    "block_assignment", "check_folder_writable", "export_bids", "export_study", "load_protocol", "parse_protocol",
    "read_events", "read_study", "timeline", "validate_participant_id",
    "OnlineSettings", "read_log", "ProtocolSession", "Window", "WindowError", "outcome_of",
    "validate_url_participant_id",
    "ErasureReport", "UnknownParticipantError", "erase_participant",
    "NotSavedError",
]
