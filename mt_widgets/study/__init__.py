"""The study runner: protocols as data, participants, the session engine, the crash-safe log
and the tidy export. No widgets here (``mt_widgets.apps`` composes them with this package).

Depends on ``mt_widgets.core`` only. The simulation of teachers (``mt_widgets.in_silico``) and the
analysis (``mt_widgets.analysis``) are packages of their own above this one.
"""

from .analysis_plan import PAPER_CHANGES, AnalysisPlan, Change
from .bids import export_bids
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
]
