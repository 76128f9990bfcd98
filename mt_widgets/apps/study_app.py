"""The study app's former home, kept so ``from mt_widgets.apps.study_app import StudyApp`` still
works (tutorial 10, the uArm app). The code lives in ``mt_widgets.apps.study``, one concern per module."""

from .study import LOG_FOLDER_VARIABLE, ExperimenterPanel, QuestionForm, StudyApp, VideoStep, default_log_folder

__all__ = ["ExperimenterPanel", "LOG_FOLDER_VARIABLE", "QuestionForm", "StudyApp", "VideoStep", "default_log_folder"]
