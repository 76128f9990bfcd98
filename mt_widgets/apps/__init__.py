"""Ready-made compositions of the study runner, the widgets and the hardware.

Nothing in the package imports ``mt_widgets.apps``; notebooks do:

- ``StudyApp``: the lab's study app (experimenter panel, then the participant view); the
  pages in ``mt_widgets.apps.study`` (``LabStudyPage``, ``OnlineStudyPage``).
- ``UArmStudyApp``: the same on a uArm Swift Pro (or its simulated arm), with the paper's
  screen under the arm (``ScreenGeometry``), the arm bridge (``UArmBridge``, re-exported from
  ``mt_widgets.hardware.bridge``) and audio cues.
"""

from mt_widgets.hardware.bridge import UArmBridge, connect_arm

from .study import ExperimenterPanel, StudyApp, default_log_folder
from .uarm_screen import ScreenGeometry
from .uarm_study import UArmEpisodePage, UArmStudyApp, UArmTeaching

__all__ = ["ExperimenterPanel", "ScreenGeometry", "StudyApp", "UArmBridge", "UArmEpisodePage", "UArmStudyApp",
           "UArmTeaching", "connect_arm", "default_log_folder"]
