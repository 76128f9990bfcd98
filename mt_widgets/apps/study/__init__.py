"""The study's pages: the lab's experimenter page and participant page, and the online participant page.

One concern per module:

- ``participant``: ``ParticipantView``, the participant's page for one session: a thin
  dispatcher from the session's current step to the step views below. It holds nothing of the
  experimenter's and nothing about other participants.
- step views: ``forms`` (questions, problems in plain words), ``video`` (watched to the end,
  really), ``practice`` (its clock survives a reload), ``episode_step`` (an episode, its
  guidance arrow named, the reproduction); ``controls`` (buttons that act once) and ``texts``.
- ``panel``: ``ExperimenterPanel``; ``app``: ``StudyApp``, the panel then the participant view.
- ``lab_page``: ``LabStudyPage``, the lab's page: the panel only after the experimenter's code,
  and a participant's reload resumes them (never the panel).
- ``online``: ``OnlineStudyPage``, the page for online participants: enrolled from the URL,
  resumed on a reload or a return, sent on to the protocol's completion URL.
"""

from .app import LOG_FOLDER_VARIABLE, StudyApp, default_log_folder
from .forms import QuestionForm
from .lab_page import EXPERIMENTER_CODE_VARIABLE, LabStudyPage
from .online import OnlineStudyPage
from .panel import ExperimenterPanel
from .participant import ParticipantView
from .video import VideoStep

__all__ = ["EXPERIMENTER_CODE_VARIABLE", "ExperimenterPanel", "LOG_FOLDER_VARIABLE", "LabStudyPage", "OnlineStudyPage",
           "ParticipantView", "QuestionForm", "StudyApp", "VideoStep", "default_log_folder"]
