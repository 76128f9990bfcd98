"""Teaching widgets (ipycanvas + ipywidgets): draw demonstrations, see guidance, watch the robot.

- ``EpisodeWidget``: a whole episode (the three-line entry point), for every arm: planar or in
  space (the UR5), as the plant's drawing says; its state machine is one ``EpisodeController``
  (``mt_widgets.widgets.episode_controller``: no widget library, tested without a kernel).
- ``TeachingCanvas``: query states one after another, an arrow drawn at each (the planar view);
  ``SpaceTeachingCanvas`` the same in three linked views of a plant drawn in space.
- ``ArmView``: the workspace, target and robot on layered canvases.
- ``ReproductionPlayer``: the learnt skill's rollout as an animation.
- ``DemoPage``: the visitors' one-click page (skill chooser, guidance switch, try again).
- ``EffortProgress``, ``GuidancePanel``: the progress bars and the guidance in words.
- ``ViewTransform``: world <-> pixel mapping; ``draw_arrow``: arrow rendering;
  ``play_frames``: animation (``stop_animations`` / ``retire`` when a view is replaced);
  ``THEMES``: colour-blind-safe default and the paper's look.

Widgets hold no science: they call ``mt_widgets.core`` and draw the result.
"""

from .animation import play_frames, retire, stop_animations
from .arm_view import ArmView
from .arrows import draw_arrow
from .coords import ViewTransform
from .demo import DemoPage
from .episode import DemonstrationRecord, EpisodeResult, EpisodeWidget
from .episode_controller import EpisodeController
from .guidance import GuidancePanel
from .progress import EffortProgress
from .reproduction import ReproductionPlayer
from .robots import RobotPainter, painter_for
from .space_teaching import SpaceTeachingCanvas
from .teaching import TeachingCanvas
from .theme import DEFAULT_THEME, PAPER_THEME, PAPER_UARM_THEME, THEMES, Theme, get_theme

# What a user builds a lesson or a page from. The helpers the views share (legend entries, arrow
# styles, colour names, drawing batches, frame times, ...) stay in their modules
# (``mt_widgets.widgets.theme``, ``.legend``, ``.redraw``, ``.animation``, ...), imported from there.
__all__ = [
    "DEFAULT_THEME", "PAPER_THEME", "PAPER_UARM_THEME", "THEMES", "ArmView", "DemoPage",
    "DemonstrationRecord", "EffortProgress", "EpisodeController", "EpisodeResult", "EpisodeWidget", "GuidancePanel",
    "ReproductionPlayer",
    "RobotPainter", "TeachingCanvas", "Theme", "ViewTransform", "draw_arrow", "get_theme", "painter_for",
    "play_frames", "retire", "stop_animations", "SpaceTeachingCanvas",
]
