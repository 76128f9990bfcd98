"""Ready-made compositions of the study runner, the widgets and the hardware.

Nothing in the package imports ``mt_widgets.apps``; notebooks do:

- ``StudyApp``: the participant app (experimenter panel, then the participant view).
"""

from .study_app import ExperimenterPanel, StudyApp, default_log_folder, participant_texts

__all__ = ["ExperimenterPanel", "StudyApp", "default_log_folder", "participant_texts"]
